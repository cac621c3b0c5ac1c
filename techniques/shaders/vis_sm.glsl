// vis_sm.glsl - one shadow map (also the per-cascade lookup of cascaded techniques).
// SB_FILTER: 0 none (1 nearest tap), 1 hw (bilinear 2x2 compare), 2 pcf3, 3 pcf5, 4 poisson16
uniform sampler2DShadow u_shadow;
uniform mat4 u_shadow_mat;      // origin-relative world -> [0,1]^3
uniform float u_bias;           // constant depth bias, in [0,1] depth units
uniform float u_normal_offset;  // world units, scaled by the sine of the light angle
uniform vec3 u_light;           // toward the light
uniform vec2 u_texel;           // 1 / shadow map size

float sb_tap(vec3 c, vec2 off) { return texture(u_shadow, vec3(c.xy + off * u_texel, c.z)); }

float sb_visibility(vec3 p, vec3 n, float view_z) {
    float cosl = clamp(dot(n, u_light), -1.0, 1.0);
    vec3 q = p + n * u_normal_offset * sqrt(1.0 - cosl * cosl);
    vec4 s = u_shadow_mat * vec4(q, 1.0);
    vec3 c = s.xyz / s.w;
    if (c.x < 0.0 || c.x > 1.0 || c.y < 0.0 || c.y > 1.0 || c.z > 1.0) return 1.0;
    c.z -= u_bias;
#if SB_FILTER == 0 || SB_FILTER == 1
    return sb_tap(c, vec2(0.0));
#elif SB_FILTER == 2 || SB_FILTER == 3
    const int r = SB_FILTER == 2 ? 1 : 2;
    float sum = 0.0;
    for (int y = -r; y <= r; y++)
        for (int x = -r; x <= r; x++) sum += sb_tap(c, vec2(x, y));
    return sum / float((2 * r + 1) * (2 * r + 1));
#else
    const vec2 disk[16] = vec2[](
        vec2(-0.942, -0.399), vec2(0.946, -0.769), vec2(-0.094, -0.929), vec2(0.345, 0.294),
        vec2(-0.916, 0.458), vec2(-0.815, -0.879), vec2(-0.383, 0.277), vec2(0.975, 0.756),
        vec2(0.443, -0.975), vec2(0.537, -0.474), vec2(-0.265, -0.419), vec2(0.792, 0.191),
        vec2(-0.242, 0.997), vec2(-0.814, 0.914), vec2(0.200, 0.786), vec2(0.144, -0.141));
    float sum = 0.0;
    for (int i = 0; i < 16; i++) sum += sb_tap(c, disk[i] * 1.5);
    return sum / 16.0;
#endif
}
