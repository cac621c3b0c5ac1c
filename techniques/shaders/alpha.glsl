// alpha.glsl - the alpha test of glTF MASK materials (and BLEND ones under
// --blend-casters mask), in every pass that rasterizes the scene: prepended
// after common.glsl when the scene has alpha-tested draws (SB_ALPHA), with the
// stage's macro (SB_VERTEX, SB_GEOMETRY, SB_FRAGMENT; SB_TO_GS for a vertex
// shader that feeds a geometry shader). A vertex carries its material and
// texture coordinates; a fragment is kept when alpha * texel >= cutoff, with
// the nearest texel: the same arithmetic as sb_material_covers() in scene.c,
// which the reference's rays use. Shaders call SB_ALPHA_VS(), SB_ALPHA_GS(i)
// and SB_ALPHA_TEST(); without SB_ALPHA (or with SB_NO_ALPHA) they are empty.
#if defined(SB_ALPHA) && !defined(SB_NO_ALPHA)
#if defined(SB_VERTEX)
layout(location = 2) in vec2 sb_a_uv;
layout(location = 3) in uint sb_a_mat;
#ifdef SB_TO_GS
out vec2 sb_vs_uv;
flat out uint sb_vs_mat;
#define SB_ALPHA_VS() sb_vs_uv = sb_a_uv; sb_vs_mat = sb_a_mat
#else
out vec2 sb_uv;
flat out uint sb_mat;
#define SB_ALPHA_VS() sb_uv = sb_a_uv; sb_mat = sb_a_mat
#endif
#elif defined(SB_GEOMETRY)
in vec2 sb_vs_uv[];
flat in uint sb_vs_mat[];
out vec2 sb_uv;
flat out uint sb_mat;
#define SB_ALPHA_GS(i) sb_uv = sb_vs_uv[i]; sb_mat = sb_vs_mat[i]
#elif defined(SB_FRAGMENT)
in vec2 sb_uv;
flat in uint sb_mat;
// i: first texel, width, height, wrap_s | wrap_t << 16 (width 0: no texture);
// f0: cutoff, alpha, uv[0], uv[1]; f1: uv[2], uv[3], uv[4], uv[5]
struct SbMaterial { uvec4 i; vec4 f0; vec4 f1; };
layout(std430, binding = 7) readonly buffer SbMaterials { SbMaterial sb_materials[]; };
layout(binding = 15) uniform usamplerBuffer sb_texels;
float sb_wrap(float t, uint mode) {
    if (mode == 33071u) return t;                           // CLAMP_TO_EDGE: clamped on the index
    if (mode == 33648u) {                                   // MIRRORED_REPEAT
        float f = t - 2.0 * floor(t * 0.5);
        return f > 1.0 ? 2.0 - f : f;
    }
    return t - floor(t);                                    // REPEAT
}
uint sb_texel_index(float t, uint mode, uint n) {
    float x = floor(sb_wrap(t, mode) * float(n));
    return x <= 0.0 ? 0u : x >= float(n) - 1.0 ? n - 1u : uint(x);
}
bool sb_covered() {
    if (sb_mat == 0u) return true;
    SbMaterial m = sb_materials[sb_mat];
    float a = m.f0.y;
    if (m.i.y > 0u) {
        float tu = m.f0.z * sb_uv.x + m.f0.w * sb_uv.y + m.f1.x;
        float tv = m.f1.y * sb_uv.x + m.f1.z * sb_uv.y + m.f1.w;
        uint x = sb_texel_index(tu, m.i.w & 0xffffu, m.i.y), y = sb_texel_index(tv, m.i.w >> 16, m.i.z);
        a *= float(texelFetch(sb_texels, int(m.i.x + y * m.i.y + x)).r) / 255.0;
    }
    return a >= m.f0.x;
}
#define SB_ALPHA_TEST() if (!sb_covered()) discard
#endif
#endif
#ifndef SB_ALPHA_VS
#define SB_ALPHA_VS()
#endif
#ifndef SB_ALPHA_GS
#define SB_ALPHA_GS(i)
#endif
#ifndef SB_ALPHA_TEST
#define SB_ALPHA_TEST()
#endif
