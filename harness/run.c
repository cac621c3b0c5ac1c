/* run.c - sessions, technique instances, and the timed frame loop. */
#include "run.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "autobias.h"
#include "eval.h"
#include "image.h"
#include "reference.h"
#include "report.h"
#include "stability.h"
#include "stats.h"

void sb_run_opts_defaults(sb_run_opts *o) {
    memset(o, 0, sizeof *o);
    o->backend = SB_BACKEND_EGL;
    o->timing = SB_TIMING_AUTO;
    o->ring = 3;
    o->frames = 60;
    o->warmup = -1;
    o->width = 1280;
    o->height = 720;
    o->error_every = 10;
    o->repeat = 1;
    o->max_repeat = 10;
    o->overlap = -1;
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
        if (!strcmp(v, "auto")) o->warmup = -1;
        else if (!sb_parse_int(v, &n) || n < 0 || n > 10000)
            return sb_fail(err, "--warmup %s: expected auto or 0..10000", v), -1;
        else o->warmup = (int)n;
    } else if (!strcmp(a, "--clocks")) {
        if (!sb_clocks_parse(v, &o->clocks)) return sb_fail(err, "--clocks %s: expected auto, lock or free", v), -1;
    } else if (!strcmp(a, "--order")) {
        if (!strcmp(v, "matrix")) o->order = SB_ORDER_MATRIX;
        else if (!strcmp(v, "interleave")) o->order = SB_ORDER_INTERLEAVE;
        else if (!strcmp(v, "shuffle")) o->order = SB_ORDER_SHUFFLE;
        else return sb_fail(err, "--order %s: expected matrix, interleave or shuffle", v), -1;
    } else if (!strcmp(a, "--seed")) {
        unsigned long long u;
        char extra;
        if (sscanf(v, "%llu%c", &u, &extra) != 1 || u == 0 || v[0] == '-')
            return sb_fail(err, "--seed %s: expected an integer >= 1", v), -1;
        o->seed = u;
    } else if (!strcmp(a, "--blend-casters")) {
        if (!sb_blend_policy_parse(v, &o->blend))
            return sb_fail(err, "--blend-casters %s: expected mask, opaque or none", v), -1;
    } else if (!strcmp(a, "--pose")) {
        if (!sb_parse_double(v, &o->pose_time) || !isfinite(o->pose_time))
            return sb_fail(err, "--pose %s: expected a time in seconds", v), -1;
        o->pose = true;
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
        if (n > 0 && !sb_images_available())
            return sb_fail(err, "--images %s: %s", v, sb_images_unavailable_reason()), -1;
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
    } else if (!strcmp(a, "--overlap")) {
        if (!strcmp(v, "auto")) o->overlap = -1;
        else if (!strcmp(v, "on") || !strcmp(v, "off")) o->overlap = !strcmp(v, "on");
        else return sb_fail(err, "--overlap %s: expected auto, on or off", v), -1;
    } else if (!strcmp(a, "--run-timeout")) {
        if (!sb_parse_double(v, &o->run_timeout_s) || o->run_timeout_s < 0)
            return sb_fail(err, "--run-timeout %s: expected seconds >= 0", v), -1;
    } else {
        return 0;
    }
    return 1;
}

sb_scene_opts sb_run_scene_opts(const sb_run_opts *o) {
    return (sb_scene_opts){.allow_external_uris = o->allow_external_uris, .blend = o->blend, .pose = o->pose,
                           .pose_time = o->pose_time};
}

void sb_run_opts_finish(sb_run_opts *o) {
    if (o->order != SB_ORDER_SHUFFLE || o->seed) return;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    uint64_t x = (uint64_t)ts.tv_sec * 1000000007u ^ (uint64_t)ts.tv_nsec ^ (uint64_t)getpid() << 32;
    o->seed = (x % 1000000000u) + 1; /* short enough to type back with --seed */
}

const char *sb_order_name(sb_order o) {
    return o == SB_ORDER_INTERLEAVE ? "interleave" : o == SB_ORDER_SHUFFLE ? "shuffle" : "matrix";
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
    sb_scene_opts so = sb_run_scene_opts(o);
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

bool sb_session_clocks(sb_session *s, const sb_run_opts *o, sb_err *err) {
    if (s->clocks) return true;
    s->clocks = sb_clocks_open(&s->ctx, "/sys");
    return sb_clocks_apply(s->clocks, o->clocks, s->clocks_mode, sizeof s->clocks_mode, err);
}

bool sb_session_attach(sb_session *s, const sb_run_opts *o, sb_scene *scene, sb_path *path, sb_err *err) {
    bool have_ctx = s->ctx.renderer[0] != 0;
    sb_context keep = s->ctx;
    sb_clocks *clocks = s->clocks;
    char mode[sizeof s->clocks_mode];
    memcpy(mode, s->clocks_mode, sizeof mode);
    memset(s, 0, sizeof *s);
    s->opts = *o;
    s->scene = *scene;
    s->path = *path;
    memset(scene, 0, sizeof *scene);
    memset(path, 0, sizeof *path);
    if (have_ctx) {
        s->ctx = keep;
        s->clocks = clocks;
        memcpy(s->clocks_mode, mode, sizeof mode);
    }
    if ((!have_ctx && !sb_context_create(&s->ctx, o->backend, err)) || !sb_session_clocks(s, o, err)) {
        sb_session_close_scene(s);
        return false;
    }
    sb_v3 sun = s->scene.has_sun ? s->scene.sun : sb_sun_dir(135, 40);
    if (o->sun_override) sun = sb_sun_dir(o->sun_az, o->sun_el);
    double t0 = sb_now_ms();
    if (!sb_gpu_init(&s->gpu, &s->ctx, &s->scene, o->width, o->height, sun, err)) {
        sb_session_close_scene(s);
        return false;
    }
    glFinish();
    s->gpu_upload_ms = sb_now_ms() - t0;
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
    if (!sb_calib_init(&s->calib, &s->ctx, s->timing == SB_TIMING_QUERIES, err)) {
        sb_session_close_scene(s);
        return false;
    }
    return true;
}

/* The file of the scene's kept answers and the tag they are kept under. */
static bool ref_store_file(const sb_session *s, char *out, size_t len, uint64_t *tag) {
    if (!s->ref_store[0]) return false;
    uint64_t v[3] = {s->scene.content_hash, sb_binary_identity(), 1 /* format */};
    *tag = sb_fnv1a(SB_FNV_SEED, v, sizeof v);
    return (size_t)snprintf(out, len, "%s/%016llx.ref", s->ref_store, (unsigned long long)*tag) < len;
}

void sb_session_keep_reference(sb_session *s, const char *results_dir) {
    const char *slash = strrchr(results_dir, '/');
    int n = slash ? (int)(slash - results_dir) : 0;
    snprintf(s->ref_store, sizeof s->ref_store, "%.*s%s.reference", n, results_dir, slash ? "/" : "");
}

void sb_session_close_scene(sb_session *s) {
    char file[4200];
    uint64_t tag;
    if (s->ref_cache) sb_ref_background_stop(s->ref_cache); /* before the reference it casts with goes */
    if (sb_ref_cache_dirty(s->ref_cache) && ref_store_file(s, file, sizeof file, &tag)) {
        sb_err e;
        if (!sb_mkdir_p(s->ref_store, &e) || !sb_ref_cache_save(s->ref_cache, file, tag, &e))
            sb_log("the reference's answers are not kept for later runs: %s", e.msg);
    }
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
    sb_ref_cache_free(s->ref_cache);
    s->ref_cache = NULL;
    free(s->scratch);
    s->scratch = NULL;
    sb_calib_free(&s->calib);
    sb_gpu_free(&s->gpu);
    sb_path_free(&s->path);
    sb_scene_free(&s->scene);
}

void sb_session_close(sb_session *s) {
    sb_session_close_scene(s);
    sb_clocks_close(s->clocks);
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
    s->ref_cache = sb_ref_cache_new(SB_REF_CACHE_BYTES);
    char file[4200];
    uint64_t tag;
    if (ref_store_file(s, file, sizeof file, &tag)) sb_ref_cache_load(s->ref_cache, file, tag);
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
    for (int i = 0; i < spec->params.count; i++)
        if (spec->params.v[i].automatic)
            return sb_fail(err, "%s:%s=auto: only run, batch and tune calibrate auto values", t->name,
                           spec->params.v[i].def->name);
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

int sb_instance_history(const sb_instance *in) { return in->tech->history ? in->tech->history(in->desc) : 0; }

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
                     sb_frame_rec *recs, sb_err *err) {
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
        ok = sb_eval_frame(s, in, pf, n, sb_instance_history(in), &seq, &b, &f, &r->err, err);
        if (ok && s->opts.error_every > 0 && pf % s->opts.error_every == 0) {
            r->evaluated = true;
        }
        if (ok && s->opts.images > 0 && pf % s->opts.images == 0)
            ok = sb_images_write_frame(dir, run_id, pf, b.w, b.h, b.rgba, b.vis, b.ref, b.pos, b.aux, err);
    }
    sb_eval_buf_free(&b);
    return ok;
}

/* ---- one run: passes of the path ---- */

struct sb_run {
    sb_session *s;
    const sb_run_spec *spec;
    sb_run_spec used;           /* spec with its "auto" values chosen (autobias.h) */
    bool calibrated;
    sb_summary *sum;
    char run_id[17], params[1024], csv_path[4096], out_dir[4096];
    sb_run_info info;
    sb_instance in;
    bool have_instance, keep_instance;   /* matrix order: one instance for every repetition */
    int seq;                    /* the instance's next frame sequence number (warm-up frames first) */
    sb_timer timer;             /* the measured frames: repetition r's frame j at r*N + j */
    sb_frame_rec *recs;
    int capacity, done, written, repeats;
    int warmup_frames;          /* warm-up frames rendered, every pass */
    double calib_before, calib_after;
    sb_csv rows;
    sb_csv_file cf;
    bool failed, finished;
    double t_run;
    sb_err err;
};

static bool fail_run(sb_run *r, const char *fmt, const char *what) {
    if (!r->failed) sb_fail(&r->err, fmt, what);
    r->failed = true;
    return false;
}

static bool ensure_instance(sb_run *r) {
    if (r->have_instance) return true;
    const sb_run_opts *o = &r->s->opts;
    int frames = (o->warmup < 0 ? SB_WARMUP_AUTO_CAP : o->warmup) + o->frames * (r->keep_instance ? r->capacity / o->frames : 1);
    if (!r->calibrated) { /* once per run, before its first frame */
        if (!sb_autobias_choose(r->s, r->spec, &r->used, r->info.auto_params, sizeof r->info.auto_params, NULL, &r->err))
            return fail_run(r, "auto offsets: %s", r->err.msg);
        r->calibrated = true;
    }
    if (!sb_instance_create(&r->in, r->s, &r->used, frames, &r->err)) return fail_run(r, "%s", r->err.msg);
    r->have_instance = true;
    r->seq = 0;
    return true;
}

static void drop_instance(sb_run *r) {
    if (!r->have_instance) return;
    sb_instance_destroy(&r->in);
    r->have_instance = false;
}

/* One warm-up frame: rendered and finished (its time is GPU-bound); returns that time. */
static double warm_frame(sb_run *r, sb_timer *wt, int k) {
    sb_session *s = r->s;
    double w0 = sb_now_ms();
    sb_timer_frame_begin(wt, k);
    sb_frame f;
    memset(&f, 0, sizeof f);
    int pf = s->opts.warmup < 0 ? 0 : k % s->opts.frames;   /* auto: the same frame, so times compare */
    sb_render_frame(s, &r->in, &f, pf, s->opts.frames, r->seq++, wt);
    sb_timer_frame_end(wt);
    glFinish();
    double ms = sb_now_ms() - w0;
    r->info.frames_wall_ms += ms; /* warm-up frames render too */
    return ms;
}

/* Warm-up: --warmup N frames replaying the path's first frames, or (auto, N < 0)
 * the path's first frame until the GPU has been busy long enough and the last
 * frames' times (and clocks, where readable) agree; capped. */
static void warm_up(sb_run *r) {
    sb_session *s = r->s;
    const bool hw = !s->ctx.software;
    const int fixed = s->opts.warmup;
    const int window = hw ? 5 : 4, cap = hw ? SB_WARMUP_AUTO_CAP : 30;
    const double min_busy = hw ? 300 : 0, tol = hw ? 0.03 : 0.10, cap_ms = 5000;
    sb_timer wt;
    sb_timer_init(&wt, s->timing, s->opts.ring, fixed >= 0 ? (fixed ? fixed : 1) : cap);
    double t[SB_WARMUP_AUTO_CAP], mhz[SB_WARMUP_AUTO_CAP], busy = 0, t0 = sb_now_ms();
    int k = 0;
    for (; fixed >= 0 ? k < fixed : k < cap; k++) {
        t[k] = warm_frame(r, &wt, k);
        mhz[k] = sb_clocks_mhz(s->clocks);
        busy += t[k];
        if (fixed >= 0 || k + 1 < window || busy < min_busy) continue;
        double lo = 1e300, hi = 0, clo = 1e300, chi = 0;
        for (int i = k + 1 - window; i <= k; i++) {
            lo = fmin(lo, t[i]), hi = fmax(hi, t[i]);
            clo = fmin(clo, mhz[i]), chi = fmax(chi, mhz[i]);
        }
        bool times_agree = hi - lo <= tol * lo;
        bool clocks_agree = isnan(mhz[k]) || chi - clo <= 0.02 * clo;
        if ((times_agree && clocks_agree) || sb_now_ms() - t0 > cap_ms) {
            k++;
            break;
        }
    }
    sb_timer_drain(&wt);
    sb_timer_free(&wt);
    r->warmup_frames += k;
}

static void record_frame(sb_run *r, int i, int pf, const sb_frame *f, double wall_ms) {
    sb_frame_rec *rec = &r->recs[i];
    rec->frame = pf;
    rec->repeat = i / r->s->opts.frames;
    rec->seq = f->seq;
    rec->progress = f->progress;
    rec->counters = f->counters;
    rec->wall_ms = wall_ms;
    rec->cpu_ms = wall_ms - r->timer.wait_ms;
    sb_clock_sample cs;
    sb_clocks_sample(r->s->clocks, &cs);
    rec->gpu_clock_mhz = cs.gfx_mhz;
    rec->throttle = cs.throttle;
    rec->start_s = (f->start_ms - sb_process_start_ms()) / 1e3;
    r->info.frames_wall_ms += wall_ms;
    r->done = i + 1;
}

/* The measured frames of repetition `rep`; false on failure (r->err). */
static bool measured_frames(sb_run *r, int rep, int index, int total) {
    sb_session *s = r->s;
    const sb_run_opts *o = &s->opts;
    const int N = o->frames;
    s->timed = true;
    sb_ref_background_timed(s->ref_cache, true);
    for (int j = 0; j < N; j++) {
        int i = rep * N + j;
        double w0 = sb_now_ms();
        sb_timer_frame_begin(&r->timer, i);
        sb_frame f;
        memset(&f, 0, sizeof f);
        f.start_ms = w0;
        sb_render_frame(s, &r->in, &f, j, N, r->seq++, &r->timer);
        sb_timer_frame_end(&r->timer);
        record_frame(r, i, j, &f, sb_now_ms() - w0);
        progress_line(s, index, total, r->spec->tech->name, j + 1, N, r->t_run);
        if (o->run_timeout_s > 0 && sb_now_ms() - r->t_run > o->run_timeout_s * 1e3) {
            char what[128];
            snprintf(what, sizeof what, "the run took longer than %g s (frame %d of %d)", o->run_timeout_s, i + 1,
                     r->capacity);
            s->timed = false;
            sb_ref_background_timed(s->ref_cache, false);
            return fail_run(r, "timeout: %s", what);
        }
    }
    sb_timer_drain(&r->timer); /* between repetitions, never inside a frame */
    s->timed = false;
    sb_ref_background_timed(s->ref_cache, false);
    if (r->spec->tech->collect)
        for (int j = 0; j < N; j++) r->spec->tech->collect(r->in.state, r->recs[rep * N + j].seq, &r->recs[rep * N + j].counters);
    return true;
}

bool sb_run_pass(sb_run *r, int index, int total) {
    if (r->failed || r->finished) return false;
    const sb_run_opts *o = &r->s->opts;
    bool first = r->repeats == 0;
    if (!ensure_instance(r)) return false;
    if (first || !r->keep_instance) warm_up(r);
    if (first) r->calib_before = sb_calib_measure(&r->s->calib);
    bool ok = measured_frames(r, r->repeats, index, total);
    if (ok) r->repeats++;
    r->calib_after = sb_calib_measure(&r->s->calib);
    if (!r->keep_instance) drop_instance(r);
    if (!ok) return false;
    if (o->error_every == 0) { /* nothing fills these rows later: they can go out now */
        for (; r->written < r->done; r->written++)
            sb_report_frame_row(&r->rows, &r->recs[r->written], &r->timer.times[r->written], r->spec->tech->stages);
        if (!sb_csv_file_write(&r->cf, &r->rows, &r->err)) return fail_run(r, "%s", r->err.msg);
    }
    return true;
}

bool sb_run_wants_more(const sb_run *r) {
    const sb_run_opts *o = &r->s->opts;
    if (r->failed || r->finished || r->repeats * o->frames >= r->capacity) return false;
    if (o->target_ci <= 0) return r->repeats < o->repeat;
    return r->repeats == 0 || sb_report_gpu_ci_pct(r->timer.times, r->done, o->frames) > o->target_ci;
}

/* A technique with shadow stages that drew no caster in any measured frame
 * measured nothing a user asked about: said in the run's warnings. */
static void check_shadows_drawn(sb_run *r) {
    const unsigned shadow = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_VOLUMES);
    if (!(r->spec->tech->stages & shadow)) return;
    for (int i = 0; i < r->done; i++)
        if (r->recs[i].counters.shadow_triangles) return;
    sb_run_warn(&r->info, "no shadow-casting triangle was drawn in any frame (nothing in view casts toward the light)");
}

/* When the evaluation cannot stand behind its figures: rays and rasterizer
 * disagree on the geometry, or the reference itself is not exact enough. */
static void check_geometry(sb_run *r) {
    long mism = 0, ns = 0, flip = 0, nf = 0;
    for (int i = 0; i < r->done; i++) {
        if (!r->recs[i].evaluated) continue;
        mism += r->recs[i].err.geom_mismatches, ns += r->recs[i].err.geom_samples;
        flip += r->recs[i].err.floor_disagree, nf += r->recs[i].err.floor_samples;
    }
    if (ns && (double)mism / ns > SB_GEOM_MISMATCH_WARN)
        sb_run_warn(&r->info, "rays and rasterizer disagree on the first surface at %.3g%% of sampled pixels "
                    "(geom_mismatch): the error figures are not against the geometry that was drawn",
                    100.0 * mism / ns);
    if (nf && (double)flip / nf > SB_ERR_FLOOR_WARN)
        sb_run_warn(&r->info, "the reference flips at %.3g%% of sampled pixels when cast from the exact surface "
                    "(err_floor): error differences below that are noise", 100.0 * flip / nf);
}

/* The stability verdict from the probe, the batch's probes and the frames' drift. */
static void judge_stability(sb_run *r) {
    double *ms = sb_xmalloc(sizeof(double) * (size_t)(r->done ? r->done : 1));
    for (int i = 0; i < r->done; i++) {
        const sb_stage_times *t = &r->timer.times[i];
        ms[i] = 0;
        for (int k = 0; k < SB_STAGE_COUNT; k++)
            if (t->mask & SB_STAGE_BIT(k)) ms[i] += t->ms[k];
    }
    /* a software rasterizer shares the CPU with everything else on the machine: wider tolerances */
    const bool sw = r->s->ctx.software;
    sb_stability_in in = {.calib_before = r->calib_before, .calib_after = r->calib_after,
                          .batch_calib = r->sum->calib, .nbatch = r->sum->ncalib, .frame_ms = ms, .n = r->done,
                          .per_repeat = r->s->opts.frames, .probe_tol = sw ? 0.25 : 0.10,
                          .batch_tol = sw ? 0.35 : 0.15, .drift_tol = sw ? 0.20 : 0.05};
    r->info.stable = sb_stability(&in, r->info.unstable_reason, sizeof r->info.unstable_reason) ? "yes" : "no";
    free(ms);
    r->info.calib_ms_before = r->calib_before;
    r->info.calib_ms_after = r->calib_after;
    sb_summary_add_calib(r->sum, r->calib_before);
}

/* After the passes: the evaluation pass, the rest of the rows, the file committed. */
static bool finish_run(sb_run *r) {
    const sb_run_opts *o = &r->s->opts;
    if (r->failed) return false;
    if (o->error_every > 0 || o->images > 0) {
        if (!ensure_instance(r)) return false;
        if (!evaluate(r->s, &r->in, r->seq, r->out_dir, r->run_id, r->recs, &r->err))
            return fail_run(r, "%s", r->err.msg);
    }
    for (; r->written < r->done; r->written++)
        sb_report_frame_row(&r->rows, &r->recs[r->written], &r->timer.times[r->written], r->spec->tech->stages);
    if (!sb_csv_file_write(&r->cf, &r->rows, &r->err) || !sb_gl_check(r->spec->tech->name, &r->err) ||
        !sb_csv_file_commit(&r->cf, &r->err))
        return fail_run(r, "%s", r->err.msg);
    check_shadows_drawn(r);
    check_geometry(r);
    judge_stability(r);
    return true;
}

sb_run *sb_run_begin(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index,
                     bool keep_instance) {
    sb_run *r = sb_xcalloc(1, sizeof *r);
    const sb_run_opts *o = &s->opts;
    r->s = s;
    r->spec = spec;
    r->sum = sum;
    r->keep_instance = keep_instance;
    r->t_run = sb_now_ms();
    sb_session_run_id(s, spec, r->run_id);
    sb_params_canonical(&spec->params, r->params, sizeof r->params);
    snprintf(r->csv_path, sizeof r->csv_path, "%s/%s.csv", out_dir, r->run_id);
    snprintf(r->out_dir, sizeof r->out_dir, "%s", out_dir);
    r->info = (sb_run_info){
        .run_id = r->run_id, .run_index = run_index, .scene = s->scene_name, .path = s->path_name,
        .technique = spec->tech->name, .params = r->params, .backend = sb_backend_name(o->backend),
        .renderer = s->ctx.renderer, .timing = sb_timing_name(s->timing), .clocks = s->clocks_mode, .status = "ok",
        .order = sb_order_name(o->order), .seed = o->order == SB_ORDER_SHUFFLE ? o->seed : 0,
        .reason = "", .frames = o->frames, .warmup = o->warmup, .width = o->width, .height = o->height,
        .target_ci = o->target_ci, .scene_triangles = sb_scene_triangles(&s->scene), .load_ms = s->scene.load_ms,
        .calib_ms_before = NAN, .calib_ms_after = NAN, .stable = "", .unstable_reason = "",
    };
    const char *skip = sb_skip_reason(s, spec->tech, &spec->params);
    if (skip) {
        r->finished = true;
        r->info.status = "skipped";
        r->info.reason = skip;
        return r;
    }
    r->capacity = o->frames * (o->target_ci > 0 ? o->max_repeat : o->repeat);
    sb_timer_init(&r->timer, s->timing, o->ring, r->capacity);
    r->recs = sb_xcalloc((size_t)r->capacity, sizeof *r->recs);
    if (sb_csv_file_open(&r->cf, r->csv_path, &r->err)) {
        sb_report_frame_header(&r->rows);
        if (!sb_csv_file_write(&r->cf, &r->rows, &r->err)) fail_run(r, "%s", r->err.msg);
    } else {
        fail_run(r, "%s", r->err.msg);
    }
    if (!r->failed && keep_instance) ensure_instance(r);
    return r;
}

bool sb_run_end(sb_run *r) {
    bool ok = r->info.status[0] == 's' || finish_run(r); /* skipped runs have nothing to finish */
    drop_instance(r);
    if (r->cf.f && r->failed) sb_csv_file_abort(&r->cf);
    r->info.run_wall_s = (sb_now_ms() - r->t_run) / 1e3;
    r->info.repeats = r->repeats;
    r->info.warmup = r->s->opts.warmup < 0 ? (r->repeats ? r->warmup_frames / r->repeats : 0) : r->s->opts.warmup;
    if (!ok) {
        sb_log("run %s (%s): failed: %s", r->run_id, r->spec->tech->name, r->err.msg);
        r->info.status = "failed";
        r->info.reason = r->err.msg;
    }
    bool measured = ok && r->info.status[0] == 'o';
    sb_summary_add_outcome(r->sum, &r->info, r->spec->tech->stages, measured ? r->recs : NULL, r->timer.times,
                           r->done);
    sb_csv_free(&r->rows);
    free(r->recs);
    if (r->timer.times) sb_timer_free(&r->timer);
    free(r);
    return ok;
}

bool sb_run_one(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index,
                int index, int total) {
    sb_run *r = sb_run_begin(s, spec, out_dir, sum, run_index, true);
    while (sb_run_wants_more(r) && sb_run_pass(r, index, total)) {}
    return sb_run_end(r);
}

static void shuffle(int *v, int n, uint64_t *rng) {
    for (int i = n - 1; i > 0; i--) {
        int j = (int)(sb_splitmix64(rng) % (uint64_t)(i + 1));
        int t = v[i];
        v[i] = v[j], v[j] = t;
    }
}

static bool end_run(sb_run *r, sb_summary *sum) {
    bool ok = sb_run_end(r);
    sb_err e;
    if (!sb_summary_flush(sum, &e)) fprintf(stderr, "shadowbench: %s\n", e.msg);
    return ok;
}

/* Rounds: every run that wants another repetition renders one, in the
 * round's order (interleave: matrix order; shuffle: a fresh permutation). */
static void run_rounds(sb_session *s, sb_run **runs, int n, int first, int total, uint64_t *rng) {
    int *perm = sb_xmalloc(sizeof(int) * (size_t)n);
    for (;;) {
        bool more = false;
        for (int k = 0; k < n; k++) more |= sb_run_wants_more(runs[k]);
        if (!more) break;
        for (int k = 0; k < n; k++) perm[k] = k;
        if (s->opts.order == SB_ORDER_SHUFFLE) shuffle(perm, n, rng);
        for (int k = 0; k < n; k++)
            if (sb_run_wants_more(runs[perm[k]])) sb_run_pass(runs[perm[k]], first + perm[k], total);
    }
    free(perm);
}

/* --overlap: the reference of the frames the runs evaluate is cast in the
 * background while they render, when a run will use it: one that is not
 * skipped and shades with the sun (a lamp's frames have other answers). */
static void start_background(sb_session *s, const sb_run_spec *const *specs, int n) {
    bool wanted = false;
    for (int k = 0; k < n && !wanted; k++)
        wanted = !(specs[k]->tech->needs & SB_NEEDS_POINT_LIGHT) && !sb_skip_reason(s, specs[k]->tech, &specs[k]->params);
    sb_err err;
    if (wanted && !sb_eval_background(s, &err))
        sb_log("the reference is not cast in the background: %s", err.msg); /* the evaluation says it again */
}

static void stop_background(sb_session *s) {
    if (!s->ref_cache) return;
    sb_ref_background_stats st = sb_ref_background_stop(s->ref_cache);
    if (st.queued && s->opts.progress)
        sb_log("reference background: %d frame(s) queued, %d cast (%llu rays, %.0f ms, %.0f ms of it while timed frames "
               "rendered), %d taken back by the evaluation, %d dropped",
               st.queued, st.frames, (unsigned long long)st.rays, st.ms, st.timed_ms, st.taken_back, st.dropped);
}

int sb_run_group(sb_session *s, const sb_run_spec *const *specs, const int *run_index, int n, const char *out_dir,
                 sb_summary *sum, int first, int total) {
    const sb_run_opts *o = &s->opts;
    if (n <= 0) return 0;
    start_background(s, specs, n);
    int failed = 0, *at = sb_xmalloc(sizeof(int) * (size_t)n);
    sb_run **runs = sb_xmalloc(sizeof *runs * (size_t)n);
    uint64_t rng = o->seed;
    for (int k = 0; k < n; k++) at[k] = k;
    /* one pass each: interleaving has nothing to interleave, shuffle permutes the runs */
    bool one_pass = o->repeat == 1 && o->target_ci <= 0;
    if (o->order == SB_ORDER_SHUFFLE && one_pass) shuffle(at, n, &rng);
    if (o->order == SB_ORDER_MATRIX || one_pass) {
        for (int k = 0; k < n; k++) {
            failed += !sb_run_one(s, specs[at[k]], out_dir, sum, run_index[at[k]], first + k, total);
            sb_err e;
            if (!sb_summary_flush(sum, &e)) fprintf(stderr, "shadowbench: %s\n", e.msg);
        }
    } else {
        for (int k = 0; k < n; k++) runs[k] = sb_run_begin(s, specs[k], out_dir, sum, run_index[k], false);
        run_rounds(s, runs, n, first, total, &rng);
        for (int k = 0; k < n; k++) failed += !end_run(runs[k], sum);
    }
    stop_background(s);
    free(runs);
    free(at);
    return failed;
}
