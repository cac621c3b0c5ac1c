// vis_virtual.glsl - the virtual shadow map's lookup (after virtual_common.glsl): the pixel's level, its page
// through the page table, the page's slot in the atlas (a slot is the page with a border of SB_BORDER texels on
// every side, so filter taps stay in it). A page the pool could not hold is looked up one level finer, then
// coarser, level by level; none at all: lit. Never another page's texels.
// level, row, column: slot + 1 (0: none), 16 bits each, two to a uint (the lower half first)
layout(std430, binding = 3) readonly buffer SbPageTable { uint sb_table[]; };
uniform sampler2DShadow u_atlas;
uniform vec2 u_atlas_texel;     // 1 / the atlas's size
uniform vec2 u_vdepth;          // light-view z -> map depth: z * x + y
uniform float u_vrange;         // the depth range, world units
uniform float u_bias;           // constant bias, in texels of the level
uniform float u_normal;         // normal offset, in texels of the level
uniform vec3 u_light;           // toward the light

float sb_vtap(vec2 uv, float z, vec2 off) { return texture(u_atlas, vec3(uv + off * u_atlas_texel, z)); }

// visibility at level l, or -1 where the level holds no page for p
float sb_vlookup(int l, vec3 p, vec3 n) {
    float t = sb_vtexel(l);
    float cosl = clamp(dot(n, u_light), -1.0, 1.0);
    vec3 lp = (u_vlight * vec4(p + n * (u_normal * t * sqrt(1.0 - cosl * cosl)), 1.0)).xyz;
    vec2 c = sb_vtexcoord(l, lp.xy);
    ivec2 pg = ivec2(floor(c / float(SB_PAGE)));
    if (pg.x < 0 || pg.y < 0 || pg.x >= SB_PAGES || pg.y >= SB_PAGES) return -1.0;
    uint i = uint((l * SB_PAGES + pg.y) * SB_PAGES + pg.x);
    uint e = (sb_table[i >> 1] >> ((i & 1u) * 16u)) & 0xffffu;
    if (e == 0u) return -1.0;
    int slot = int(e) - 1;
    vec2 corner = vec2(float(slot % SB_SLOTS_X), float(slot / SB_SLOTS_X)) * float(SB_SLOT) + float(SB_BORDER);
    vec2 uv = (corner + c - vec2(pg) * float(SB_PAGE)) * u_atlas_texel;
    float z = lp.z * u_vdepth.x + u_vdepth.y - u_bias * t / u_vrange;
#if SB_FILTER == 2
    float sum = 0.0;
    for (int y = -1; y <= 1; y++)
        for (int x = -1; x <= 1; x++) sum += sb_vtap(uv, z, vec2(x, y));
    return sum / 9.0;
#else
    return sb_vtap(uv, z, vec2(0.0));
#endif
}

float sb_visibility(vec3 p, vec3 n, float view_z) {
    int l = sb_vlevel(p);
#ifdef SB_EVAL
    // resolution: texels of the pixel's level per screen pixel (in uniform control flow, for the derivatives)
    vec2 c0 = sb_vtexcoord(l, (u_vlight * vec4(p, 1.0)).xy);
    SB_EVAL_OUT(max(length(dFdx(c0)), length(dFdy(c0))), float(l));
#endif
    float v = sb_vlookup(l, p, n);
    if (v >= 0.0) return v;
    if (l > 0) {
        v = sb_vlookup(l - 1, p, n);
        if (v >= 0.0) return v;
    }
    for (int k = l + 1; k < SB_LEVELS; k++) {
        v = sb_vlookup(k, p, n);
        if (v >= 0.0) return v;
    }
    return 1.0;
}
