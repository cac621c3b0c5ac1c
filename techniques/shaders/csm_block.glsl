// csm_block.glsl - the cascade block, filled by the CPU (glBufferSubData) or by
// SDSM's split compute shader: every cascade pass and the final lookup read it.
#ifndef SB_CASCADE_ACCESS
#define SB_CASCADE_ACCESS readonly
#endif
layout(std430, binding = 0) SB_CASCADE_ACCESS buffer SbCascades {
    mat4 sb_light_vp[8];    // origin-relative world -> light clip space
    mat4 sb_shadow_mat[8];  // origin-relative world -> [0,1]^3 shadow coordinates
    vec4 sb_cascade[8];     // x: near split, y: far split (view depth), z: texel world size, w: depth range
    vec4 sb_flags[8];       // x: 1 rendered, 0 skipped (no receivers); y: 1 warped (LiSPSM)
    vec4 sb_info;           // x: cascade count
};
