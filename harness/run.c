/* run.c - sessions, technique instances, and the timed frame loop. */
#include "run.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "image.h"
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
}

static void base_name(const char *path, char *out, size_t len) {
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    snprintf(out, len, "%s", b);
    char *dot = strrchr(out, '.');
    if (dot && dot != out && !strchr(dot, '#')) *dot = 0;
}

bool sb_session_open(sb_session *s, const sb_run_opts *o, const char *scene, const char *path, sb_err *err) {
    bool have_ctx = s->ctx.renderer[0] != 0;
    sb_context keep = s->ctx;
    memset(s, 0, sizeof *s);
    s->opts = *o;
    if (have_ctx) s->ctx = keep;
    else if (!sb_context_create(&s->ctx, o->backend, err)) return false;
    if (!sb_scene_load(&s->scene, scene, err)) return false;
    if (!sb_path_load(&s->path, path, &s->scene, err)) {
        sb_scene_free(&s->scene);
        return false;
    }
    base_name(scene, s->scene_name, sizeof s->scene_name);
    base_name(path, s->path_name, sizeof s->path_name);
    sb_v3 sun = s->scene.has_sun ? s->scene.sun : sb_sun_dir(135, 40);
    if (o->sun_override) sun = sb_sun_dir(o->sun_az, o->sun_el);
    if (!sb_gpu_init(&s->gpu, &s->ctx, &s->scene, o->width, o->height, sun, err)) {
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

void sb_session_close(sb_session *s) {
    sb_gpu_free(&s->gpu);
    sb_path_free(&s->path);
    sb_scene_free(&s->scene);
    sb_context_destroy(&s->ctx);
    memset(s, 0, sizeof *s);
}

const char *sb_skip_reason(const sb_session *s, const sb_technique *t) {
    if (t->needs & SB_NEEDS_POINT_LIGHT) {
        bool any = false;
        for (uint32_t i = 0; i < s->scene.light_count; i++) any |= s->scene.lights[i].type != SB_LIGHT_DIRECTIONAL;
        if (!any) return "the scene has no point or spot light";
    }
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

void sb_run_id(const sb_session *s, const sb_run_spec *spec, char out[17]) {
    char params[1024];
    sb_params_canonical(&spec->params, params, sizeof params);
    uint64_t h = SB_FNV_SEED;
    h = sb_fnv1a(h, &s->scene.content_hash, sizeof s->scene.content_hash);
    h = sb_fnv1a(h, &s->path.content_hash, sizeof s->path.content_hash);
    h = sb_fnv1a(h, spec->tech->name, strlen(spec->tech->name) + 1);
    h = sb_fnv1a(h, params, strlen(params) + 1);
    int dims[4] = {s->opts.frames, s->opts.width, s->opts.height, (int)s->opts.backend};
    h = sb_fnv1a(h, dims, sizeof dims);
    if (s->opts.sun_override) {
        double sun[2] = {s->opts.sun_az, s->opts.sun_el};
        h = sb_fnv1a(h, sun, sizeof sun);
    }
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

/* ---- summary ---- */

#define N_SUMMARY_STAGES (SB_STAGE_COUNT + 3) /* stages, gpu, cpu, wall */
static const char *summary_stage_name(int k) {
    static const char *extra[] = {"gpu", "cpu", "wall"};
    return k < SB_STAGE_COUNT ? sb_stage_names[k] : extra[k - SB_STAGE_COUNT];
}

static void summary_header(sb_csv *c) {
    const char *cols[] = {"run_id", "scene", "path", "technique", "params", "backend", "renderer", "timing",
                          "frames", "warmup", "width", "height", "status", "reason", "stalls", "scene_triangles",
                          "load_ms", "run_wall_s", "harness_share", "draw_calls_mean", "shadow_draw_calls_mean",
                          "shadow_triangles_mean", "cascades_rendered_mean", "cascades_skipped_mean"};
    for (size_t i = 0; i < SB_COUNT(cols); i++) sb_csv_str(c, cols[i]);
    const char *st[] = {"mean", "median", "p95", "p99", "std", "ci95"};
    for (int k = 0; k < N_SUMMARY_STAGES; k++)
        for (size_t j = 0; j < SB_COUNT(st); j++) {
            char name[64];
            snprintf(name, sizeof name, "%s_ms_%s", summary_stage_name(k), st[j]);
            sb_csv_str(c, name);
        }
    sb_csv_end_row(c);
}

void sb_summary_open(sb_summary *sum, const char *path) {
    memset(sum, 0, sizeof *sum);
    sum->path = sb_strdup(path);
    summary_header(&sum->rows);
}

bool sb_summary_flush(sb_summary *sum, sb_err *err) {
    return sb_write_file_atomic(sum->path, sum->rows.buf, sum->rows.len, err);
}

void sb_summary_free(sb_summary *sum) {
    free(sum->path);
    sb_csv_free(&sum->rows);
    memset(sum, 0, sizeof *sum);
}

/* ---- per-frame CSV ---- */

typedef struct frame_rec {
    double progress;
    sb_counters counters;
    double cpu_ms, wall_ms;
} frame_rec;

static void frame_header(sb_csv *c) {
    const char *cols[] = {"frame", "progress", "draw_calls", "shadow_draw_calls", "triangles", "shadow_triangles",
                          "cascades_rendered", "cascades_skipped"};
    for (size_t i = 0; i < SB_COUNT(cols); i++) sb_csv_str(c, cols[i]);
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        char name[32];
        snprintf(name, sizeof name, "%s_ms", sb_stage_names[s]);
        sb_csv_str(c, name);
    }
    sb_csv_str(c, "gpu_ms");
    sb_csv_str(c, "cpu_ms");
    sb_csv_str(c, "wall_ms");
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        if (s == SB_STAGE_MINMAX || s == SB_STAGE_RAYS) continue; /* stages that draw nothing */
        char name[40];
        snprintf(name, sizeof name, "%s_draw_calls", sb_stage_names[s]);
        sb_csv_str(c, name);
    }
    for (int k = 0; k < SB_MAX_CASCADES; k++) {
        char name[16];
        snprintf(name, sizeof name, "split_%d", k + 1);
        sb_csv_str(c, name);
    }
    sb_csv_end_row(c);
}

static double frame_gpu_ms(const sb_stage_times *t) {
    double sum = 0;
    for (int s = 0; s < SB_STAGE_COUNT; s++)
        if (t->mask & SB_STAGE_BIT(s)) sum += t->ms[s];
    return sum;
}

static void frame_row(sb_csv *c, int frame, const frame_rec *r, const sb_stage_times *t, unsigned stages) {
    sb_csv_int(c, frame);
    sb_csv_num(c, r->progress);
    sb_csv_int(c, r->counters.draw_calls);
    sb_csv_int(c, r->counters.shadow_draw_calls);
    sb_csv_int(c, (long long)r->counters.triangles);
    sb_csv_int(c, (long long)r->counters.shadow_triangles);
    if (stages & SB_STAGE_BIT(SB_STAGE_CASCADE)) {
        sb_csv_int(c, r->counters.cascades_rendered);
        sb_csv_int(c, r->counters.cascades_skipped);
    } else {
        sb_csv_empty(c);
        sb_csv_empty(c);
    }
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        if ((stages & SB_STAGE_BIT(s)) && (t->mask & SB_STAGE_BIT(s))) sb_csv_num(c, t->ms[s]);
        else sb_csv_empty(c);
    }
    sb_csv_num(c, frame_gpu_ms(t));
    sb_csv_num(c, r->cpu_ms);
    sb_csv_num(c, r->wall_ms);
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        if (s == SB_STAGE_MINMAX || s == SB_STAGE_RAYS) continue;
        if (stages & SB_STAGE_BIT(s)) sb_csv_int(c, r->counters.stage_draw_calls[s]);
        else sb_csv_empty(c);
    }
    for (int k = 0; k < SB_MAX_CASCADES; k++) {
        if (k < r->counters.split_count) sb_csv_num(c, r->counters.splits[k]);
        else sb_csv_empty(c);
    }
    sb_csv_end_row(c);
}

static void summary_row(sb_summary *sum, const sb_session *s, const sb_run_spec *spec, const char *run_id,
                        const char *status, const char *reason, const sb_timer *t, const frame_rec *recs,
                        int first, int n, double run_wall_s, double frames_wall_ms) {
    sb_csv *c = &sum->rows;
    char params[1024];
    sb_params_canonical(&spec->params, params, sizeof params);
    sb_csv_str(c, run_id);
    sb_csv_str(c, s->scene_name);
    sb_csv_str(c, s->path_name);
    sb_csv_str(c, spec->tech->name);
    sb_csv_str(c, params);
    sb_csv_str(c, sb_backend_name(s->opts.backend));
    sb_csv_str(c, s->ctx.renderer);
    sb_csv_str(c, sb_timing_name(s->timing));
    sb_csv_int(c, s->opts.frames);
    sb_csv_int(c, s->opts.warmup);
    sb_csv_int(c, s->opts.width);
    sb_csv_int(c, s->opts.height);
    sb_csv_str(c, status);
    sb_csv_str(c, reason);
    sb_csv_int(c, t ? (long long)t->stalls : 0);
    sb_csv_int(c, (long long)sb_scene_triangles(&s->scene));
    sb_csv_num(c, s->scene.load_ms);
    sb_csv_num(c, run_wall_s);
    sb_csv_num(c, run_wall_s > 0 && t ? 1.0 - frames_wall_ms / (run_wall_s * 1e3) : NAN);
    double *v = malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    for (int field = 0; field < 5; field++) {
        for (int i = 0; i < n; i++) {
            const sb_counters *k = &recs[first + i].counters;
            v[i] = field == 0 ? k->draw_calls : field == 1 ? k->shadow_draw_calls : field == 2 ? (double)k->shadow_triangles
                 : field == 3 ? k->cascades_rendered : k->cascades_skipped;
        }
        bool has_cascades = spec->tech->stages & SB_STAGE_BIT(SB_STAGE_CASCADE);
        if (field >= 3 && !has_cascades) sb_csv_empty(c);
        else sb_csv_num(c, t && n ? sb_stats_compute(v, n).mean : NAN);
    }
    for (int k = 0; k < N_SUMMARY_STAGES; k++) {
        for (int i = 0; i < n; i++) {
            const sb_stage_times *st = t ? &t->times[first + i] : NULL;
            const frame_rec *r = &recs[first + i];
            if (!st) v[i] = NAN;
            else if (k < SB_STAGE_COUNT)
                v[i] = (spec->tech->stages & SB_STAGE_BIT(k)) && (st->mask & SB_STAGE_BIT(k)) ? st->ms[k] : NAN;
            else if (k == SB_STAGE_COUNT) v[i] = frame_gpu_ms(st);
            else if (k == SB_STAGE_COUNT + 1) v[i] = r->cpu_ms;
            else v[i] = r->wall_ms;
        }
        sb_stats st = sb_stats_compute(v, t ? n : 0);
        sb_csv_num(c, st.mean);
        sb_csv_num(c, st.median);
        sb_csv_num(c, st.p95);
        sb_csv_num(c, st.p99);
        sb_csv_num(c, st.std);
        sb_csv_num(c, st.ci95);
    }
    free(v);
    sb_csv_end_row(c);
    sum->count++;
    if (strcmp(status, "failed") == 0) sum->failed++;
    if (strcmp(status, "skipped") == 0) sum->skipped++;
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

/* Untimed pass over the same frames: readbacks never touch the timed loop. */
static bool write_images(sb_session *s, sb_instance *in, const char *out_dir, const char *run_id, sb_err *err) {
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/images", out_dir);
    if (!sb_mkdir_p(dir, err)) return false;
    const int w = s->gpu.width, h = s->gpu.height, n = s->opts.frames;
    unsigned char *rgba = malloc((size_t)w * h * 4), *vis = malloc((size_t)w * h);
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 1, n);
    bool ok = true;
    for (int i = 0; ok && i < n; i += s->opts.images) {
        sb_frame f;
        memset(&f, 0, sizeof f);
        sb_timer_frame_begin(&timer, i);
        sb_render_frame(s, in, &f, i, n, i, &timer);
        sb_gpu_readback(&s->gpu, NULL, vis, rgba);
        char path[4400];
        snprintf(path, sizeof path, "%s/%s_f%04d_color.png", dir, run_id, i);
        ok = sb_image_write_u8(path, w, h, 4, rgba, err);
        snprintf(path, sizeof path, "%s/%s_f%04d_vis.png", dir, run_id, i);
        if (ok) ok = sb_image_write_u8(path, w, h, 1, vis, err);
    }
    sb_timer_free(&timer);
    free(rgba);
    free(vis);
    return ok;
}

bool sb_run_one(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int index,
                int total) {
    char run_id[17], path[4096];
    sb_run_id(s, spec, run_id);
    snprintf(path, sizeof path, "%s/%s.csv", out_dir, run_id);
    double t_run = sb_now_ms();
    const char *skip = sb_skip_reason(s, spec->tech);
    if (skip) {
        summary_row(sum, s, spec, run_id, "skipped", skip, NULL, NULL, 0, 0, 0, 0);
        return true;
    }
    sb_err err = {{0}};
    sb_instance in;
    s->gpu.run_frames = s->opts.frames + s->opts.warmup;
    if (!sb_instance_create(&in, s, spec, &err)) {
        sb_log("run %s (%s): failed: %s", run_id, spec->tech->name, err.msg);
        summary_row(sum, s, spec, run_id, "failed", err.msg, NULL, NULL, 0, 0, (sb_now_ms() - t_run) / 1e3, 0);
        return false;
    }
    const int N = s->opts.frames, W = s->opts.warmup, total_frames = N + W;
    sb_timer timer;
    sb_timer_init(&timer, s->timing, s->opts.ring, total_frames);
    frame_rec *recs = calloc((size_t)total_frames, sizeof *recs);
    sb_csv rows = {0};
    sb_csv_file cf;
    bool ok = sb_csv_file_open(&cf, path, &err);
    if (ok) {
        frame_header(&rows);
        ok = sb_csv_file_write(&cf, &rows, &err);
    }
    int written = W; /* next measured frame to write */
    double frames_wall = 0;
    for (int i = 0; ok && i < total_frames; i++) {
        /* warm-up frames replay the path's first frames and are discarded */
        int pf = i < W ? i % N : i - W;
        double w0 = sb_now_ms();
        sb_timer_frame_begin(&timer, i);
        sb_frame f;
        memset(&f, 0, sizeof f);
        sb_render_frame(s, &in, &f, pf, N, i, &timer);
        if (timer.mode == SB_TIMING_QUERIES) glFlush();
        double w1 = sb_now_ms();
        recs[i].progress = f.progress;
        recs[i].counters = f.counters;
        recs[i].wall_ms = w1 - w0;
        recs[i].cpu_ms = recs[i].wall_ms - timer.wait_ms;
        frames_wall += recs[i].wall_ms;
        /* techniques with counters known only after the run write their rows at the end */
        while (!spec->tech->collect && written < total_frames && timer.times[written].ready) {
            frame_row(&rows, written - W, &recs[written], &timer.times[written], spec->tech->stages);
            written++;
        }
        if (rows.len > 65536) ok = sb_csv_file_write(&cf, &rows, &err);
        if (i >= W) progress_line(s, index, total, spec->tech->name, i - W + 1, N, t_run);
    }
    sb_timer_drain(&timer);
    if (ok && spec->tech->collect)
        for (int i = W; i < total_frames; i++) spec->tech->collect(in.state, i, &recs[i].counters);
    if (ok) {
        for (; written < total_frames; written++)
            frame_row(&rows, written - W, &recs[written], &timer.times[written], spec->tech->stages);
        ok = sb_csv_file_write(&cf, &rows, &err);
    }
    if (ok) ok = sb_gl_check(spec->tech->name, &err);
    if (ok && s->opts.images > 0) ok = write_images(s, &in, out_dir, run_id, &err);
    if (ok) ok = sb_csv_file_commit(&cf, &err);
    else sb_csv_file_abort(&cf);
    sb_instance_destroy(&in, s);
    double run_wall_s = (sb_now_ms() - t_run) / 1e3;
    if (ok) {
        summary_row(sum, s, spec, run_id, "ok", "", &timer, recs, W, N, run_wall_s, frames_wall);
    } else {
        sb_log("run %s (%s): failed: %s", run_id, spec->tech->name, err.msg);
        summary_row(sum, s, spec, run_id, "failed", err.msg, NULL, NULL, 0, 0, run_wall_s, 0);
    }
    sb_csv_free(&rows);
    free(recs);
    sb_timer_free(&timer);
    return ok;
}
