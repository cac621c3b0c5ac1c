// vis_cube.glsl - point-light shadows from a depth cube map (six 90-degree
// perspective faces). The reference depth is the face's perspective depth of
// the point's major-axis distance; bias and normal offset scale with the
// texel size at that distance. SB_FILTER: 0 none, 1 hw (bilinear compare), 2 pcf (8 taps).
// One lamp's cube (sb_visibility), or with SB_LIGHT_LOOP every lamp's, cube i of a cube-map array
// (sb_visibility_at, the records of vis_lamps.glsl).
uniform float u_bias, u_normal;
#ifdef SB_LIGHT_LOOP
uniform samplerCubeArrayShadow u_map;
#define SB_CUBE_LOOKUP(dq, z, i) texture(u_map, vec4(dq, float(i)), z)
#else
uniform samplerCubeShadow u_map;
uniform vec3 u_lamp;
uniform float u_near, u_far, u_res;
#define SB_CUBE_LOOKUP(dq, z, i) texture(u_map, vec4(dq, z))
#endif

// a: the map's near, far and texels across a face
float sb_cube_tap(vec3 dq, vec3 a, int i) {
    float axis = max(abs(dq.x), max(abs(dq.y), abs(dq.z)));
    float texel = 2.0 * axis / a.z;
    axis -= u_bias * texel;
    if (axis >= a.y) return 1.0;
    float z = (a.y + a.x) / (a.y - a.x) - 2.0 * a.y * a.x / ((a.y - a.x) * max(axis, a.x));
    return SB_CUBE_LOOKUP(dq, 0.5 * z + 0.5, i);
}

float sb_cube_visibility(vec3 p, vec3 n, vec3 lamp, vec3 a, int i) {
    vec3 d = p - lamp;
    float dist = length(d);
    float texel = 2.0 * max(abs(d.x), max(abs(d.y), abs(d.z))) / a.z;
    vec3 L = -d / max(dist, 1e-20);
    float cosl = clamp(dot(n, L), -1.0, 1.0);
    vec3 dq = p + n * (u_normal * texel * sqrt(1.0 - cosl * cosl)) - lamp;
#if SB_FILTER == 2
    vec3 t1 = normalize(cross(dq, abs(dq.y) < 0.9 * length(dq) ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    vec3 t2 = normalize(cross(dq, t1));
    float sum = 0.0;
    for (int k = 0; k < 8; k++) {
        float ang = float(k) * 0.785398;
        sum += sb_cube_tap(dq + (t1 * cos(ang) + t2 * sin(ang)) * texel * 1.5, a, i);
    }
    return sum / 8.0;
#else
    return sb_cube_tap(dq, a, i);
#endif
}

#ifdef SB_LIGHT_LOOP
float sb_visibility_at(int i, vec3 p, vec3 n) { return sb_cube_visibility(p, n, sb_light_at(i).xyz, sb_lamp_clip(i), i); }
#else
float sb_visibility(vec3 p, vec3 n, float view_z) { return sb_cube_visibility(p, n, u_lamp, vec3(u_near, u_far, u_res), 0); }
#endif
