// csm_block.glsl - the cascade block, filled by the CPU (glBufferSubData) or by
// SDSM's split compute shader: every cascade pass and the final lookup read it.
// Readers see it as a uniform block: a storage block's loads are bounds-checked
// gathers on some implementations (llvmpipe: a mat4 from one cost a 1280x720
// camera pass 80 ms), a uniform block's are constant-cache reads. The writers
// (SDSM's compute shaders, SB_CASCADE_STORAGE) bind the same buffer as storage:
// std140 and std430 place these members (vec4 and mat4 arrays) alike.
#ifdef SB_CASCADE_STORAGE
#ifndef SB_CASCADE_ACCESS
#define SB_CASCADE_ACCESS readonly
#endif
layout(std430, binding = 0) SB_CASCADE_ACCESS buffer SbCascades {
#else
layout(std140, binding = 0) uniform SbCascades {
#endif
    mat4 sb_light_vp[8];    // origin-relative world -> light clip space
    mat4 sb_shadow_mat[8];  // origin-relative world -> [0,1]^3 shadow coordinates
    vec4 sb_cascade[8];     // x: near split, y: far split (view depth), z: texel world size, w: depth range
    vec4 sb_flags[8];       // x: 1 rendered, 0 skipped (no receivers); y: 1 warped (LiSPSM)
    vec4 sb_info;           // x: cascade count
};
