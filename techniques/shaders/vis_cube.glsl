// vis_cube.glsl - point-light shadows from a depth cube map (six 90-degree
// perspective faces). The reference depth is the face's perspective depth of
// the point's major-axis distance; bias and normal offset scale with the
// texel size at that distance. SB_FILTER: 0 none, 1 hw (bilinear compare), 2 pcf (8 taps)
uniform samplerCubeShadow u_map;
uniform vec3 u_lamp;
uniform float u_near, u_far, u_res, u_bias, u_normal;

float sb_cube_tap(vec3 dq) {
    float axis = max(abs(dq.x), max(abs(dq.y), abs(dq.z)));
    float texel = 2.0 * axis / u_res;
    axis -= u_bias * texel;
    if (axis >= u_far) return 1.0;
    float z = (u_far + u_near) / (u_far - u_near) - 2.0 * u_far * u_near / ((u_far - u_near) * max(axis, u_near));
    return texture(u_map, vec4(dq, 0.5 * z + 0.5));
}

float sb_visibility(vec3 p, vec3 n, float view_z) {
    vec3 d = p - u_lamp;
    float dist = length(d);
    float texel = 2.0 * max(abs(d.x), max(abs(d.y), abs(d.z))) / u_res;
    vec3 L = -d / max(dist, 1e-20);
    float cosl = clamp(dot(n, L), -1.0, 1.0);
    vec3 dq = p + n * (u_normal * texel * sqrt(1.0 - cosl * cosl)) - u_lamp;
#if SB_FILTER == 2
    vec3 t1 = normalize(cross(dq, abs(dq.y) < 0.9 * length(dq) ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    vec3 t2 = normalize(cross(dq, t1));
    float sum = 0.0;
    for (int i = 0; i < 8; i++) {
        float a = float(i) * 0.785398;
        sum += sb_cube_tap(dq + (t1 * cos(a) + t2 * sin(a)) * texel * 1.5);
    }
    return sum / 8.0;
#else
    return sb_cube_tap(dq);
#endif
}
