/* error.h - how wrong a frame's shadows are, against the exact reference.
 *
 * Evaluated pixels: not sky, and facing the light (geometric normal · sun > 0).
 * err_rate: share whose binary state (visibility < 0.5 is shadow) differs from
 * the reference, split into false shadow and false light; vis_mae: mean
 * |visibility - reference| (fractional for filtered techniques); resolution
 * error per pixel: max(-log2(shadow texels per pixel), 0), undersampling only. */
#pragma once
#include <stdint.h>

#include "reference.h"

typedef struct sb_error_metrics {
    long pixels;                       /* evaluated */
    double err_rate, false_shadow, false_lit, vis_mae;
    double res_err_mean, res_err_p95, texel_px_p95;   /* NaN when the technique has no map */
    uint64_t rays;
    double ray_ms;
} sb_error_metrics;

/* pos/aux: the evaluation targets (4 floats a pixel); vis: the technique's
 * visibility target; ref_out (optional, w*h): 255 lit, 0 shadowed, 128 not
 * evaluated. eye: camera position relative to the scene origin. light: as
 * sb_reference_visibility_light (the technique's shaded light). */
void sb_evaluate_frame(const sb_reference *r, const double light[4], sb_v3 eye, int w, int h, const float *pos,
                       const float *aux, const unsigned char *vis, unsigned char *ref_out, sb_error_metrics *out,
                       int threads);
