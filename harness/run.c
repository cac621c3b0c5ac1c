/* run.c - sessions, technique instances, and the timed frame loop. */
#include "run.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "eval.h"
#include "image.h"
#include "reference.h"
#include "report.h"
#include "stats.h"

void sb_run_opts_defaults(sb_run_opts *o) {
    memset(o, 0, sizeof *o);
    o->backend = SB_BACKEND_EGL;
    o->timing = SB_TIMING_AUTO;
    o->ring = 3;
    o->frames = 60;
    o->warmup = 3;
    o->width = 1280;
    o->height = 720;
    o->error_every = 10;
    o->repeat = 1;
    o->max_repeat = 10;
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    o->threads = cpus > 1024 ? 1024 : cpus > 0 ? (int)cpus : 1;
}

int sb_run_opts_set(sb_run_opts *o, const char *a, const char *v, sb_err *err) {
    long n;
    if (!v) return sb_fail(err, "%s needs a value", a), -1;
    if (!strcmp(a, "--backend")) {
        if (!sb_backend_parse(v, &o->backend)) return sb_fail(err, "--backend %s: expected egl or osmesa", v), -1;
    } else if (!strcmp(a, "--timing")) {
        if (!sb_timing_parse(v, &o->timing)) return sb_fail(err, "--timing %s: expected auto, queries or sync", v), -1;
    } else if (!strcmp(a, "--ring")) {
        if (!sb_parse_int(v, &n) || n < 1 || n > 16) return sb_fail(err, "--ring %s: expected 1..16", v), -1;
        o->ring = (int)n;
    } else if (!strcmp(a, "--frames")) {
        if (!sb_parse_int(v, &n) || n < 1 || n > 1000000) return sb_fail(err, "--frames %s: expected 1..1000000", v), -1;
        o->frames = (int)n;
    } else if (!strcmp(a, "--warmup")) {
        if (!sb_parse_int(v, &n) || n < 0 || n > 10000) return sb_fail(err, "--warmup %s: expected 0..10000", v), -1;
        o->warmup = (int)n;
    } else if (!strcmp(a, "--size")) {
        int w, h;
        char extra;
        if (sscanf(v, "%dx%d%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384)
            return sb_fail(err, "--size %s: expected WxH, e.g. 1280x720", v), -1;
        o->width = w;
        o->height = h;
    } else if (!strcmp(a, "--sun")) {
        char buf[64];
        snprintf(buf, sizeof buf, "%s", v);
        char *comma = strchr(buf, ',');
        if (comma) *comma = 0;
        if (!comma || !sb_parse_double(buf, &o->sun_az) || !sb_parse_double(comma + 1, &o->sun_el) ||
            o->sun_el < -90 || o->sun_el > 90)
            return sb_fail(err, "--sun %s: expected AZIMUTH,ELEVATION in degrees (elevation -90..90)", v), -1;
        o->sun_override = true;
    } else if (!strcmp(a, "--images")) {
        if (!sb_parse_int(v, &n) || n < 0 || n > 1000000) return sb_fail(err, "--images %s: expected a frame interval >= 0", v), -1;
        o->images = (int)n;
    } else if (!strcmp(a, "--error-every")) {
        if (!sb_parse_int(v, &n) || n < 0 || n > 1000000) return sb_fail(err, "--error-every %s: expected a frame interval >= 0", v), -1;
        o->error_every = (int)n;
    } else if (!strcmp(a, "--repeat")) {
        if (!sb_parse_int(v, &n) || n < 1 || n > 1000) return sb_fail(err, "--repeat %s: expected 1..1000", v), -1;
        o->repeat = (int)n;
    } else if (!strcmp(a, "--target-ci")) {
        if (!sb_parse_double(v, &o->target_ci) || o->target_ci <= 0 || o->target_ci > 100)
            return sb_fail(err, "--target-ci %s: expected a percentage in (0, 100]", v), -1;
    } else if (!strcmp(a, "--max-repeat")) {
        if (!sb_parse_int(v, &n) || n < 1 || n > 1000) return sb_fail(err, "--max-repeat %s: expected 1..1000", v), -1;
        o->max_repeat = (int)n;
    } else if (!strcmp(a, "--threads")) {
        if (!sb_parse_int(v, &n) || n < 1 || n > 1024) return sb_fail(err, "--threads %s: expected 1..1024", v), -1;
        o->threads = (int)n;
    } else if (!strcmp(a, "--run-timeout")) {
        if (!sb_parse_double(v, &o->run_timeout_s) || o->run_timeout_s < 0)
            return sb_fail(err, "--run-timeout %s: expected seconds >= 0", v), -1;
    } else {
        return 0;
    }
    return 1;
}

static void base_name(const char *path, char *out, size_t len) {
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    snprintf(out, len, "%s", b);
    char *dot = strrchr(out, '.');
    if (dot && dot != out && !strchr(dot, '#')) *dot = 0;
}

/* ---- sessions ---- */

bool sb_session_open(sb_session *s, const sb_run_opts *o, const char *scene, const char *path, sb_err *err) {
    /* files first: a broken scene or path is refused before any GL is touched */
    sb_scene sc;
    sb_path p;
    sb_scene_opts so = {.allow_external_uris = o->allow_external_uris};
    if (!sb_scene_load(&sc, scene, &so, err)) return false;
    if (!sb_path_load(&p, path, &sc, err)) {
        sb_scene_free(&sc);
        return false;
    }
    if (!sb_session_attach(s, o, &sc, &p, err)) return false;
    base_name(scene, s->scene_name, sizeof s->scene_name);
    base_name(path, s->path_name, sizeof s->path_name);
    return true;
}

bool sb_session_attach(sb_session *s, const sb_run_opts *o, sb_scene *scene, sb_path *path, sb_err *err) {
    bool have_ctx = s->ctx.renderer[0] != 0;
    sb_context keep = s->ctx;
    memset(s, 0, sizeof *s);
    s->opts = *o;
    s->scene = *scene;
    s->path = *path;
    memset(scene, 0, sizeof *scene);
    memset(path, 0, sizeof *path);
    if (have_ctx) s->ctx = keep;
    if (!have_ctx && !sb_context_create(&s->ctx, o->backend, err)) {
        sb_session_close_scene(s);
        return false;
    }
    sb_v3 sun = s->scene.has_sun ? s->scene.sun : sb_sun_dir(135, 40);
    if (o->sun_override) sun = sb_sun_dir(o->sun_az, o->sun_el);
    if (!sb_gpu_init(&s->gpu, &s->ctx, &s->scene, o->width, o->height, sun, err)) {
        sb_session_close_scene(s);
        return false;
    }
    s->gpu.has_sun = s->scene.has_sun || o->sun_override;
    s->scratch = sb_xcalloc(s->scene.draw_count + 1, sizeof(uint32_t));
    s->tech_data = sb_xcalloc((size_t)sb_technique_count(), sizeof *s->tech_data);
    s->tech_loaded = sb_xcalloc((size_t)sb_technique_count(), sizeof *s->tech_loaded);
    s->timing = o->timing;
    if (s->timing == SB_TIMING_AUTO) s->timing = s->ctx.software ? SB_TIMING_SYNC : SB_TIMING_QUERIES;
    if (s->timing == SB_TIMING_QUERIES && !s->ctx.has_timer_query) {
        sb_log("note: %s has no timer queries; using sync timing", s->ctx.renderer);
        s->timing = SB_TIMING_SYNC;
    }
    return true;
}

void sb_session_close_scene(sb_session *s) {
    for (int i = 0; s->tech_loaded && i < sb_technique_count(); i++)
        if (s->tech_loaded[i] && sb_technique_at(i)->unload) sb_technique_at(i)->unload(s->tech_data[i]);
    free(s->tech_data);
    free(s->tech_loaded);
    s->tech_data = NULL;
    s->tech_loaded = NULL;
    if (s->ref) {
        sb_reference_free(s->ref);
        free(s->ref);
        s->ref = NULL;
    }
    free(s->scratch);
    s->scratch = NULL;
    sb_gpu_free(&s->gpu);
    sb_path_free(&s->path);
    sb_scene_free(&s->scene);
}

void sb_session_close(sb_session *s) {
    sb_session_close_scene(s);
    sb_context_destroy(&s->ctx);
    memset(s, 0, sizeof *s);
}

const sb_reference *sb_session_reference(sb_session *s, sb_err *err) {
    if (s->ref) return s->ref;
    sb_reference *r = sb_xcalloc(1, sizeof *r);
    if (!sb_reference_build(r, &s->scene, err)) {
        free(r);
        return NULL;
    }
    s->ref = r;
    return r;
}

/* What the technique's load step made for this scene (made on first use). */
static bool scene_data(sb_session *s, const sb_technique *t, void **out, sb_err *err) {
    int i = sb_technique_index(t);
    *out = NULL;
    if (!t->load || i < 0) return true;
    if (!s->tech_loaded[i]) {
        s->tech_loaded[i] = true;   /* unload frees whatever a failed load left */
        if (!t->load(&s->gpu, &s->tech_data[i], err)) return false;
    }
    *out = s->tech_data[i];
    return true;
}

/* ---- why a run cannot apply ---- */

static const char *scene_skip_reason(sb_session *s, const sb_technique *t) {
    const sb_scene *sc = &s->scene;
    int points = 0, spots = 0;
    for (uint32_t i = 0; i < sc->light_count; i++) {
        points += sc->lights[i].type == SB_LIGHT_POINT;
        spots += sc->lights[i].type == SB_LIGHT_SPOT;
    }
    if (sc->degenerate[0]) {
        snprintf(s->skip, sizeof s->skip, "the scene is degenerate: %s", sc->degenerate);
        return s->skip;
    }
    if ((t->needs & SB_NEEDS_SUN) && !sc->has_sun && points + spots && !s->opts.sun_override) {
        char lamps[96];
        if (points && spots) snprintf(lamps, sizeof lamps, "%d point and %d spot light(s)", points, spots);
        else snprintf(lamps, sizeof lamps, "%d %s light(s)", points + spots, points ? "point" : "spot");
        snprintf(s->skip, sizeof s->skip, "the scene is lit only by %s, no sun; --sun AZ,EL adds one", lamps);
        return s->skip;
    }
    if ((t->needs & SB_NEEDS_PLANE) && sc->plane_count == 0) return "the scene has no large planar receiver";
    if ((t->needs & SB_NEEDS_POINT_LIGHT) && !(points + spots)) return "the scene has no point or spot light";
    return NULL;
}

const char *sb_skip_reason(sb_session *s, const sb_technique *t, const sb_params *p) {
    const char *why = scene_skip_reason(s, t);
    if (why || !t->supported) return why;
    sb_params defaults;
    if (!p) {
        sb_params_defaults(&defaults, t);
        p = &defaults;
    }
    void *desc = sb_xcalloc(1, t->desc_size ? t->desc_size : 1);
    sb_params_bind(p, t, desc);
    sb_run_ctx rc = {.gpu = &s->gpu, .tech = t};
    sb_err e;
    bool ok = t->supported(&rc, desc, &e);
    free(desc);
    if (ok) return NULL;
    snprintf(s->skip, sizeof s->skip, "%s", e.msg);
    return s->skip;
}

/* ---- instances and frames ---- */

bool sb_instance_create(sb_instance *in, sb_session *s, const sb_run_spec *spec, int frames, sb_err *err) {
    const sb_technique *t = spec->tech;
    memset(in, 0, sizeof *in);
    in->tech = t;
    in->params = spec->params;
    in->desc = sb_xcalloc(1, t->desc_size ? t->desc_size : 1);
    sb_params_bind(&in->params, t, in->desc);
    in->rc = (sb_run_ctx){.gpu = &s->gpu, .tech = t, .frames = frames};
    bool ok = !t->supported || t->supported(&in->rc, in->desc, err);
    if (ok) ok = scene_data(s, t, &in->rc.scene_data, err);
    if (ok && (t->needs & SB_NEEDS_REFERENCE)) ok = (in->rc.reference = sb_session_reference(s, err)) != NULL;
    if (ok) {
        in->state = sb_xcalloc(1, t->state_size ? t->state_size : 1);
        ok = t->create(in->state, &in->rc, in->desc, err);
    }
    if (!ok) {
        sb_instance_destroy(in);
        while (glGetError() != GL_NO_ERROR) {}
    }
    return ok;
}

void sb_instance_destroy(sb_instance *in) {
    if (in->state) in->tech->destroy(in->state);
    free(in->state);
    free(in->desc);
    in->state = in->desc = NULL;
}

void sb_render_camera(sb_session *s, sb_instance *in, sb_frame *f, const sb_camera *cam, int seq, sb_timer *timer,
                      bool eval) {
    f->timer = timer;
    f->seq = seq;
    sb_frame_setup(f, &s->gpu, cam);
    f->scratch = s->scratch;
    f->eval = eval;
    in->tech->frame(in->state, f);
}

void sb_render_frame(sb_session *s, sb_instance *in, sb_frame *f, int i, int n, int seq, sb_timer *timer) {
    sb_camera cam = sb_path_camera(&s->path, i, n, (double)s->opts.width / s->opts.height, &s->scene);
    f->index = i;
    f->progress = sb_path_progress(i, n);
    sb_render_camera(s, in, f, &cam, seq, timer, false);
}

/* ---- run ids ---- */

void sb_run_id(uint64_t scene_hash, uint64_t path_hash, const sb_run_opts *o, const sb_run_spec *spec, char out[17]) {
    char params[1024];
    sb_params_canonical(&spec->params, params, sizeof params);
    uint64_t h = SB_FNV_SEED;
    h = sb_fnv1a(h, &scene_hash, sizeof scene_hash);
    h = sb_fnv1a(h, &path_hash, sizeof path_hash);
    h = sb_fnv1a(h, spec->tech->name, strlen(spec->tech->name) + 1);
    h = sb_fnv1a(h, params, strlen(params) + 1);
    int dims[4] = {o->frames, o->width, o->height, (int)o->backend};
    h = sb_fnv1a(h, dims, sizeof dims);
    if (o->sun_override) {
        double sun[2] = {o->sun_az, o->sun_el};
        h = sb_fnv1a(h, sun, sizeof sun);
    }
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

void sb_session_run_id(const sb_session *s, const sb_run_spec *spec, char out[17]) {
    sb_run_id(s->scene.content_hash, s->path.content_hash, &s->opts, spec, out);
}

static void progress_line(const sb_session *s, int index, int total, const char *tech, int frame, int frames,
                          double t0) {
    if (!s->opts.progress) return;
    double el = (sb_now_ms() - t0) / 1e3;
    double eta = frame > 0 ? el / frame * (frames - frame) : 0;
    fprintf(stderr, "\rrun %d/%d %-10s frame %d/%d  %.1fs  ETA %.1fs   ", index + 1, total, tech, frame, frames, el,
            eta);
    if (frame == frames) fputc('\n', stderr);
}

/* ---- the untimed evaluation pass: error against the reference, images ---- */

static bool eval_frame_wanted(const sb_run_opts *o, int pf) {
    return (o->error_every > 0 && pf % o->error_every == 0) || (o->images > 0 && pf % o->images == 0);
}

/* Re-renders the selected path frames with the evaluation targets bound and
 * reads them back: nothing here runs inside a timed frame. seq: after the
 * timed frames. */
static bool evaluate(sb_session *s, sb_instance *in, int seq, const char *out_dir, const char *run_id,
                     sb_frame_rec *recs, sb_run_info *info, sb_err *err) {
    const int n = s->opts.frames;
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/images", out_dir);
    if (s->opts.images > 0 && !sb_mkdir_p(dir, err)) return false;
    sb_eval_buf b;
    sb_eval_buf_init(&b, &s->gpu, s->opts.images > 0);
    bool ok = true;
    for (int pf = 0; ok && pf < n; pf++) {
        if (!eval_frame_wanted(&s->opts, pf)) continue;
        sb_frame f;
        sb_frame_rec *r = &recs[pf];
        ok = sb_eval_frame(s, in, pf, n, in->tech->temporal ? 2 : 0, &seq, &b, &f, &r->err, err);
        if (ok && s->opts.error_every > 0 && pf % s->opts.error_every == 0) {
            r->evaluated = true;
            info->rays += r->err.rays;
            info->ray_ms += r->err.ray_ms;
        }
        if (ok && s->opts.images > 0 && pf % s->opts.images == 0)
            ok = sb_images_write_frame(dir, run_id, pf, b.w, b.h, b.rgba, b.vis, b.ref, b.pos, b.aux, err);
    }
    sb_eval_buf_free(&b);
    return ok;
}

/* ---- one run ---- */

/* A run being measured: its frames' records and timings, its CSV file. */
typedef struct run_state {
    sb_session *s;
    sb_instance in;
    const sb_run_spec *spec;
    sb_run_info *info;
    sb_timer timer;
    sb_frame_rec *recs;
    sb_csv rows;
    sb_csv_file cf;
    int capacity, done, written, repeats;
    bool stream;                /* rows go out as their timings arrive */
    double t_run;
    sb_err err;
} run_state;

static void record_frame(run_state *r, int i, int pf, const sb_frame *f, double wall_ms) {
    const int W = r->s->opts.warmup, N = r->s->opts.frames;
    sb_frame_rec *rec = &r->recs[i];
    rec->frame = pf;
    rec->repeat = i < W ? -1 : (i - W) / N;
    rec->progress = f->progress;
    rec->counters = f->counters;
    rec->wall_ms = wall_ms;
    rec->cpu_ms = wall_ms - r->timer.wait_ms;
    r->info->frames_wall_ms += wall_ms; /* warm-up frames render too */
    r->done = i + 1;
    while (r->stream && r->written < r->done && r->timer.times[r->written].ready) {
        sb_report_frame_row(&r->rows, &r->recs[r->written], &r->timer.times[r->written], r->spec->tech->stages);
        r->written++;
    }
}

/* The warm-up frames, then the path (repeated as asked); false on failure (r->err). */
static bool timed_frames(run_state *r, int index, int total) {
    sb_session *s = r->s;
    const sb_run_opts *o = &s->opts;
    const int N = o->frames, W = o->warmup;
    bool ok = true;
    s->timed = true;
    for (int i = 0; ok && i < r->capacity; i++) {
        /* warm-up frames replay the path's first frames and are discarded */
        int pf = i < W ? i % N : (i - W) % N;
        double w0 = sb_now_ms();
        sb_timer_frame_begin(&r->timer, i);
        sb_frame f;
        memset(&f, 0, sizeof f);
        sb_render_frame(s, &r->in, &f, pf, N, i, &r->timer);
        sb_timer_frame_end(&r->timer);
        record_frame(r, i, pf, &f, sb_now_ms() - w0);
        if (r->rows.len > 65536) ok = sb_csv_file_write(&r->cf, &r->rows, &r->err);
        if (ok && o->run_timeout_s > 0 && sb_now_ms() - r->t_run > o->run_timeout_s * 1e3)
            ok = sb_fail(&r->err, "timeout: the run took longer than %g s (frame %d of %d)", o->run_timeout_s, i + 1,
                         r->capacity);
        if (i >= W) progress_line(s, index, total, r->spec->tech->name, (i - W) % N + 1, N, r->t_run);
        if (i >= W && (i - W) % N == N - 1) { /* a repetition of the path is complete */
            r->repeats++;
            if (o->target_ci > 0) {
                sb_timer_drain(&r->timer); /* between repetitions, never inside a frame */
                double ci = sb_report_gpu_ci_pct(r->timer.times + W, r->done - W, N);
                if (ci <= o->target_ci) break;
            }
        }
    }
    sb_timer_drain(&r->timer);
    s->timed = false;
    return ok;
}

/* A technique with shadow stages that drew no caster in any measured frame
 * measured nothing a user asked about: said in the run's warnings. */
static void check_shadows_drawn(run_state *r) {
    const unsigned shadow = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_VOLUMES);
    if (!(r->spec->tech->stages & shadow)) return;
    for (int i = r->s->opts.warmup; i < r->done; i++)
        if (r->recs[i].counters.shadow_triangles) return;
    sb_run_warn(r->info, "no shadow-casting triangle was drawn in any frame (nothing in view casts toward the light)");
}

/* After the timed frames: collected counters, the evaluation pass, the rest of the rows. */
static bool finish_run(run_state *r, const char *out_dir) {
    const sb_run_opts *o = &r->s->opts;
    const int W = o->warmup;
    bool ok = true;
    if (r->spec->tech->collect)
        for (int i = W; i < r->done; i++) r->spec->tech->collect(r->in.state, i, &r->recs[i].counters);
    if (o->error_every > 0 || o->images > 0)
        ok = evaluate(r->s, &r->in, r->capacity, out_dir, r->info->run_id, r->recs + W, r->info, &r->err);
    if (ok) {
        for (; r->written < r->done; r->written++)
            sb_report_frame_row(&r->rows, &r->recs[r->written], &r->timer.times[r->written], r->spec->tech->stages);
        ok = sb_csv_file_write(&r->cf, &r->rows, &r->err);
    }
    if (ok) ok = sb_gl_check(r->spec->tech->name, &r->err);
    if (ok) check_shadows_drawn(r);
    return ok;
}

static void record_outcome(sb_summary *sum, sb_run_info *info, unsigned stages, const char *why, double t_run) {
    info->status = "failed";
    info->reason = why;
    info->run_wall_s = (sb_now_ms() - t_run) / 1e3;
    sb_log("run %s (%s): failed: %s", info->run_id, info->technique, why);
    sb_summary_add_outcome(sum, info, stages, NULL, NULL, 0);
}

bool sb_run_one(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index,
                int index, int total) {
    char run_id[17], path[4096], params[1024];
    sb_session_run_id(s, spec, run_id);
    sb_params_canonical(&spec->params, params, sizeof params);
    snprintf(path, sizeof path, "%s/%s.csv", out_dir, run_id);
    const sb_run_opts *o = &s->opts;
    const unsigned stages = spec->tech->stages;
    sb_run_info info = {
        .run_id = run_id, .run_index = run_index, .scene = s->scene_name, .path = s->path_name, .technique = spec->tech->name,
        .params = params, .backend = sb_backend_name(o->backend), .renderer = s->ctx.renderer,
        .timing = sb_timing_name(s->timing), .status = "ok", .reason = "", .frames = o->frames,
        .warmup = o->warmup, .width = o->width, .height = o->height, .target_ci = o->target_ci,
        .scene_triangles = sb_scene_triangles(&s->scene), .load_ms = s->scene.load_ms,
    };
    run_state r = {.s = s, .spec = spec, .info = &info, .t_run = sb_now_ms(), .written = o->warmup};
    const char *skip = sb_skip_reason(s, spec->tech, &spec->params);
    if (skip) {
        info.status = "skipped";
        info.reason = skip;
        sb_summary_add_outcome(sum, &info, stages, NULL, NULL, 0);
        return true;
    }
    r.capacity = o->warmup + o->frames * (o->target_ci > 0 ? o->max_repeat : o->repeat);
    if (!sb_instance_create(&r.in, s, spec, r.capacity, &r.err)) {
        record_outcome(sum, &info, stages, r.err.msg, r.t_run);
        return false;
    }
    sb_timer_init(&r.timer, s->timing, o->ring, r.capacity);
    r.recs = sb_xcalloc((size_t)r.capacity, sizeof *r.recs);
    /* rows stream out as their timings arrive, unless something is only known
       after the timed frames (GPU-side counters, error evaluation) */
    r.stream = !spec->tech->collect && o->error_every == 0;
    bool ok = sb_csv_file_open(&r.cf, path, &r.err);
    if (ok) {
        sb_report_frame_header(&r.rows);
        ok = sb_csv_file_write(&r.cf, &r.rows, &r.err);
    }
    ok = ok && timed_frames(&r, index, total) && finish_run(&r, out_dir);
    if (ok) ok = sb_csv_file_commit(&r.cf, &r.err);
    else sb_csv_file_abort(&r.cf);
    sb_instance_destroy(&r.in);
    info.run_wall_s = (sb_now_ms() - r.t_run) / 1e3;
    info.repeats = r.repeats;
    if (!ok) {
        sb_log("run %s (%s): failed: %s", run_id, spec->tech->name, r.err.msg);
        info.status = "failed";
        info.reason = r.err.msg;
    }
    sb_summary_add_outcome(sum, &info, stages, ok ? r.recs + o->warmup : NULL, r.timer.times + o->warmup,
                           r.done - o->warmup);
    sb_csv_free(&r.rows);
    free(r.recs);
    sb_timer_free(&r.timer);
    return ok;
}
