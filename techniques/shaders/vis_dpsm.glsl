// vis_dpsm.glsl - dual-paraboloid lookup: the hemisphere of the point picks
// the map; the reference is the point's distance to the lamp. One lamp's two
// maps (sb_visibility), or with SB_LIGHT_LOOP every lamp's, layers 2i and 2i + 1
// (sb_visibility_at, the records of vis_lamps.glsl).
uniform sampler2DArrayShadow u_map;
uniform mat3 u_frame;
uniform float u_bias, u_normal;
#ifndef SB_LIGHT_LOOP
uniform vec3 u_lamp;
uniform float u_near, u_far, u_res;
#endif

// a: the maps' near, far and texels across; first: the lamp's first layer
float sb_dpsm_visibility(vec3 p, vec3 n, vec3 lamp, vec3 a, float first) {
    vec3 dw = p - lamp;
    float dist = length(dw);
    // a paraboloid texel spans about 2 * dist / res at the rim, dist / res at the centre
    float texel = 2.0 * dist / a.z;
    vec3 L = -dw / max(dist, 1e-20);
    float cosl = clamp(dot(n, L), -1.0, 1.0);
    vec3 q = p + n * (u_normal * texel * sqrt(1.0 - cosl * cosl));
    vec3 v = u_frame * (q - lamp);
    float layer = v.z >= 0.0 ? 0.0 : 1.0;
    v.z = abs(v.z);
    float len = length(v);
    vec3 d = v / max(len, 1e-20);
    vec2 uv = d.xy / (1.0 + d.z) * 0.5 + 0.5;
    float ref = (len - u_bias * texel - a.x) / (a.y - a.x);
    if (ref >= 1.0) return 1.0;
    return texture(u_map, vec4(uv, first + layer, ref));
}

#ifdef SB_LIGHT_LOOP
float sb_visibility_at(int i, vec3 p, vec3 n) {
    return sb_dpsm_visibility(p, n, sb_light_at(i).xyz, sb_lamp_clip(i), 2.0 * float(i));
}
#else
float sb_visibility(vec3 p, vec3 n, float view_z) { return sb_dpsm_visibility(p, n, u_lamp, vec3(u_near, u_far, u_res), 0.0); }
#endif
