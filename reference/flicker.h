/* flicker.h - flicker_rate and its companions: how a frame's shadows change
 * at the same points a short step of path time later, against how the exact
 * reference's change there.
 *
 * The harness renders the twin (eval.c: the next frame a display would show,
 * its camera pass drawn from the frame's camera, so that the frame's points
 * are looked up in the twin's maps, then the twin's own depth) and hands the
 * read-back targets here; this is where the figures are defined. */
#pragma once
#include <stdbool.h>

#include "error.h"

/* A frame's cascade split distances (view-space far distance of each; count 0: none). */
typedef struct sb_splits {
    int count;
    const double *far;
} sb_splits;

/* The frame and its twin, as read back (w x h pixels, rows bottom-up). */
typedef struct sb_flicker_view {
    int w, h;
    const unsigned char *vis;          /* the frame's visibility (255 lit) */
    const unsigned char *ref;          /* its reference: 255 lit, 0 shadowed, 128 not evaluated */
    const float *pos, *aux;            /* its positions and normals (4 floats a pixel) */
    sb_v3 eye;                         /* its camera, origin-relative */
    const double *light;               /* its shaded light (sb_reference_visibility_light) */
    sb_splits splits;                  /* its split distances */
    /* the twin */
    const unsigned char *twin_vis;     /* its lookup of the frame's points */
    const float *twin_pos;             /* the positions that lookup drew (another surface: not compared) */
    const float *twin_depth;           /* its own camera's depth (which points it sees) */
    sb_m4 twin_view_proj, twin_proj;   /* its camera (origin-relative) */
    const double *twin_light;
    sb_splits twin_splits;
    bool looked_up;                    /* the twin's final pass was a lookup (not split by a stencil) */
    bool scene_moved;           /* the twin's scene is posed otherwise (its clips play): the reference is cast again */
    unsigned char *image;              /* optional, 3 bytes a pixel: the points that flipped (lit -> shadowed red,
                                          shadowed -> lit blue), grey where steady, black where not compared */
} sb_flicker_view;

/* The largest relative change of a split distance between two frames (NaN: no splits). */
double sb_split_jitter(const sb_splits *a, const sb_splits *b);

/* Fills m's flicker_rate, flicker_vis, ref_flicker, split_jitter and
 * flicker_points: over the evaluated points the twin's camera also sees (in
 * its view, not behind its depth by more than 1 % of the distance, the same
 * surface looked up), the share whose shadow state changes while the
 * reference's does not; where the light moved between the two, the reference
 * is cast again at the twin's light (r, threads), and the points whose
 * reference changed are ref_flicker's, not the technique's. The figures are
 * NaN where nothing is compared (no lookup, no steady point). Returns
 * whether points were compared (the image drawn). */
bool sb_evaluate_flicker(const sb_reference *r, const sb_flicker_view *v, sb_error_metrics *m, int threads);
