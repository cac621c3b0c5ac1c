/* taa.h - temporal anti-aliasing in the evaluation loop (--taa on).
 *
 * What a player sees is not one raw frame but the frame resolved through TAA:
 * each display frame rendered with a sub-pixel jitter of its projection
 * (Halton 2,3), the previous resolved frame reprojected to it by each pixel's
 * surface point (the camera's motion and the movers'), clamped to the current
 * frame's 3x3 neighbourhood, and blended exponentially (the current frame
 * weighs SB_TAA_ALPHA). For an evaluated frame at path time t the evaluation
 * renders the SB_TAA_FRAMES display frames up to t (one --flicker-dt apart,
 * 1/60 s by default) and resolves two sequences through the same TAA, the same
 * jitter and the same history rules: the frames shaded with the technique's
 * visibility, and the same frames shaded with the reference's. TAA's own blur
 * is in both, so it is never counted as shadow error:
 *
 * - taa_flip_mean: LDR-FLIP of the resolved technique frame against the
 *   resolved reference frame (sRGB-encoded, as --flip's);
 * - taa_flicker_rate: the raw flicker's question asked of the resolved
 *   frames. Each display frame is drawn a second time from the same jittered
 *   camera with the shadow maps of the next display frame (t + dt: the
 *   flicker twin's maps, looked up from the frame's camera), and that
 *   sequence resolved through the same TAA. The share of the evaluated frame's
 *   scored pixels whose resolved shadow is on the other side of half lit in
 *   the two, while the reference's resolved shadow is not: the sampling (the
 *   cameras, the jitters, the history) is the same in both, so only what the
 *   technique's maps change from one display frame to the next is left, as
 *   far as TAA lets it through.
 *
 * Without --taa nothing of this runs: every figure and run id as before. */
#pragma once
#include "eval.h"
#include "resolve.h"   /* the per-pixel resolve and the jitter (reference/) */

#define SB_TAA_FRAMES 8         /* display frames resolved up to the evaluated one */

/* The frames --taa renders for an evaluated frame beyond the frame and its flicker twin (0 without it): what a
 * run's instance makes room for. */
int sb_taa_frames(const sb_run_opts *o);

/* The display frames and resolved sequences of a run's evaluation (made on first use into *t, w x h; free with
 * sb_taa_buf_free, NULL: nothing). */
typedef struct sb_taa_buf sb_taa_buf;
void sb_taa_buf_free(sb_taa_buf *t);

/* After sb_eval_frame and sb_eval_flicker of path frame pf of n: its TAA figures into m (NaN without --taa, with
 * --lights, or for score's frames). */
bool sb_eval_taa(sb_session *s, sb_instance *in, int pf, int n, int *seq, sb_taa_buf **t, int w, int h,
                 sb_error_metrics *m, sb_err *err);
