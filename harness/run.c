/* run.c - sessions, technique instances, and the timed frame loop. */
#include "run.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "image.h"
#include "report.h"
#include "stats.h"

bool sb_timed_frames_active;

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
    o->threads = cpus > 0 ? (int)cpus : 1;
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
        if (!sb_parse_int(v, &n) || n < 1 || n > 16) return sb_fail(err, "--threads %s: expected 1..16", v), -1;
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
        sb_path_free(&s->path);
        sb_scene_free(&s->scene);
        return false;
    }
    sb_v3 sun = s->scene.has_sun ? s->scene.sun : sb_sun_dir(135, 40);
    if (o->sun_override) sun = sb_sun_dir(o->sun_az, o->sun_el);
    bool init_ok = sb_gpu_init(&s->gpu, &s->ctx, &s->scene, o->width, o->height, sun, err);
    s->gpu.has_sun = s->scene.has_sun || o->sun_override;
    if (!init_ok) {
        sb_path_free(&s->path);
        sb_scene_free(&s->scene);
        return false;
    }
    s->timing = o->timing;
    if (s->timing == SB_TIMING_AUTO) s->timing = s->ctx.software ? SB_TIMING_SYNC : SB_TIMING_QUERIES;
    if (s->timing == SB_TIMING_QUERIES && !s->ctx.has_timer_query) {
        sb_log("note: %s has no timer queries; using sync timing", s->ctx.renderer);
        s->timing = SB_TIMING_SYNC;
    }
    return true;
}

void sb_session_close_scene(sb_session *s) {
    sb_gpu_free(&s->gpu);
    sb_path_free(&s->path);
    sb_scene_free(&s->scene);
}

void sb_session_close(sb_session *s) {
    sb_gpu_free(&s->gpu);
    sb_path_free(&s->path);
    sb_scene_free(&s->scene);
    sb_context_destroy(&s->ctx);
    memset(s, 0, sizeof *s);
}

const char *sb_skip_reason(sb_session *s, const sb_technique *t) {
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

bool sb_instance_create(sb_instance *in, sb_session *s, const sb_run_spec *spec, sb_err *err) {
    memset(in, 0, sizeof *in);
    in->tech = spec->tech;
    in->params = spec->params;
    in->state = calloc(1, spec->tech->state_size ? spec->tech->state_size : 1);
    if (!spec->tech->create(in->state, &s->gpu, &in->params, err)) {
        spec->tech->destroy(in->state, &s->gpu);
        free(in->state);
        in->state = NULL;
        while (glGetError() != GL_NO_ERROR) {}
        return false;
    }
    return true;
}

void sb_instance_destroy(sb_instance *in, sb_session *s) {
    if (in->state) in->tech->destroy(in->state, &s->gpu);
    free(in->state);
    in->state = NULL;
}

void sb_render_camera(sb_session *s, sb_instance *in, sb_frame *f, const sb_camera *cam, int seq, sb_timer *timer) {
    f->timer = timer;
    f->seq = seq;
    sb_frame_setup(f, &s->gpu, cam);
    in->tech->frame(in->state, f);
}

void sb_render_frame(sb_session *s, sb_instance *in, sb_frame *f, int i, int n, int seq, sb_timer *timer) {
    sb_camera cam = sb_path_camera(&s->path, i, n, (double)s->opts.width / s->opts.height, &s->scene);
    f->index = i;
    f->progress = sb_path_progress(i, n);
    sb_render_camera(s, in, f, &cam, seq, timer);
}

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
 * reads them back: nothing here runs inside a timed frame. */
static bool evaluate(sb_session *s, sb_instance *in, const char *out_dir, const char *run_id, sb_frame_rec *recs,
                     sb_run_info *info, sb_err *err) {
    const int w = s->gpu.width, h = s->gpu.height, n = s->opts.frames, np = w * h;
    sb_reference *ref = sb_gpu_reference(&s->gpu, err);
    if (!ref) return false;
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/images", out_dir);
    if (s->opts.images > 0 && !sb_mkdir_p(dir, err)) return false;
    unsigned char *rgba = malloc((size_t)np * 4), *vis = malloc((size_t)np), *refvis = malloc((size_t)np);
    float *pos = malloc(sizeof(float) * 4 * (size_t)np), *aux = malloc(sizeof(float) * 4 * (size_t)np);
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 1, 3);
    bool ok = true;
    int seq = s->gpu.run_frames;   /* after the timed frames */
    for (int pf = 0; ok && pf < n; pf++) {
        if (!eval_frame_wanted(&s->opts, pf)) continue;
        /* a temporal technique's frame depends on the frames before it: replay two */
        for (int k = in->tech->temporal ? 2 : 0; k >= 0; k--) {
            if (pf - k < 0) continue;
            sb_frame f;
            memset(&f, 0, sizeof f);
            s->gpu.eval = k == 0;
            sb_timer_frame_begin(&timer, 0);
            sb_render_frame(s, in, &f, pf - k, n, seq++, &timer);
        }
        s->gpu.eval = false;
        sb_gpu_readback(&s->gpu, NULL, vis, rgba);
        sb_gpu_readback_eval(&s->gpu, pos, aux);
        sb_frame_rec *r = &recs[pf];
        sb_camera cam = sb_path_camera(&s->path, pf, n, (double)w / h, &s->scene);
        sb_evaluate_frame(ref, s->gpu.shade_light, sb_v3_sub(cam.pos, s->scene.origin), w, h, pos, aux, vis, refvis, &r->err,
                          s->opts.threads);
        if (s->opts.error_every > 0 && pf % s->opts.error_every == 0) {
            r->evaluated = true;
            info->rays += r->err.rays;
            info->ray_ms += r->err.ray_ms;
        }
        if (s->opts.images > 0 && pf % s->opts.images == 0)
            ok = sb_images_write_frame(dir, run_id, pf, w, h, rgba, vis, refvis, pos, aux, err);
    }
    if (ok) ok = sb_gl_check("evaluation pass", err);
    sb_timer_free(&timer);
    free(rgba);
    free(vis);
    free(refvis);
    free(pos);
    free(aux);
    return ok;
}

/* ---- one run ---- */

bool sb_run_one(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index,
                int index, int total) {
    char run_id[17], path[4096], params[1024];
    sb_session_run_id(s, spec, run_id);
    sb_params_canonical(&spec->params, params, sizeof params);
    snprintf(path, sizeof path, "%s/%s.csv", out_dir, run_id);
    const sb_run_opts *o = &s->opts;
    sb_run_info info = {
        .run_id = run_id, .run_index = run_index, .scene = s->scene_name, .path = s->path_name, .technique = spec->tech->name,
        .params = params, .backend = sb_backend_name(o->backend), .renderer = s->ctx.renderer,
        .timing = sb_timing_name(s->timing), .status = "ok", .reason = "", .frames = o->frames,
        .warmup = o->warmup, .width = o->width, .height = o->height, .target_ci = o->target_ci,
        .scene_triangles = sb_scene_triangles(&s->scene), .load_ms = s->scene.load_ms,
    };
    const unsigned stages = spec->tech->stages;
    double t_run = sb_now_ms();
    const char *skip = sb_skip_reason(s, spec->tech);
    if (skip) {
        info.status = "skipped";
        info.reason = skip;
        sb_summary_add_outcome(sum, &info, stages, NULL, NULL, 0);
        return true;
    }
    const int N = o->frames, W = o->warmup;
    const int max_repeat = o->target_ci > 0 ? o->max_repeat : o->repeat;
    const int capacity = W + N * max_repeat;
    sb_err err = {{0}};
    sb_instance in;
    s->gpu.run_frames = capacity;
    if (!sb_instance_create(&in, s, spec, &err)) {
        sb_log("run %s (%s): failed: %s", run_id, spec->tech->name, err.msg);
        info.status = "failed";
        info.reason = err.msg;
        info.run_wall_s = (sb_now_ms() - t_run) / 1e3;
        sb_summary_add_outcome(sum, &info, stages, NULL, NULL, 0);
        return false;
    }
    sb_timer timer;
    sb_timer_init(&timer, s->timing, o->ring, capacity);
    sb_frame_rec *recs = calloc((size_t)capacity, sizeof *recs);
    sb_csv rows = {0};
    sb_csv_file cf;
    bool ok = sb_csv_file_open(&cf, path, &err);
    if (ok) {
        sb_report_frame_header(&rows);
        ok = sb_csv_file_write(&cf, &rows, &err);
    }
    /* rows stream out as their timings arrive, unless something is only known
       after the timed frames (GPU-side counters, error evaluation) */
    const bool stream = !spec->tech->collect && o->error_every == 0;
    int written = W, done = 0, repeats = 0;
    sb_timed_frames_active = true;
    for (int i = 0; ok && i < capacity; i++) {
        /* warm-up frames replay the path's first frames and are discarded */
        int pf = i < W ? i % N : (i - W) % N;
        double w0 = sb_now_ms();
        sb_timer_frame_begin(&timer, i);
        sb_frame f;
        memset(&f, 0, sizeof f);
        sb_render_frame(s, &in, &f, pf, N, i, &timer);
        if (timer.mode == SB_TIMING_QUERIES) glFlush();
        double w1 = sb_now_ms();
        sb_frame_rec *r = &recs[i];
        r->frame = pf;
        r->repeat = i < W ? -1 : (i - W) / N;
        r->progress = f.progress;
        r->counters = f.counters;
        r->wall_ms = w1 - w0;
        r->cpu_ms = r->wall_ms - timer.wait_ms;
        info.frames_wall_ms += r->wall_ms; /* warm-up frames render too */
        done = i + 1;
        while (stream && written < done && timer.times[written].ready) {
            sb_report_frame_row(&rows, &recs[written], &timer.times[written], stages);
            written++;
        }
        if (rows.len > 65536) ok = sb_csv_file_write(&cf, &rows, &err);
        if (ok && o->run_timeout_s > 0 && sb_now_ms() - t_run > o->run_timeout_s * 1e3)
            ok = sb_fail(&err, "timeout: the run took longer than %g s (frame %d of %d)", o->run_timeout_s, i + 1,
                         capacity);
        if (i >= W) progress_line(s, index, total, spec->tech->name, (i - W) % N + 1, N, t_run);
        if (i >= W && (i - W) % N == N - 1) { /* a repetition of the path is complete */
            repeats++;
            if (o->target_ci > 0) {
                sb_timer_drain(&timer); /* between repetitions, never inside a frame */
                double ci = sb_report_gpu_ci_pct(timer.times + W, done - W, N);
                if (ci <= o->target_ci) break;
            }
        }
    }
    sb_timer_drain(&timer);
    sb_timed_frames_active = false;
    const int measured = done - W;
    if (ok && spec->tech->collect)
        for (int i = W; i < done; i++) spec->tech->collect(in.state, i, &recs[i].counters);
    if (ok && (o->error_every > 0 || o->images > 0)) ok = evaluate(s, &in, out_dir, run_id, recs + W, &info, &err);
    if (ok) {
        for (; written < done; written++) sb_report_frame_row(&rows, &recs[written], &timer.times[written], stages);
        ok = sb_csv_file_write(&cf, &rows, &err);
    }
    if (ok) ok = sb_gl_check(spec->tech->name, &err);
    if (ok) ok = sb_csv_file_commit(&cf, &err);
    else sb_csv_file_abort(&cf);
    sb_instance_destroy(&in, s);
    info.run_wall_s = (sb_now_ms() - t_run) / 1e3;
    info.repeats = repeats;
    info.stalls = timer.stalls;
    if (!ok) {
        sb_log("run %s (%s): failed: %s", run_id, spec->tech->name, err.msg);
        info.status = "failed";
        info.reason = err.msg;
    }
    sb_summary_add_outcome(sum, &info, stages, ok ? recs + W : NULL, timer.times + W, measured);
    sb_csv_free(&rows);
    free(recs);
    sb_timer_free(&timer);
    return ok;
}
