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
