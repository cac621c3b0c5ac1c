/* eval.h - one evaluated frame: the untimed pass that measures how wrong a
 * technique's shadows are. The run loop, the stress battery and the tests all
 * evaluate through sb_eval_frame, so they measure the same thing. */
#pragma once
#include "error.h"
#include "flicker.h"
#include "session.h"

/* The read-back targets of an evaluated frame (w * h pixels, rows bottom-up). */
typedef struct sb_eval_buf {
    int w, h;
    unsigned char *vis;         /* the technique's visibility (255 lit) */
    unsigned char *rgba;        /* colour, when asked for (images) */
    unsigned char *ref;         /* the reference: 255 lit, 0 shadowed, 128 not evaluated */
    float *pos, *aux;           /* origin-relative position + texels per pixel; normal + cascade */
    uint64_t pixels_key[2];     /* --lights: sb_eval_view_pixels_key of the frame's targets, from its first light */
    /* the flicker twin's (made on first use): its lookup's visibility and
       positions, its own depth; flicker (rgb, when rgba is asked for): the
       points that flipped, black where nothing was compared */
    unsigned char *twin_vis, *flicker;
    float *twin_pos, *twin_depth;
    bool flicker_drawn;         /* flicker holds this frame's */
    /* --flip (made on first use): the base target (colour, N.L), the frame shaded with the technique's visibility
       and with the reference's (sRGB-encoded RGB floats) and their FLIP map */
    unsigned char *base;
    float *shaded, *shaded_ref, *flip;
    bool flip_drawn;            /* they hold this frame's */
} sb_eval_buf;

/* The reference's visibility of a pixel, for shading: its own where it scores the pixel, else the technique's. */
static inline double sb_eval_ref_vis(unsigned char ref, unsigned char vis) { return (ref == 128 ? vis : ref) / 255.0; }

/* A pixel lit the way the camera pass lights it, base colour x (ambient + direct N.L x visibility), in linear light,
 * from the base target (colour, N.L in alpha): --flip's and --taa's shaded frames. */
static inline void sb_eval_shade(const unsigned char base[4], double vis, float out[3]) {
    const double light = SB_SHADE_AMBIENT + SB_SHADE_DIRECT * (base[3] / 255.0) * vis;
    for (int c = 0; c < 3; c++) out[c] = (float)(base[c] / 255.0 * light);
}

void sb_eval_buf_init(sb_eval_buf *b, const sb_gpu *g, bool rgba);
void sb_eval_buf_free(sb_eval_buf *b);

/* Renders path frame pf of n with the evaluation targets bound, after
 * replaying the `replay` frames before it (sb_instance_history: a frame
 * depends on them), reads the targets back and measures the error against
 * the scene's reference. *seq is the run sequence number of the first frame
 * rendered and is advanced past the last. f gets the evaluated frame (its
 * camera, shaded light and counters, collected ones included). */
bool sb_eval_frame(sb_session *s, sb_instance *in, int pf, int n, int replay, int *seq, sb_eval_buf *b, sb_frame *f,
                   sb_error_metrics *m, sb_err *err);

/* After sb_eval_frame of the same frame (b and f as it left them): the
 * frame's twin, --flicker-dt of path time later, rendered next by the same
 * instance (its state goes on as in a run), with its camera pass drawing the
 * frame's camera, so that the frame's points are looked up in the twin's
 * maps; then the twin's own depth, for which of those points its camera sees.
 * Fills m's flicker figures (NaN with --flicker-dt 0, or where the
 * technique's final pass is not a lookup). */
bool sb_eval_flicker(sb_session *s, sb_instance *in, int pf, int n, int *seq, sb_eval_buf *b, const sb_frame *f,
                     sb_error_metrics *m, sb_err *err);

/* --overlap (on, or auto on a GPU), before a scene's runs: draws the frames the runs will
 * evaluate once (positions and normals, which every technique rasterizes the
 * same) and hands them to the reference's background (sb_ref_background_*),
 * which casts their answers while the runs render timed frames. Does
 * nothing with --overlap off or no evaluated frames; false with err when
 * the reference cannot be built or the frames not drawn. */
bool sb_eval_background(sb_session *s, sb_err *err);
