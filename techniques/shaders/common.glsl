// common.glsl - prepended to every shadowbench shader after #version and defines.
#define SB_PI 3.14159265358979
// Set by a technique's sb_visibility() for error evaluation: shadow texels per
// screen pixel of the map actually used, and that map's cascade (-1: none).
// Only worth computing in the (untimed) evaluation pass, when sb_eval is set:
// timed frames must not pay for it.
float sb_out_texel_px;
float sb_out_cascade;
uniform bool sb_eval;
