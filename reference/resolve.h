/* resolve.h - TAA's per-pixel resolve, the definition behind --taa's figures (beside flip.c and flicker.c: the
 * harness renders the display frames and hands them here; harness/taa.h says what is measured with them).
 *
 * Each display frame is rendered with a sub-pixel jitter of its projection (Halton 2,3); a resolve reprojects
 * the previous resolved frame to the current one by each pixel's surface point, clamps it to the current frame's
 * 3x3 neighbourhood and blends it exponentially, the current frame weighing SB_TAA_ALPHA. */
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "sbmath.h"

#define SB_TAA_ALPHA 0.1        /* the current frame's weight in the blend */

/* The k-th jitter of the sequence, in pixels in (-0.5, 0.5): Halton bases 2 and 3, from index 1. */
void sb_taa_jitter(int k, double *jx, double *jy);

/* One frame to resolve, w x h pixels, rows bottom-up. */
typedef struct sb_taa_frame {
    int w, h;
    const float *rgb, *vis;     /* the current shading: linear colour (3 floats a pixel) and visibility */
    const float *pos, *aux;     /* its evaluation targets (4 floats a pixel): surface points, origin-relative, and
                                   normals (none: the sky) */
    const sb_m4 *prev_vp;       /* the last display frame's view-projection without its jitter */
} sb_taa_frame;

/* Resolves f into the history (hist_rgb, hist_vis, in place): where have_history is false, where f holds no
 * surface, or where the point falls outside the last frame, the history is the current frame. */
void sb_taa_resolve(const sb_taa_frame *f, bool have_history, float *hist_rgb, float *hist_vis, float *out_rgb,
                    float *out_vis);
