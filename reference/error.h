/* error.h - how wrong a frame's shadows are, against the exact reference.
 *
 * Evaluated pixels: not sky, and facing the light (geometric normal · sun > 0).
 * err_rate: share whose binary state (visibility < 0.5 is shadow) differs from
 * the reference, split into false shadow and false light; vis_mae: mean
 * |visibility - reference| (fractional for filtered techniques, and for the
 * reference of a light with a size); resolution
 * error per pixel: max(-log2(shadow texels per pixel), 0), undersampling only. */
#pragma once
#include <stdint.h>

#include "reference.h"

/* Whether the evaluation targets hold a surface at pixel i (aux: 4 floats a pixel, a normal there; cleared to 0
 * where nothing drew: the sky). */
static inline bool sb_eval_has_geometry(const float *aux, size_t i) {
    const float *a = aux + 4 * i;
    return a[0] * a[0] + a[1] * a[1] + a[2] * a[2] > 0.25f;
}

typedef struct sb_error_metrics {
    long pixels;                       /* evaluated */
    double err_rate, false_shadow, false_lit, vis_mae;
    /* a light with a size (--sun-size, --lamp-radius): the share of evaluated
       pixels the reference puts strictly inside a penumbra, and the mean
       |visibility - reference| over them (NaN: none) */
    double penumbra_px, penumbra_err;
    double res_err_mean, res_err_p95, texel_px_p95;   /* NaN when the technique has no map */
    /* One geometry: camera rays through every 2nd pixel of every 2nd row. A
     * sample mismatches when the first surface the ray meets is not where the
     * rasterizer put the pixel (or the rasterizer shows sky where the ray hits
     * something). The floor: the reference from the ray's exact hit point and
     * normal against the one from the rasterized position, on the sampled
     * evaluated pixels: how exact the error figures can be. */
    long geom_samples, geom_mismatches, floor_samples, floor_disagree;
    double geom_mismatch, err_floor;   /* shares; NaN without samples */
    /* Flicker (eval.c's twin, a short step of path time later, looks the
     * frame's points up in its own maps): over the evaluated points the twin's
     * camera also sees, the share whose shadow state changes while the
     * reference does not (flicker_rate), their mean |visibility change|
     * (flicker_vis), the share whose reference changes (ref_flicker: a moving
     * light), and the largest relative change of a cascade split
     * (split_jitter). NaN: not measured (--flicker-dt 0, or a technique whose
     * shadows are not a lookup). */
    double flicker_rate, flicker_vis, ref_flicker, split_jitter;
    long flicker_points;                /* the points they are over */
    /* A cached technique in a moving scene (eval.c): the share of evaluated pixels whose visibility differs
     * from the same technique's with its caches bypassed on the same frame (0 is the only right answer; NaN:
     * not measured, nothing cached or nothing moves). */
    double stale_px;
    /* --lights: the mean number of the run's lights evaluated at a pixel that at least one of them lights (NaN:
     * one light, as without --lights) */
    double lights_px;
    /* --flip: LDR-FLIP of the frame shaded with the technique's visibility against it shaded with the reference's
     * (base colour x (0.3 + 0.7 N.L x visibility), sRGB-encoded), mean and 95th percentile over every pixel (NaN:
     * not asked, or --lights) */
    double flip_mean, flip_p95;
    /* --taa on (harness/taa.h): the frame resolved through TAA, shaded with the technique's visibility, against the
     * same with the reference's: LDR-FLIP mean; and the share of its points whose resolved shadow changes at the
     * twin while the reference's does not (NaN: --taa off, --lights) */
    double taa_flip_mean, taa_flicker_rate;
    uint64_t rays;                     /* reference rays cast for this frame (0: the answers were reused) */
    double ray_ms;                     /* time in the reference for this frame (casting, or finding the answers) */
    bool reused;                       /* the reference's answers came from the cache */
    bool background;                   /* they were cast in the background for this run (rays counts them) */
} sb_error_metrics;

/* --lights: one light's figures of a frame added to those of the lights before it (acc zeroed first, its
 * err_rate... then shares of every evaluated (pixel, light) pair; the geometry check's, the camera's, from the
 * first light). */
void sb_error_metrics_add(sb_error_metrics *acc, const sb_error_metrics *e, bool first);

/* The reference's answers for a frame, kept by their exact inputs: the
 * rasterized positions and normals of every pixel, the camera, the size and
 * the light (not the technique's own values: texels per pixel, cascade). Two
 * runs that rasterize the same frame bit for bit (every technique of a
 * scene, path and size does) share one set of rays: what a cached answer
 * says is what casting would say. Entries past max_bytes go oldest first. */
typedef struct sb_ref_cache sb_ref_cache;
sb_ref_cache *sb_ref_cache_new(size_t max_bytes);
void sb_ref_cache_free(sb_ref_cache *c);
/* Kept across processes (a results folder's reference/): every answer with
 * its key, under a tag the caller makes of what else decides them (the
 * scene's contents, the binary); written whole and renamed. load adds the
 * file's answers when its tag and checksum hold and returns how many (0 for
 * a missing, stale or damaged file). dirty: answers added since made or loaded. */
bool sb_ref_cache_save(sb_ref_cache *c, const char *path, uint64_t tag, sb_err *err);
int sb_ref_cache_load(sb_ref_cache *c, const char *path, uint64_t tag);
bool sb_ref_cache_dirty(sb_ref_cache *c);

/* The frame being evaluated: the targets and the camera. */
typedef struct sb_eval_view sb_eval_view;

/* The background (overlap): the answers of frames the runs will evaluate,
 * cast while the GPU renders timed frames, on `threads` threads at the
 * lowest CPU priority there is (Linux SCHED_IDLE: they run only on cores
 * nothing else wants, so the timed frames' threads, a CPU rasterizer's
 * included, always go first). An evaluation that needs a queued frame takes
 * it back and casts it itself; one being cast is waited for. The first
 * evaluation to use background answers counts their rays as its own
 * (`background`, not `reused`). start: false where no such priority exists
 * (frames are then cast by the evaluation, as without it). add: copies the
 * view (2 x 16 bytes a pixel): 1 queued, 0 its answers are known or queued
 * already, -1 the queue holds SB_REF_BACKGROUND_BYTES (the rest are cast by
 * the evaluation). stop: drops what is queued, waits for the frame being
 * cast. */
#define SB_REF_BACKGROUND_BYTES ((size_t)1 << 30)
typedef struct sb_ref_background_stats {
    int queued, frames, dropped, taken_back, waited; /* frames queued, cast, dropped at stop, taken back; waits */
    uint64_t rays;
    double ms;                         /* casting, on the background's clock */
    double timed_ms;                   /* of it, while timed frames rendered (sb_ref_background_timed) */
} sb_ref_background_stats;
bool sb_ref_background_start(sb_ref_cache *c, const sb_reference *r, int threads);
int sb_ref_background_add(sb_ref_cache *c, const sb_eval_view *v);
sb_ref_background_stats sb_ref_background_stop(sb_ref_cache *c);
/* Timed frames begin (on) and end: how much casting they overlapped is in the stats. */
void sb_ref_background_timed(sb_ref_cache *c, bool on);

struct sb_eval_view {
    int w, h;
    const float *pos, *aux;            /* the evaluation targets (4 floats a pixel) */
    sb_v3 eye;                         /* camera position relative to the scene origin */
    const sb_m4 *inv_view_proj;        /* origin-relative clip -> world (NULL: no geometry check) */
    const double *light;               /* as sb_reference_visibility_light: the technique's shaded light */
    double range;                      /* a lamp's range; points beyond it are not evaluated (0: none) */
    double spot[4];                    /* a spot light: the way it shines (unit) and 1 - cos of its outer cone;
                                          points outside the cone are not evaluated (all 0: none) */
    const uint64_t *pixels_key;        /* sb_eval_view_pixels_key of pos and aux, where the caller has it (NULL:
                                          computed): the lights of one --lights frame share the targets */
};

/* Two 64-bit hashes of the view's pos and aux (xyz of each): part of the key of the reference's answers. */
void sb_eval_view_pixels_key(const sb_eval_view *v, uint64_t key[2]);

/* The points the reference casts from (pts and pix: w*h capacity; pix[k] is
 * the pixel of pts[k]): every pixel that is not sky, faces the light and lies within its range and cone, from
 * its rasterized position and geometric normal. Returns how many. */
int sb_ref_points(const sb_reference *r, const sb_eval_view *v, sb_ref_point *pts, int *pix);

/* vis: the technique's visibility target; ref_out (optional, w*h): 255 lit,
 * 0 shadowed, 128 not evaluated. */
void sb_evaluate_frame(const sb_reference *r, sb_ref_cache *cache, const sb_eval_view *v, const unsigned char *vis,
                       unsigned char *ref_out, sb_error_metrics *out, int threads);
