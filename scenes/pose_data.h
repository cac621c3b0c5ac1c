/* pose_data.h - what the GPU's posing pass reads of a moving scene: the rows motion.cc builds once
 * (sb_motion_gpu_data, motion.h) and techniques/pose.c sends. Its own header: motion.h and the motion module's
 * C++ data (motion_data.h) both hold it. */
#pragma once
#include <stdint.h>

/* What the GPU's posing pass (techniques/pose.c, shaders/pose.comp) reads: the std430 rows, built once a scene. */
typedef struct sb_pose_place {
    uint32_t first;          /* its first vertex in the scene (render.c writes the vertex buffer's number) */
    uint32_t count;          /* its vertices */
    uint32_t rest_first;     /* its first row in rest */
    uint32_t palette_first;  /* its first matrix in the palette (one a joint; a rigid placement: one) */
    uint32_t joints;         /* its skin's joints (0: rigid) */
    uint32_t morph_first;    /* its first target row in morph (targets x count rows) */
    uint32_t targets;        /* its morph targets */
    uint32_t weights_first;  /* its first morph weight */
} sb_pose_place;
#define SB_POSE_REST_FLOATS 24   /* pos.xyz, its placement (as uint bits); normal.xyz, 0; joints 0-7 (uint bits); weights 0-7 */
#define SB_POSE_MORPH_FLOATS 8   /* delta pos.xyz, 0; delta normal.xyz, 0 */
typedef struct sb_pose_data {
    uint32_t place_count, rest_count, morph_count;   /* rows of places, rest and morph */
    uint32_t palette_count, weight_count;            /* matrices and weights sb_motion_gpu_frame writes */
    const sb_pose_place *places;
    const uint32_t *place_draw;                       /* a draw of each placement (its vertices' numbering) */
    const float *rest, *morph;
} sb_pose_data;
