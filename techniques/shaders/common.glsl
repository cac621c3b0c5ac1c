// common.glsl - prepended to every shadowbench shader after #version and defines.
#define SB_PI 3.14159265358979
// A camera-pass program is linked twice (render.c): the timed variant, which
// writes colour only, and the evaluation variant (SB_EVAL), which also writes
// the visibility, position and normal targets the error metrics read. A
// technique's sb_visibility() reports, through SB_EVAL_OUT, the shadow texels
// per screen pixel of the map it used and that map's cascade (-1: none); the
// macro and what computes its arguments exist only in the evaluation variant
// (#ifdef SB_EVAL), so timed frames never pay for them.
#ifdef SB_EVAL
float sb_out_texel_px = -1.0;
float sb_out_cascade = -1.0;
#define SB_EVAL_OUT(texel_px, cascade) sb_out_texel_px = (texel_px); sb_out_cascade = (cascade)
#else
#define SB_EVAL_OUT(texel_px, cascade)
#endif
#if defined(SB_VERTEX) && defined(SB_SHARED)
// A draw's instance transform (render.c): a draw that repeats another's triangles is drawn from that draw's
// vertices through it (three rows of a 3x4 matrix, per draw at its baseInstance); identity for every other
// draw, where sb_world(p) is p exactly. Every vertex shader that reads the scene's vertices places them so.
// Compiled in only for a scene with shared geometry (SB_SHARED): elsewhere both are the identity.
layout(location = 6) in vec4 sb_a_x0;
layout(location = 7) in vec4 sb_a_x1;
layout(location = 8) in vec4 sb_a_x2;
vec3 sb_world(vec3 p) {
    return vec3(dot(sb_a_x0.xyz, p) + sb_a_x0.w, dot(sb_a_x1.xyz, p) + sb_a_x1.w, dot(sb_a_x2.xyz, p) + sb_a_x2.w);
}
vec3 sb_world_dir(vec3 n) { return vec3(dot(sb_a_x0.xyz, n), dot(sb_a_x1.xyz, n), dot(sb_a_x2.xyz, n)); }
#elif defined(SB_VERTEX)
vec3 sb_world(vec3 p) { return p; }
vec3 sb_world_dir(vec3 n) { return n; }
#endif
