// vis_dpsm.glsl - dual-paraboloid lookup: the hemisphere of the point picks
// the map; the reference is the point's distance to the lamp.
uniform sampler2DArrayShadow u_map;
uniform vec3 u_lamp;
uniform mat3 u_frame;
uniform float u_near, u_far, u_res, u_bias, u_normal;

float sb_visibility(vec3 p, vec3 n, float view_z) {
    vec3 dw = p - u_lamp;
    float dist = length(dw);
    // a paraboloid texel spans about 2 * dist / res at the rim, dist / res at the centre
    float texel = 2.0 * dist / u_res;
    vec3 L = -dw / max(dist, 1e-20);
    float cosl = clamp(dot(n, L), -1.0, 1.0);
    vec3 q = p + n * (u_normal * texel * sqrt(1.0 - cosl * cosl));
    vec3 v = u_frame * (q - u_lamp);
    float layer = v.z >= 0.0 ? 0.0 : 1.0;
    v.z = abs(v.z);
    float len = length(v);
    vec3 d = v / max(len, 1e-20);
    vec2 uv = d.xy / (1.0 + d.z) * 0.5 + 0.5;
    float ref = (len - u_bias * texel - u_near) / (u_far - u_near);
    if (ref >= 1.0) return 1.0;
    return texture(u_map, vec4(uv, layer, ref));
}
