/* eval.c - one evaluated frame (see eval.h). */
#include "eval.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "flip.h"

void sb_eval_buf_init(sb_eval_buf *b, const sb_gpu *g, bool rgba) {
    memset(b, 0, sizeof *b);
    b->w = g->width;
    b->h = g->height;
    size_t n = (size_t)b->w * b->h;
    b->vis = sb_xmalloc(n);
    b->ref = sb_xmalloc(n);
    b->rgba = rgba ? sb_xmalloc(4 * n) : NULL;
    b->pos = sb_xmalloc(sizeof(float) * 4 * n);
    b->aux = sb_xmalloc(sizeof(float) * 4 * n);
}

void sb_eval_buf_free(sb_eval_buf *b) {
    free(b->vis);
    free(b->ref);
    free(b->rgba);
    free(b->pos);
    free(b->aux);
    free(b->twin_vis);
    free(b->flicker);
    free(b->twin_pos);
    free(b->twin_depth);
    free(b->base);
    free(b->shaded);
    free(b->shaded_ref);
    free(b->flip);
    memset(b, 0, sizeof *b);
}

/* Renders path frame pf of n (after `replay` earlier ones) with the
 * evaluation targets bound and reads them back (aux unless b holds this
 * frame's already: a further light of --lights; pos always, whose w is the
 * light's own texel density); view points into b. */
static void render_targets(sb_session *s, sb_instance *in, int pf, int n, int replay, int *seq, sb_eval_buf *b,
                           sb_frame *f, bool vis, sb_m4 *inv, sb_eval_view *view, int light, bool have_aux) {
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 1, 1);
    for (int k = replay; k >= 0; k--) {
        /* before the path's first frame, the first frame itself: the timed pass reached it after warm-up frames
           of it, so a technique that reads an earlier frame's figures (sdsm's latency) has them of this view, not
           of whatever the evaluation drew last (a camera cut: 8x the error on desert's frame 0) */
        const int at = pf - k < 0 ? 0 : pf - k;
        memset(f, 0, sizeof *f);
        f->eval_light = light;
        f->anim_ms = sb_session_pose(s, sb_session_frame_time(s, at, n));
        sb_timer_frame_begin(&timer, 0);
        sb_camera cam = sb_path_camera(&s->path, at, n, (double)s->opts.width / s->opts.height, &s->scene);
        f->index = at;
        f->progress = sb_path_progress(at, n);
        sb_render_camera(s, in, f, &cam, (*seq)++, &timer, k == 0);
    }
    sb_timer_free(&timer);
    if (in->tech->collect) in->tech->collect(in->state, f->seq, &f->counters);
    if (vis) sb_gpu_readback(&s->gpu, NULL, b->vis, b->rgba);
    sb_gpu_readback_eval(&s->gpu, b->pos, have_aux ? NULL : b->aux);
    bool have_inv = sb_m4_invert(f->view_proj, inv);
    *view = (sb_eval_view){b->w, b->h, b->pos, b->aux, sb_v3_sub(f->cam.pos, s->scene.origin), have_inv ? inv : NULL,
                           f->shade_light, f->shade_range, {f->shade_spot[0], f->shade_spot[1], f->shade_spot[2],
                           f->shade_spot[3]}, NULL};
}

/* Whether the instance keeps maps or pages across frames while the scene moves: what the stale check is for. */
static bool caches_in_motion(const sb_session *s, const sb_instance *in) {
    double on;
    return sb_scene_moves(&s->scene) && sb_params_role(&in->spec->params, SB_PARAM_CACHE, &on) && on != 0;
}

/* The stale check: the frame drawn again with the technique's caches bypassed (everything drawn fresh, and what
 * it kept forgotten, so nothing of this draw is kept); the share of evaluated pixels whose visibility differs
 * from the cached frame's. */
static double stale_share(sb_session *s, sb_instance *in, int *seq, const sb_eval_buf *b, const sb_frame *f) {
    sb_frame g;
    memset(&g, 0, sizeof g);
    g.index = f->index;
    g.progress = f->progress;
    g.eval_light = f->eval_light;   /* --lights: the same one light */
    g.bypass_cache = true;
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 1, 1);
    sb_timer_frame_begin(&timer, 0);
    sb_render_camera(s, in, &g, &f->cam, (*seq)++, &timer, true);
    sb_timer_free(&timer);
    unsigned char *fresh = sb_xmalloc((size_t)b->w * b->h);
    sb_gpu_readback(&s->gpu, NULL, fresh, NULL);
    long n = 0, differ = 0;
    for (size_t i = 0; i < (size_t)b->w * b->h; i++) {
        if (b->ref[i] == 128) continue;   /* not evaluated (sky, facing away) */
        n++;
        differ += fresh[i] != b->vis[i];
    }
    free(fresh);
    return n ? (double)differ / n : NAN;
}

/* The shaded frame, engines' way with this tool's lights: base colour x (ambient + direct N.L x visibility, as the
 * camera pass: SB_SHADE_AMBIENT, SB_SHADE_DIRECT),
 * once with the technique's visibility and once with the reference's (where the reference scores no pixel, sky
 * or facing away, the technique's), sRGB-encoded for display; no tone map: 0.3 + 0.7 N.L is at most 1. Then
 * their LDR-FLIP at the default viewing condition. b->base: the frame's, read before anything else drew. */
static void shade_and_flip(sb_eval_buf *b, sb_error_metrics *m) {
    const size_t n = (size_t)b->w * b->h;
    if (!b->shaded) {
        b->shaded = sb_xmalloc(sizeof(float) * 3 * n);
        b->shaded_ref = sb_xmalloc(sizeof(float) * 3 * n);
        b->flip = sb_xmalloc(sizeof(float) * n);
    }
    for (size_t i = 0; i < n; i++) {
        sb_eval_shade(b->base + 4 * i, b->vis[i] / 255.0, b->shaded + 3 * i);
        sb_eval_shade(b->base + 4 * i, sb_eval_ref_vis(b->ref[i], b->vis[i]), b->shaded_ref + 3 * i);
        for (int c = 0; c < 3; c++) {
            b->shaded[3 * i + c] = sb_srgb_encode(b->shaded[3 * i + c]);
            b->shaded_ref[3 * i + c] = sb_srgb_encode(b->shaded_ref[3 * i + c]);
        }
    }
    sb_flip_stats st = sb_flip(b->shaded_ref, b->shaded, b->w, b->h, 0, b->flip);
    m->flip_mean = st.mean, m->flip_p95 = st.p95;
    b->flip_drawn = true;
}

/* One light's evaluation (light: 1 + its place in the run's --lights; 0: the run's one light; last: the set's
 * last, whose targets the images show). The camera's geometry is every light's: the first light's aux and the
 * key of its pixels serve the rest. */
static bool eval_light(sb_session *s, sb_instance *in, int pf, int n, int replay, int *seq, sb_eval_buf *b, sb_frame *f,
                       sb_error_metrics *m, int light, bool last, sb_err *err) {
    sb_m4 inv;
    sb_eval_view view;
    render_targets(s, in, pf, n, replay, seq, b, f, true, &inv, &view, light, light > 1 && !last);
    long checked_px = 0, misaligned_px = 0;   /* the technique's own check of its input (check_frame) */
    if (in->tech->check_frame &&
        !in->tech->check_frame(in->state, pf, b->w, b->h, b->aux, &checked_px, &misaligned_px, err)) {
        if (!s->input_refused[0]) snprintf(s->input_refused, sizeof s->input_refused, "%s", err->msg);
        return false;
    }
    const bool flip = s->opts.flip && light == 0;   /* --lights: not over several lights (docs/error.md) */
    if (flip) {   /* now: the stale check draws again */
        if (!b->base) b->base = sb_xmalloc(4 * (size_t)b->w * b->h);
        sb_gpu_readback_base(&s->gpu, b->base);
    }
    if (light == 1) sb_eval_view_pixels_key(&view, b->pixels_key);
    if (light >= 1) view.pixels_key = b->pixels_key;
    if (light > 1) view.inv_view_proj = NULL;   /* the camera's geometry check: once, with the first light */
    const sb_reference *ref = sb_session_reference(s, err);   /* refit to the frame's pose */
    if (!ref) return false;
    sb_evaluate_frame(ref, s->ref_cache, &view, b->vis, b->ref, m, s->opts.threads);
    if (checked_px) {   /* counted with the rays' own check of the geometry */
        m->geom_samples += checked_px, m->geom_mismatches += misaligned_px;
        m->geom_mismatch = (double)m->geom_mismatches / m->geom_samples;
    }
    m->stale_px = caches_in_motion(s, in) ? stale_share(s, in, seq, b, f) : NAN;
    m->lights_px = NAN;
    m->flip_mean = m->flip_p95 = NAN;
    m->taa_flip_mean = m->taa_flicker_rate = NAN;   /* sb_eval_taa's, with --taa on */
    b->flip_drawn = false;
    if (flip) shade_and_flip(b, m);
    return sb_gl_check("evaluation pass", err);
}

bool sb_eval_frame(sb_session *s, sb_instance *in, int pf, int n, int replay, int *seq, sb_eval_buf *b, sb_frame *f,
                   sb_error_metrics *m, sb_err *err) {
    const sb_light_set *set = in->rc.lights;
    if (!set) return eval_light(s, in, pf, n, replay, seq, b, f, m, 0, true, err);
    /* --lights: each light of the set scored on its own (pixels it lights, rays to it), the figures over every
       (pixel, light) pair; b->vis and b->ref hold the last light's, images show the frame lit by every light */
    size_t np = (size_t)b->w * b->h;
    uint16_t *lit = sb_xcalloc(np, sizeof *lit);
    for (int i = 0; i < set->count; i++) {
        sb_error_metrics e;
        if (!eval_light(s, in, pf, n, replay, seq, b, f, &e, i + 1, i + 1 == set->count, err)) {
            free(lit);
            return false;
        }
        sb_error_metrics_add(m, &e, i == 0);
        for (size_t k = 0; k < np; k++) lit[k] += b->ref[k] != 128;
    }
    long pairs = 0, pixels = 0;
    for (size_t k = 0; k < np; k++) pairs += lit[k], pixels += lit[k] > 0;
    m->lights_px = pixels ? (double)pairs / pixels : NAN;
    free(lit);
    if (b->rgba) {   /* the frame as timed frames draw it: every light */
        sb_frame g;
        memset(&g, 0, sizeof g);
        sb_timer timer;
        sb_timer_init(&timer, SB_TIMING_SYNC, 1, 1);
        sb_timer_frame_begin(&timer, 0);
        sb_render_camera(s, in, &g, &f->cam, (*seq)++, &timer, true);
        sb_timer_free(&timer);
        sb_gpu_readback(&s->gpu, NULL, NULL, b->rgba);
    }
    return true;
}

bool sb_eval_flicker(sb_session *s, sb_instance *in, int pf, int n, int *seq, sb_eval_buf *b, const sb_frame *f,
                     sb_error_metrics *m, sb_err *err) {
    m->flicker_rate = m->flicker_vis = m->ref_flicker = m->split_jitter = NAN;
    m->flicker_points = 0;
    b->flicker_drawn = false;
    const double dt = s->opts.flicker_dt;
    /* --lights: not measured over several lights (docs/error.md); another renderer's frames have no twin */
    if (dt <= 0 || in->rc.lights || (in->tech->traits & SB_TRAIT_FOREIGN)) return true;
    const size_t np = (size_t)b->w * b->h;
    if (!b->twin_vis) {
        b->twin_vis = sb_xmalloc(np);
        b->twin_pos = sb_xmalloc(sizeof(float) * 4 * np);
        b->twin_depth = sb_xmalloc(sizeof(float) * np);
        if (b->rgba) b->flicker = sb_xmalloc(3 * np);
    }
    /* the twin: the next frame the display would show, its camera pass drawn from the frame's camera */
    const sb_path *path = &s->path;
    double t = sb_path_progress(pf, n) * sb_path_duration(path);
    sb_session_pose(s, t + dt);   /* the scene a display frame later too: a moving caster's shadow moves */
    sb_camera cam = sb_path_camera_at(path, t + dt, (double)s->opts.width / s->opts.height, &s->scene);
    sb_look look = {.view = f->view, .proj = f->proj, .eye = sb_v3_sub(f->cam.pos, s->scene.origin)};
    memcpy(look.frustum, f->frustum, sizeof look.frustum);
    sb_frame tw;
    memset(&tw, 0, sizeof tw);
    tw.index = pf;
    tw.progress = sb_path_progress(pf, n);
    tw.look = &look;
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 1, 1);
    sb_timer_frame_begin(&timer, 0);
    sb_render_camera(s, in, &tw, &cam, (*seq)++, &timer, true);
    sb_timer_free(&timer);
    if (in->tech->collect) in->tech->collect(in->state, tw.seq, &tw.counters);
    sb_gpu_readback(&s->gpu, NULL, b->twin_vis, NULL);
    sb_gpu_readback_eval(&s->gpu, b->twin_pos, NULL);
    const bool looked = !tw.look_failed;
    /* the twin's own view: which of the frame's points it sees */
    tw.look = NULL;
    sb_zpass(&tw);
    sb_gpu_readback(&s->gpu, b->twin_depth, NULL, NULL);
    if (!sb_gl_check("the flicker twin", err)) return false;
    const sb_reference *ref = sb_session_reference(s, err);
    if (!ref) return false;
    sb_flicker_view v = {.w = b->w, .h = b->h, .vis = b->vis, .ref = b->ref, .pos = b->pos, .aux = b->aux,
                         .eye = look.eye, .light = f->shade_light,
                         .splits = {f->counters.split_count, f->counters.splits},
                         .twin_vis = b->twin_vis, .twin_pos = b->twin_pos, .twin_depth = b->twin_depth,
                         .twin_view_proj = tw.view_proj, .twin_proj = tw.proj, .twin_light = tw.shade_light,
                         .twin_splits = {tw.counters.split_count, tw.counters.splits}, .looked_up = looked, .image = b->flicker,
                         .scene_moved = sb_scene_moves(&s->scene)};
    b->flicker_drawn = sb_evaluate_flicker(ref, &v, m, s->opts.threads) && b->flicker;
    return true;
}

bool sb_eval_background(sb_session *s, sb_err *err) {
    const sb_run_opts *o = &s->opts;
    /* auto: not on a CPU rasterizer, which leaves the background no idle core during timed frames and draws
       the extra frames on the CPU too (measured: a net loss there; README, Error); never where the scene
       moves (the background would need the scene posed at its frames' times while the runs pose it at theirs) */
    bool on = (o->overlap < 0 ? !s->ctx.software : o->overlap > 0) && !sb_scene_moves(&s->scene) && !s->lights.count;
    if (!on || o->error_every <= 0) return true;
    const sb_reference *ref = sb_session_reference(s, err);
    if (!ref) return false;
    if (!sb_ref_background_start(s->ref_cache, ref, o->threads)) {
        static bool said;
        if (!said) sb_log("note: no idle CPU priority here; the reference is cast in the evaluation pass, as with --overlap off");
        said = true;
        return true;
    }
    /* every technique rasterizes a frame's positions and normals the same: draw them once, without shadows */
    sb_run_spec spec;
    sb_spec_defaults(&spec, sb_technique_with(SB_TRAIT_NO_SHADOWS));
    sb_instance in;
    if (!sb_instance_create(&in, s, &spec, 1, err)) return false;
    sb_eval_buf b;
    sb_eval_buf_init(&b, &s->gpu, false);
    int seq = 0;
    for (int pf = 0; pf < o->frames; pf += o->error_every) {
        sb_frame f;
        sb_m4 inv;
        sb_eval_view view;
        render_targets(s, &in, pf, o->frames, 0, &seq, &b, &f, false, &inv, &view, 0, false);
        if (sb_ref_background_add(s->ref_cache, &view) < 0) break; /* as much as it may hold */
    }
    sb_eval_buf_free(&b);
    sb_instance_destroy(&in);
    return sb_gl_check("the reference's background frames", err);
}
