/* taa.c - temporal anti-aliasing in the evaluation loop (see taa.h). */
#include "taa.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "flip.h"
#include "resolve.h"
#include "timing.h"

/* A sequence resolved through TAA: its last resolved frame, linear shaded colour and visibility. */
typedef struct taa_seq {
    float *rgb, *vis;
    bool have;
} taa_seq;

/* The sequences: the frames as drawn, shaded with the technique's visibility and with the reference's; and the
 * same cameras and jitters with each frame's shadow maps those of the next display frame (the twin's, looked up
 * from the frame's camera, as the raw flicker's twin), shaded both ways. */
enum { SEQ_TECH, SEQ_REF, SEQ_TWIN_TECH, SEQ_TWIN_REF, SEQ_COUNT };

struct sb_taa_buf {
    int w, h;
    /* the display frame just drawn: its targets, and its shading with the technique's and the reference's
       visibility (linear colour; visibility in [0, 1], the reference's the technique's where it scores none) */
    unsigned char *vis, *ref, *base;
    float *pos, *aux;
    float *cur_rgb[2], *cur_vis[2];
    taa_seq seq[SEQ_COUNT];
    float *out_rgb, *out_vis;   /* a resolve's output */
    sb_m4 prev_vp;              /* the last display frame's view-projection without its jitter */
    unsigned char *eval_ref;    /* the evaluated frame's reference: which pixels it scores */
};

int sb_taa_frames(const sb_run_opts *o) { return o->taa ? SB_TAA_FRAMES + 1 : 0; }

void sb_taa_buf_free(struct sb_taa_buf *t) {
    if (!t) return;
    free(t->vis), free(t->ref), free(t->base), free(t->pos), free(t->aux), free(t->eval_ref);
    for (int k = 0; k < 2; k++) free(t->cur_rgb[k]), free(t->cur_vis[k]);
    for (int k = 0; k < SEQ_COUNT; k++) free(t->seq[k].rgb), free(t->seq[k].vis);
    free(t->out_rgb), free(t->out_vis);
    free(t);
}

static struct sb_taa_buf *taa_buf(int w, int h) {
    struct sb_taa_buf *t = sb_xcalloc(1, sizeof *t);
    const size_t n = (size_t)w * h;
    t->w = w, t->h = h;
    t->vis = sb_xmalloc(n), t->ref = sb_xmalloc(n), t->base = sb_xmalloc(4 * n), t->eval_ref = sb_xmalloc(n);
    t->pos = sb_xmalloc(sizeof(float) * 4 * n), t->aux = sb_xmalloc(sizeof(float) * 4 * n);
    t->out_rgb = sb_xmalloc(sizeof(float) * 3 * n), t->out_vis = sb_xmalloc(sizeof(float) * n);
    for (int k = 0; k < 2; k++)
        t->cur_rgb[k] = sb_xmalloc(sizeof(float) * 3 * n), t->cur_vis[k] = sb_xmalloc(sizeof(float) * n);
    for (int k = 0; k < SEQ_COUNT; k++)
        t->seq[k].rgb = sb_xmalloc(sizeof(float) * 3 * n), t->seq[k].vis = sb_xmalloc(sizeof(float) * n);
    return t;
}

/* One resolve of the current shading `cur` (0: the technique's, 1: the reference's) into sequence q (resolve.h):
 * its history reprojected to the current frame by each pixel's surface point, clamped and blended. */
static void resolve(struct sb_taa_buf *t, int cur, int q_index) {
    taa_seq *q = &t->seq[q_index];
    sb_taa_frame f = {.w = t->w, .h = t->h, .rgb = t->cur_rgb[cur], .vis = t->cur_vis[cur], .pos = t->pos,
                      .aux = t->aux, .prev_vp = &t->prev_vp};
    sb_taa_resolve(&f, q->have, q->rgb, q->vis, t->out_rgb, t->out_vis);
    q->have = true;
}

/* The frame just drawn: read back, scored by the reference, shaded both ways, resolved into sequences q and q + 1. */
static bool take(sb_session *s, struct sb_taa_buf *t, const sb_frame *g, int q, sb_err *err) {
    sb_gpu_readback(&s->gpu, NULL, t->vis, NULL);
    sb_gpu_readback_eval(&s->gpu, t->pos, t->aux);
    sb_gpu_readback_base(&s->gpu, t->base);
    if (!sb_gl_check("the TAA frames", err)) return false;
    const sb_reference *ref = sb_session_reference(s, err);
    if (!ref) return false;
    sb_eval_view view = {t->w, t->h, t->pos, t->aux, g->look ? g->look->eye : sb_v3_sub(g->cam.pos, s->scene.origin),
                         NULL, g->shade_light, g->shade_range,
                         {g->shade_spot[0], g->shade_spot[1], g->shade_spot[2], g->shade_spot[3]}, NULL};
    sb_error_metrics e;
    memset(&e, 0, sizeof e);
    sb_evaluate_frame(ref, s->ref_cache, &view, t->vis, t->ref, &e, s->opts.threads);
    const size_t np = (size_t)t->w * t->h;
    for (size_t i = 0; i < np; i++) {   /* as --flip shades */
        const double v[2] = {t->vis[i] / 255.0, sb_eval_ref_vis(t->ref[i], t->vis[i])};
        for (int k = 0; k < 2; k++) {
            t->cur_vis[k][i] = (float)v[k];
            sb_eval_shade(t->base + 4 * i, v[k], t->cur_rgb[k] + 3 * i);
        }
    }
    resolve(t, 0, q);
    resolve(t, 1, q + 1);
    return true;
}

/* Display frame k at path time `time`, jittered: drawn as it is (sequences SEQ_TECH, SEQ_REF), then with the maps
 * of time + dt looked up from the same jittered camera (SEQ_TWIN_*). */
static bool display_frame(sb_session *s, sb_instance *in, struct sb_taa_buf *t, int pf, int n, double time, double dt,
                          int k, int *seq, sb_err *err) {
    const double aspect = (double)s->opts.width / s->opts.height;
    double jx, jy;
    sb_taa_jitter(k, &jx, &jy);
    sb_frame g, tw;
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 1, 2);
    sb_session_pose(s, time);
    sb_camera cam = sb_path_camera_at(&s->path, time, aspect, &s->scene);
    memset(&g, 0, sizeof g);
    g.index = pf;
    g.progress = sb_path_progress(pf, n);
    sb_timer_frame_begin(&timer, 0);
    sb_render_camera_jittered(s, in, &g, &cam, (*seq)++, &timer, true, jx, jy);
    bool ok = take(s, t, &g, SEQ_TECH, err);
    sb_look look = {.view = g.view, .proj = g.proj, .eye = sb_v3_sub(g.cam.pos, s->scene.origin)};
    memcpy(look.frustum, g.frustum, sizeof look.frustum);
    if (ok) {
        sb_session_pose(s, time + dt);
        sb_camera next = sb_path_camera_at(&s->path, time + dt, aspect, &s->scene);
        memset(&tw, 0, sizeof tw);
        tw.index = pf;
        tw.progress = g.progress;
        tw.look = &look;
        sb_timer_frame_begin(&timer, 1);
        sb_render_camera(s, in, &tw, &next, (*seq)++, &timer, true);
        ok = take(s, t, &tw, SEQ_TWIN_TECH, err);
    }
    sb_timer_free(&timer);
    /* the next frame reprojects by this one's view-projection without its jitter */
    sb_frame_jitter(&g, -jx, -jy);
    t->prev_vp = g.view_proj;
    return ok;
}

bool sb_eval_taa(sb_session *s, sb_instance *in, int pf, int n, int *seq, sb_taa_buf **tb, int w, int h,
                 sb_error_metrics *m, sb_err *err) {
    m->taa_flip_mean = m->taa_flicker_rate = NAN;
    /* --lights, another renderer's frames (none between the path's): not resolved (taa.h) */
    if (!s->opts.taa || in->rc.lights || (in->tech->traits & SB_TRAIT_FOREIGN)) return true;
    if (!*tb) *tb = taa_buf(w, h);
    struct sb_taa_buf *t = *tb;
    const size_t np = (size_t)t->w * t->h;
    const double dt = s->opts.flicker_dt > 0 ? s->opts.flicker_dt : 1.0 / 60;
    const double time = sb_path_progress(pf, n) * sb_path_duration(&s->path);
    for (int q = 0; q < SEQ_COUNT; q++) t->seq[q].have = false;
    for (int k = 0; k < SB_TAA_FRAMES; k++)
        if (!display_frame(s, in, t, pf, n, time - (SB_TAA_FRAMES - 1 - k) * dt, dt, k, seq, err)) return false;
    /* the evaluated frame, resolved: its LDR-FLIP against the reference's, sRGB-encoded as --flip's */
    float *enc[2];
    for (int q = 0; q < 2; q++) {
        enc[q] = sb_xmalloc(sizeof(float) * 3 * np);
        for (size_t i = 0; i < 3 * np; i++) enc[q][i] = sb_srgb_encode(t->seq[q == 0 ? SEQ_TECH : SEQ_REF].rgb[i]);
    }
    sb_flip_stats st = sb_flip(enc[1], enc[0], t->w, t->h, 0, NULL);
    free(enc[0]), free(enc[1]);
    m->taa_flip_mean = st.mean;
    /* flicker through TAA: where the resolved shadow with the next display frame's maps is on the other side of
       half lit than the resolved shadow as drawn, while the reference's stays; over the pixels the evaluated frame
       scores (the last twin's reference marks them as the frame's: the same camera) */
    long compared = 0, flipped = 0;
    for (size_t i = 0; i < np; i++) {
        if (t->ref[i] == 128) continue;   /* not scored (sky, facing away, out of range) */
        compared++;
        bool tech = (t->seq[SEQ_TECH].vis[i] >= 0.5f) != (t->seq[SEQ_TWIN_TECH].vis[i] >= 0.5f),
             refc = (t->seq[SEQ_REF].vis[i] >= 0.5f) != (t->seq[SEQ_TWIN_REF].vis[i] >= 0.5f);
        flipped += tech && !refc;
    }
    m->taa_flicker_rate = compared ? (double)flipped / compared : NAN;
    return true;
}
