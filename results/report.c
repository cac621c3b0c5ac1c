/* report.c - the two column tables of the CSV contract (see report.h). A
 * stage a technique does not have, or a metric not measured for a frame, is
 * an empty field, not 0. */
#include "report.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "clocks.h"
#include "stats.h"

const char *const sb_stat_names[SB_STAT_COUNT] = {"mean", "median", "p95", "p99", "std", "ci95", "min", "max"};

static sb_cell empty(void) { return (sb_cell){SB_CELL_EMPTY, 0, NAN, NULL}; }
static sb_cell integer(long long v) { return (sb_cell){SB_CELL_INT, v, (double)v, NULL}; }
static sb_cell number(double v) { return (sb_cell){SB_CELL_NUM, 0, v, NULL}; }
static sb_cell text(const char *s) { return (sb_cell){SB_CELL_STR, 0, NAN, s}; }

static void put(sb_csv *c, sb_cell v) {
    switch (v.kind) {
    case SB_CELL_EMPTY: sb_csv_empty(c); break;
    case SB_CELL_INT: sb_csv_int(c, v.i); break;
    case SB_CELL_NUM: sb_csv_num(c, v.num); break;
    case SB_CELL_STR: sb_csv_str(c, v.str); break;
    }
}

static bool has(unsigned stages, int s) { return stages & SB_STAGE_BIT(s); }

static double gpu_ms(const sb_stage_times *t) {
    double sum = 0;
    for (int s = 0; s < SB_STAGE_COUNT; s++)
        if (t->mask & SB_STAGE_BIT(s)) sum += t->ms[s];
    return sum;
}

/* ---- per-frame columns ---- */

enum { C_DRAWS, C_SHADOW_DRAWS, C_TRIS, C_SHADOW_TRIS, C_RENDERED, C_SKIPPED, C_WARP };
enum { E_RATE, E_FALSE_SHADOW, E_FALSE_LIT, E_MAE, E_RES_MEAN, E_RES_P95, E_TEXEL_P95, E_GEOM, E_FLOOR };

static sb_cell f_frame(const sb_frame_row *r, int a) { (void)a; return integer(r->rec->frame); }
static sb_cell f_repeat(const sb_frame_row *r, int a) { (void)a; return integer(r->rec->repeat); }
static sb_cell f_progress(const sb_frame_row *r, int a) { (void)a; return number(r->rec->progress); }

static sb_cell f_counter(const sb_frame_row *r, int a) {
    const sb_counters *k = &r->rec->counters;
    switch (a) {
    case C_DRAWS: return integer(k->draw_calls);
    case C_SHADOW_DRAWS: return integer(k->shadow_draw_calls);
    case C_TRIS: return integer((long long)k->triangles);
    case C_SHADOW_TRIS: return integer((long long)k->shadow_triangles);
    }
    if (!has(r->stages, SB_STAGE_CASCADE)) return empty(); /* no shadow maps: no cascades */
    return integer(a == C_RENDERED ? k->cascades_rendered : a == C_SKIPPED ? k->cascades_skipped : k->warp_fallbacks);
}

static sb_cell f_stage_ms(const sb_frame_row *r, int s) {
    return has(r->stages, s) && (r->t->mask & SB_STAGE_BIT(s)) ? number(r->t->ms[s]) : empty();
}
static sb_cell f_gpu_ms(const sb_frame_row *r, int a) { (void)a; return number(gpu_ms(r->t)); }
static sb_cell f_cpu_ms(const sb_frame_row *r, int a) { (void)a; return number(r->rec->cpu_ms); }
static sb_cell f_start_s(const sb_frame_row *r, int a) { (void)a; return number(r->rec->start_s); }
static sb_cell f_gpu_clock(const sb_frame_row *r, int a) { (void)a; return number(r->rec->gpu_clock_mhz); }
static sb_cell f_cpu_wait_ms(const sb_frame_row *r, int a) { (void)a; return number(r->t->cpu_wait_ms); }
static sb_cell f_gpu_idle_ms(const sb_frame_row *r, int a) { (void)a; return number(r->t->gpu_idle_ms); }
static sb_cell f_wall_ms(const sb_frame_row *r, int a) { (void)a; return number(r->rec->wall_ms); }
static sb_cell f_stage_draws(const sb_frame_row *r, int s) {
    return has(r->stages, s) ? integer(r->rec->counters.stage_draw_calls[s]) : empty();
}
static sb_cell f_split(const sb_frame_row *r, int k) {
    return k < r->rec->counters.split_count ? number(r->rec->counters.splits[k]) : empty();
}
static sb_cell f_eval_pixels(const sb_frame_row *r, int a) {
    (void)a;
    return r->rec->evaluated ? integer(r->rec->err.pixels) : empty();
}
static sb_cell f_error(const sb_frame_row *r, int k) {
    if (!r->rec->evaluated) return empty();
    const sb_error_metrics *e = &r->rec->err;
    const double v[] = {e->err_rate, e->false_shadow, e->false_lit, e->vis_mae, e->res_err_mean,
                        e->res_err_p95, e->texel_px_p95, e->geom_mismatch, e->err_floor};
    return number(v[k]);
}

#define STAGE_MS(name, s, doc) {name, f_stage_ms, s, SB_COL_STAGE_TIME, doc}
#define SPLIT(k) {"split_" #k, f_split, k - 1, 0, "view-space far distance of cascade " #k " this frame"}

const sb_frame_col sb_frame_cols[] = {
    {"frame", f_frame, 0, 0, "frame of the path (0..frames-1)"},
    {"repeat", f_repeat, 0, 0, "repetition of the path (0-based)"},
    {"progress", f_progress, 0, 0, "position along the path in [0, 1]"},
    {"start_s", f_start_s, 0, 0, "when the frame began, seconds since the process started (the order of runs and repeats)"},
    {"draw_calls", f_counter, C_DRAWS, 0, "draw calls submitted in the frame"},
    {"shadow_draw_calls", f_counter, C_SHADOW_DRAWS, 0, "draw calls of the shadow stages (cascade, volumes)"},
    {"triangles", f_counter, C_TRIS, 0, "triangles submitted (instances counted)"},
    {"shadow_triangles", f_counter, C_SHADOW_TRIS, 0, "triangles submitted in the shadow stages"},
    {"cascades_rendered", f_counter, C_RENDERED, 0, "shadow maps rendered (empty: no shadow maps)"},
    {"cascades_skipped", f_counter, C_SKIPPED, 0, "shadow maps skipped for want of receivers"},
    {"warp_fallbacks", f_counter, C_WARP, 0, "warped maps that fell back to the uniform fit"},
    STAGE_MS("zpass_ms", SB_STAGE_ZPASS, "camera depth pre-pass"),
    STAGE_MS("minmax_ms", SB_STAGE_MINMAX, "depth reduction"),
    STAGE_MS("cascade_ms", SB_STAGE_CASCADE, "all shadow-map rendering"),
    STAGE_MS("final_ms", SB_STAGE_FINAL, "camera pass with the shadow lookup"),
    STAGE_MS("volumes_ms", SB_STAGE_VOLUMES, "stencil shadow volumes (and planar casters)"),
    STAGE_MS("rays_ms", SB_STAGE_RAYS, "CPU ray casting (raycast)"),
    {"gpu_ms", f_gpu_ms, 0, 0, "sum of the stage times"},
    {"cpu_ms", f_cpu_ms, 0, 0, "frame wall time not spent waiting for the GPU"},
    {"wall_ms", f_wall_ms, 0, 0, "frame wall time"},
    {"cpu_wait_ms", f_cpu_wait_ms, 0, 0, "CPU time blocked on the GPU (the fence of the frame a ring back, or glFinish)"},
    {"gpu_clock_mhz", f_gpu_clock, 0, 0, "the GPU's graphics clock at the frame's end (empty: not readable)"},
    {"gpu_idle_ms", f_gpu_idle_ms, 0, 0, "queries: the frame's GPU span not covered by a stage (the GPU waiting for the CPU)"},
    {"zpass_draw_calls", f_stage_draws, SB_STAGE_ZPASS, 0, "draw calls of the z-pass"},
    {"cascade_draw_calls", f_stage_draws, SB_STAGE_CASCADE, 0, "draw calls of the cascade stage"},
    {"final_draw_calls", f_stage_draws, SB_STAGE_FINAL, 0, "draw calls of the final pass"},
    {"volumes_draw_calls", f_stage_draws, SB_STAGE_VOLUMES, 0, "draw calls of the volumes stage"},
    SPLIT(1), SPLIT(2), SPLIT(3), SPLIT(4), SPLIT(5), SPLIT(6), SPLIT(7), SPLIT(8),
    {"eval_pixels", f_eval_pixels, 0, 0, "pixels evaluated against the reference (lit-facing, not sky)"},
    {"err_rate", f_error, E_RATE, 0, "share of evaluated pixels whose shadow state differs from the reference"},
    {"err_false_shadow", f_error, E_FALSE_SHADOW, 0, "share shadowed by the technique, lit in the reference"},
    {"err_false_lit", f_error, E_FALSE_LIT, 0, "share lit by the technique, shadowed in the reference"},
    {"vis_mae", f_error, E_MAE, 0, "mean absolute visibility difference"},
    {"res_err_mean", f_error, E_RES_MEAN, 0, "mean of max(-log2(shadow texels per pixel), 0)"},
    {"res_err_p95", f_error, E_RES_P95, 0, "95th percentile of the resolution error"},
    {"texel_px_p95", f_error, E_TEXEL_P95, 0, "95th percentile of shadow texels per pixel"},
    {"geom_mismatch", f_error, E_GEOM, 0,
     "share of sampled pixels where a camera ray's first hit is not the rasterized surface (one geometry?)"},
    {"err_floor", f_error, E_FLOOR, 0,
     "share of sampled evaluated pixels whose reference changes when cast from the ray's exact hit point"},
};
const int sb_frame_col_count = (int)SB_COUNT(sb_frame_cols);

/* ---- per-run columns ---- */

enum {
    S_RUN_ID, S_SCENE, S_PATH, S_TECHNIQUE, S_PARAMS, S_BACKEND, S_RENDERER, S_TIMING, S_STATUS, S_REASON, S_CLOCKS,
    S_STABLE, S_ORDER
};
enum { I_RUN_INDEX, I_FRAMES, I_WARMUP, I_WIDTH, I_HEIGHT, I_SCENE_TRIS };

static sb_cell r_text(const sb_run_row *r, int a) {
    const sb_run_info *in = r->info;
    const char *v[] = {in->run_id, in->scene, in->path, in->technique, in->params, in->backend, in->renderer,
                       in->timing, sb_status_names[in->status], in->reason, in->clocks, in->stable, in->order};
    return text(v[a]);
}
static sb_cell r_int(const sb_run_row *r, int a) {
    const sb_run_info *in = r->info;
    const long long v[] = {in->run_index, in->frames, in->warmup, in->width, in->height,
                           (long long)in->scene_triangles};
    return integer(v[a]);
}
static sb_cell r_seed(const sb_run_row *r, int a) {
    (void)a;
    return r->info->seed ? integer((long long)r->info->seed) : empty();
}
static sb_cell r_unstable(const sb_run_row *r, int a) { (void)a; return text(r->info->unstable_reason); }
static sb_cell r_calib(const sb_run_row *r, int a) {
    return number(r->n ? (a ? r->info->calib_ms_after : r->info->calib_ms_before) : NAN);
}
static sb_cell r_throttle(const sb_run_row *r, int a) {
    (void)a;
    static char names[256];
    uint64_t bits = 0;
    for (int i = 0; i < r->n; i++) bits |= r->recs[i].throttle;
    sb_throttle_names(bits, names, sizeof names);
    return text(names);
}
static sb_cell r_warnings(const sb_run_row *r, int a) { (void)a; return text(r->info->warnings); }
static sb_cell r_auto(const sb_run_row *r, int a) { (void)a; return text(r->info->auto_params); }
static sb_cell r_repeats(const sb_run_row *r, int a) { (void)a; return integer(r->n ? r->info->repeats : 0); }
static sb_cell r_target_ci(const sb_run_row *r, int a) {
    (void)a;
    return number(r->info->target_ci > 0 ? r->info->target_ci : NAN);
}
static sb_cell r_gpu_ci(const sb_run_row *r, int a) {
    (void)a;
    return number(r->n ? sb_report_gpu_ci_pct(r->times, r->n, r->info->frames) : NAN);
}
static sb_cell r_load_ms(const sb_run_row *r, int a) { (void)a; return number(r->info->load_ms); }
static sb_cell r_wall_s(const sb_run_row *r, int a) { (void)a; return number(r->info->run_wall_s); }
static sb_cell r_harness_share(const sb_run_row *r, int a) {
    (void)a;
    const sb_run_info *in = r->info;
    return number(r->n && in->run_wall_s > 0 ? 1.0 - in->frames_wall_ms / (in->run_wall_s * 1e3) : NAN);
}
/* The reference's part of a run, from its evaluated frames. */
typedef struct {
    int frames, reused, background;
    uint64_t rays, cast_rays;
    double ms, cast_ms; /* all of it; of it, the frames that cast here */
} ref_totals;

static ref_totals ref_sum(const sb_frame_rec *recs, int n) {
    ref_totals t = {0};
    for (int i = 0; i < n; i++) {
        const sb_error_metrics *e = &recs[i].err;
        if (!recs[i].evaluated) continue;
        t.frames++;
        t.reused += e->reused;
        t.background += e->background;
        t.rays += e->rays;
        t.ms += e->ray_ms;
        if (!e->reused && !e->background) t.cast_ms += e->ray_ms, t.cast_rays += e->rays;
    }
    return t;
}

static sb_cell r_error_frames(const sb_run_row *r, int a) {
    (void)a;
    return integer(ref_sum(r->recs, r->n).frames);
}
/* Pooled over the evaluated frames: a = 0 geometry mismatches, 1 the floor. */
static sb_cell r_pooled(const sb_run_row *r, int a) {
    long hit = 0, n = 0;
    for (int i = 0; i < r->n; i++) {
        const sb_error_metrics *e = &r->recs[i].err;
        if (!r->recs[i].evaluated) continue;
        hit += a ? e->floor_disagree : e->geom_mismatches;
        n += a ? e->floor_samples : e->geom_samples;
    }
    return number(n ? (double)hit / n : NAN);
}
static sb_cell r_rays_per_s(const sb_run_row *r, int a) {
    (void)a;
    ref_totals t = ref_sum(r->recs, r->n);
    return number(t.cast_ms > 0 && t.cast_rays ? t.cast_rays / (t.cast_ms / 1e3) : NAN);
}
/* a = 0 rays cast, 1 time in the reference, 2 frames whose reference was reused, 3 cast in the background;
 * empty without evaluated frames */
static sb_cell r_ref(const sb_run_row *r, int a) {
    ref_totals t = ref_sum(r->recs, r->n);
    if (!t.frames) return empty();
    return a == 0 ? integer((long long)t.rays) : a == 1 ? number(t.ms) : integer(a == 2 ? t.reused : t.background);
}

#define SERIES(name, stats, flags) {name, NULL, 0, stats, flags, NULL}

const sb_run_col sb_run_cols[] = {
    {"run_id", r_text, S_RUN_ID, 0, 0, "hash of scene and path contents, technique, parameters, frames, size, backend"},
    {"run_index", r_int, I_RUN_INDEX, 0, 0, "position in the expanded matrix"},
    {"scene", r_text, S_SCENE, 0, 0, "scene name"},
    {"path", r_text, S_PATH, 0, 0, "path name"},
    {"technique", r_text, S_TECHNIQUE, 0, 0, "technique"},
    {"params", r_text, S_PARAMS, 0, 0, "every parameter, in table order"},
    {"auto_params", r_auto, 0, 0, 0, "the values a run calibrated for its parameters given as auto (bias=auto...)"},
    {"backend", r_text, S_BACKEND, 0, 0, "egl or osmesa"},
    {"renderer", r_text, S_RENDERER, 0, 0, "GL_RENDERER"},
    {"timing", r_text, S_TIMING, 0, 0, "queries or sync: the timing mode used"},
    {"clocks", r_text, S_CLOCKS, 0, 0, "the GPU clock during the run: free, or locked at N MHz (--clocks)"},
    {"order", r_text, S_ORDER, 0, 0, "matrix, interleave or shuffle: the order of runs and repetitions (--order)"},
    {"seed", r_seed, 0, 0, 0, "shuffle's seed (--seed reproduces the order); empty for the other orders"},
    {"frames", r_int, I_FRAMES, 0, 0, "frames sampled along the path"},
    {"warmup", r_int, I_WARMUP, 0, 0, "warm-up frames, excluded"},
    {"width", r_int, I_WIDTH, 0, 0, "render width"},
    {"height", r_int, I_HEIGHT, 0, 0, "render height"},
    {"status", r_text, S_STATUS, 0, 0, "ok, failed, skipped or interrupted (SIGINT/SIGTERM; --resume redoes it)"},
    {"reason", r_text, S_REASON, 0, 0, "why a run failed or was skipped"},
    {"stable", r_text, S_STABLE, 0, 0, "yes, or no when the timings cannot be trusted (unstable_reason says why)"},
    {"unstable_reason", r_unstable, 0, 0, 0, "why stable is no: the calibration probe moved, or the frames drifted"},
    {"calib_ms_before", r_calib, 0, 0, 0, "the calibration probe just before the timed frames"},
    {"calib_ms_after", r_calib, 1, 0, 0, "the calibration probe just after them"},
    {"warnings", r_warnings, 0, 0, 0, "what the tool cannot stand behind in this run, \"; \"-separated"},
    {"repeats", r_repeats, 0, 0, 0, "repetitions of the path measured"},
    {"target_ci_pct", r_target_ci, 0, 0, 0, "--target-ci"},
    {"gpu_ci_pct", r_gpu_ci, 0, 0, 0, "95% CI half-width of mean gpu_ms, percent of the mean"},
    {"scene_triangles", r_int, I_SCENE_TRIS, 0, 0, "triangles in the scene"},
    {"load_ms", r_load_ms, 0, 0, 0, "scene load time"},
    {"run_wall_s", r_wall_s, 0, 0, 0, "wall time of the run"},
    {"harness_share", r_harness_share, 0, 0, 0, "share of the run's wall time outside rendered frames"},
    SERIES("draw_calls", SB_STAT_MEAN, 0),
    SERIES("shadow_draw_calls", SB_STAT_MEAN, SB_COL_DEFAULT_METRIC),
    SERIES("shadow_triangles", SB_STAT_MEAN, 0),
    SERIES("cascades_rendered", SB_STAT_MEAN, 0),
    SERIES("cascades_skipped", SB_STAT_MEAN, 0),
    SERIES("warp_fallbacks", SB_STAT_MEAN, 0),
    SERIES("zpass_ms", SB_STATS_TIMING, 0),
    SERIES("minmax_ms", SB_STATS_TIMING, 0),
    SERIES("cascade_ms", SB_STATS_TIMING, SB_COL_DEFAULT_METRIC),
    SERIES("final_ms", SB_STATS_TIMING, SB_COL_DEFAULT_METRIC),
    SERIES("volumes_ms", SB_STATS_TIMING, 0),
    SERIES("rays_ms", SB_STATS_TIMING, 0),
    SERIES("gpu_ms", SB_STATS_TIMING | SB_STAT_MIN, SB_COL_DEFAULT_METRIC),
    SERIES("cpu_ms", SB_STATS_TIMING, 0),
    SERIES("wall_ms", SB_STATS_TIMING, 0),
    SERIES("cpu_wait_ms", SB_STAT_MEAN, 0),
    SERIES("gpu_idle_ms", SB_STAT_MEAN, 0),
    SERIES("gpu_clock_mhz", SB_STAT_MIN | SB_STAT_MEDIAN | SB_STAT_MAX, 0),
    {"throttle_reasons", r_throttle, 0, 0, 0, "clock event (throttle) reasons seen in the measured frames (NVML)"},
    {"error_frames", r_error_frames, 0, 0, 0, "frames evaluated against the reference"},
    SERIES("err_rate", SB_STAT_MEAN | SB_STAT_P95 | SB_STAT_CI95, SB_COL_DEFAULT_METRIC),
    SERIES("err_false_shadow", SB_STAT_MEAN | SB_STAT_P95, 0),
    SERIES("err_false_lit", SB_STAT_MEAN | SB_STAT_P95, 0),
    SERIES("vis_mae", SB_STAT_MEAN | SB_STAT_P95, 0),
    SERIES("res_err_mean", SB_STAT_MEAN | SB_STAT_P95, 0),
    SERIES("res_err_p95", SB_STAT_MEAN | SB_STAT_P95, 0),
    SERIES("texel_px_p95", SB_STAT_MEAN | SB_STAT_P95, 0),
    {"geom_mismatch", r_pooled, 0, 0, 0,
     "share of sampled pixels (all evaluated frames) where rays and rasterizer disagree on the first surface"},
    {"err_floor", r_pooled, 1, 0, 0,
     "share of sampled evaluated pixels whose reference flips when cast from the exact hit: the error figures' floor"},
    {"ref_rays", r_ref, 0, 0, 0, "reference rays cast for this run: 0 when every evaluated frame's answers were reused"},
    {"ref_reused", r_ref, 2, 0, 0, "evaluated frames whose reference came from an earlier run of the same frame"},
    {"ref_background", r_ref, 3, 0, 0, "evaluated frames whose reference was cast in the background for this run (--overlap; their rays are in ref_rays)"},
    {"ref_ms", r_ref, 1, 0, 0, "time the run spent in the reference (casting, geometry check, finding the answers or waiting for the background)"},
    {"ref_rays_per_s", r_rays_per_s, 0, 0, 0, "reference rays per second on this machine (frames that cast)"},
};
const int sb_run_col_count = (int)SB_COUNT(sb_run_cols);

/* ---- writing ---- */

static const sb_frame_col *frame_col(const char *name) {
    for (int k = 0; k < sb_frame_col_count; k++)
        if (!strcmp(sb_frame_cols[k].name, name)) return &sb_frame_cols[k];
    return NULL;
}

static void stat_name(char *out, size_t len, const char *series, int bit) {
    snprintf(out, len, "%s_%s", series, sb_stat_names[bit]);
}

void sb_report_frame_header(sb_csv *c) {
    for (int k = 0; k < sb_frame_col_count; k++) sb_csv_str(c, sb_frame_cols[k].name);
    sb_csv_end_row(c);
}

void sb_report_frame_row(sb_csv *c, const sb_frame_rec *r, const sb_stage_times *t, unsigned stages) {
    const sb_frame_row row = {r, t, stages};
    for (int k = 0; k < sb_frame_col_count; k++) put(c, sb_frame_cols[k].get(&row, sb_frame_cols[k].arg));
    sb_csv_end_row(c);
}

void sb_report_summary_header(sb_csv *c) {
    char name[128];
    for (int k = 0; k < sb_run_col_count; k++) {
        const sb_run_col *col = &sb_run_cols[k];
        if (col->get) {
            sb_csv_str(c, col->name);
            continue;
        }
        for (int b = 0; b < SB_STAT_COUNT; b++)
            if (col->stats & (1u << b)) {
                stat_name(name, sizeof name, col->name, b);
                sb_csv_str(c, name);
            }
    }
    sb_csv_end_row(c);
}

void sb_report_summary_row(sb_csv *c, const sb_run_info *info, unsigned stages, const sb_frame_rec *recs,
                           const sb_stage_times *times, int n) {
    if (!recs) n = 0;
    const sb_run_row row = {info, recs, times, n, stages};
    double *v = sb_xmalloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    for (int k = 0; k < sb_run_col_count; k++) {
        const sb_run_col *col = &sb_run_cols[k];
        if (col->get) {
            put(c, col->get(&row, col->arg));
            continue;
        }
        const sb_frame_col *fc = frame_col(col->name);
        for (int i = 0; i < n; i++) {
            const sb_frame_row fr = {&recs[i], &times[i], stages};
            sb_cell cell = fc->get(&fr, fc->arg);
            v[i] = cell.kind == SB_CELL_INT || cell.kind == SB_CELL_NUM ? cell.num : NAN;
        }
        sb_stats st = sb_stats_compute(v, n);
        const double s[SB_STAT_COUNT] = {st.mean, st.median, st.p95, st.p99, st.std, st.ci95, st.min, st.max};
        for (int b = 0; b < SB_STAT_COUNT; b++)
            if (col->stats & (1u << b)) sb_csv_num(c, s[b]);
    }
    sb_csv_end_row(c);
    free(v);
}

void sb_report_columns(sb_csv *c) {
    const char *hdr[] = {"scope", "name", "statistics", "flags", "doc"};
    for (size_t i = 0; i < SB_COUNT(hdr); i++) sb_csv_str(c, hdr[i]);
    sb_csv_end_row(c);
    for (int k = 0; k < sb_frame_col_count; k++) {
        const sb_frame_col *f = &sb_frame_cols[k];
        sb_csv_str(c, "frame");
        sb_csv_str(c, f->name);
        sb_csv_str(c, "");
        sb_csv_str(c, f->flags & SB_COL_STAGE_TIME ? "stage_time" : "");
        sb_csv_str(c, f->doc);
        sb_csv_end_row(c);
    }
    for (int k = 0; k < sb_run_col_count; k++) {
        const sb_run_col *r = &sb_run_cols[k];
        char stats[96] = "";
        for (int b = 0; b < SB_STAT_COUNT; b++)
            if (r->stats & (1u << b)) {
                size_t l = strlen(stats);
                snprintf(stats + l, sizeof stats - l, "%s%s", l ? "|" : "", sb_stat_names[b]);
            }
        const sb_frame_col *fc = r->get ? NULL : frame_col(r->name);
        sb_csv_str(c, "run");
        sb_csv_str(c, r->name);
        sb_csv_str(c, stats);
        sb_csv_str(c, r->flags & SB_COL_DEFAULT_METRIC ? "default_metric" : "");
        sb_csv_str(c, fc ? fc->doc : r->doc);
        sb_csv_end_row(c);
    }
}

/* One markdown cell: pipes escaped. */
static void md_cell(FILE *out, const char *text) {
    fputs("| ", out);
    for (const char *p = text; *p; p++) {
        if (*p == '|') fputc('\\', out);
        fputc(*p, out);
    }
    fputc(' ', out);
}

void sb_report_columns_markdown(FILE *out) {
    fprintf(out, "### Per frame (`<run_id>.csv`)\n\n| column | meaning |\n|---|---|\n");
    for (int k = 0; k < sb_frame_col_count; k++) {
        char name[80];
        snprintf(name, sizeof name, "`%s`", sb_frame_cols[k].name);
        md_cell(out, name);
        md_cell(out, sb_frame_cols[k].doc);
        fputs("|\n", out);
    }
    fprintf(out, "\n### Per run (`summary.csv`)\n\nA series is a per-frame column summarised as "
                 "`<column>_<statistic>` for each statistic listed.\n\n| column | statistics | meaning |\n|---|---|---|\n");
    for (int k = 0; k < sb_run_col_count; k++) {
        const sb_run_col *r = &sb_run_cols[k];
        char name[80], stats[120] = "";
        snprintf(name, sizeof name, "`%s`", r->name);
        for (int b = 0; b < SB_STAT_COUNT; b++)
            if (r->stats & (1u << b)) {
                size_t l = strlen(stats);
                snprintf(stats + l, sizeof stats - l, "%s%s", l ? ", " : "", sb_stat_names[b]);
            }
        const sb_frame_col *fc = r->get ? NULL : frame_col(r->name);
        md_cell(out, name);
        md_cell(out, stats);
        md_cell(out, fc ? fc->doc : r->doc);
        fputs("|\n", out);
    }
}

bool sb_report_metric(const char *name, sb_metric_cols *out) {
    memset(out, 0, sizeof *out);
    for (int k = 0; k < sb_run_col_count; k++) {
        const sb_run_col *r = &sb_run_cols[k];
        if (strcmp(r->name, name)) continue;
        if (r->get) {
            snprintf(out->center, sizeof out->center, "%s", name);
            snprintf(out->mean, sizeof out->mean, "%s", name);
        } else if ((r->stats & SB_STAT_MEDIAN) && (r->stats & SB_STAT_CI95)) {
            snprintf(out->center, sizeof out->center, "%s_median", name);
            snprintf(out->mean, sizeof out->mean, "%s_mean", name);
            snprintf(out->ci, sizeof out->ci, "%s_ci95", name);
        } else {
            snprintf(out->center, sizeof out->center, "%s_mean", name);
            snprintf(out->mean, sizeof out->mean, "%s_mean", name);
        }
        return true;
    }
    return false;
}

int sb_report_default_metrics(const char **out, int max) {
    int n = 0;
    for (int k = 0; k < sb_run_col_count && n < max; k++)
        if (sb_run_cols[k].flags & SB_COL_DEFAULT_METRIC) out[n++] = sb_run_cols[k].name;
    return n;
}

double sb_report_gpu_ci_pct(const sb_stage_times *times, int n, int per_repeat) {
    double *v = sb_xmalloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    int m = 0;
    if (per_repeat > 0 && n >= 2 * per_repeat) {
        for (int r = 0; r + per_repeat <= n; r += per_repeat) {
            double sum = 0;
            for (int i = r; i < r + per_repeat; i++) sum += gpu_ms(&times[i]);
            v[m++] = sum / per_repeat;
        }
    } else {
        for (int i = 0; i < n; i++) v[m++] = gpu_ms(&times[i]);
    }
    sb_stats st = sb_stats_compute(v, m);
    free(v);
    return st.mean > 0 ? 100.0 * st.ci95 / st.mean : NAN;
}

void sb_run_warn(sb_run_info *info, const char *fmt, ...) {
    size_t n = strlen(info->warnings);
    if (n && n + 2 < sizeof info->warnings) {
        memcpy(info->warnings + n, "; ", 3);
        n += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(info->warnings + n, sizeof info->warnings - n, fmt, ap);
    va_end(ap);
}

/* ---- the summary file ---- */

void sb_summary_open(sb_summary *sum, const char *path) {
    memset(sum, 0, sizeof *sum);
    sum->path = sb_strdup(path);
    sb_report_summary_header(&sum->rows);
}

void sb_summary_add_calib(sb_summary *sum, double calib_ms) {
    if (!(calib_ms > 0)) return;
    sum->calib = sb_xrealloc(sum->calib, sizeof(double) * (size_t)(sum->ncalib + 1));
    sum->calib[sum->ncalib++] = calib_ms;
}

const char *const sb_status_names[SB_STATUS_COUNT] = {"ok", "skipped", "interrupted", "failed"};

sb_status sb_status_of(const char *name) {
    for (int s = 0; s < SB_STATUS_COUNT; s++) { /* the one place a name is read back */
        const char *n = sb_status_names[s];
        if (name && !strcmp(name, n)) return s;
    }
    return SB_STATUS_FAILED;
}

static void count_status(sb_summary *sum, sb_status status) {
    sum->count++;
    sum->failed += status == SB_STATUS_FAILED;
    sum->interrupted += status == SB_STATUS_INTERRUPTED;
    sum->skipped += status == SB_STATUS_SKIPPED;
}

/* $SB_AUDIT_OUTCOMES (the test suite sets it): every run that did not end ok
 * is appended there, status and reason, so the suite can check over every
 * summary it wrote that none ended without a reason. */
static void audit_outcome(const sb_run_info *info) {
    const char *file = getenv("SB_AUDIT_OUTCOMES");
    if (!file || !*file || info->status == SB_STATUS_OK) return;
    FILE *f = fopen(file, "a");
    if (!f) return;
    char reason[1100];
    snprintf(reason, sizeof reason, "%s", info->reason ? info->reason : "");
    for (char *p = reason; *p; p++)
        if (*p == '\t' || *p == '\n') *p = ' ';
    fprintf(f, "%s\t%s\t%s\t%s\n", sb_status_names[info->status], info->run_id ? info->run_id : "", info->technique ? info->technique : "",
            reason);
    fclose(f);
}

void sb_summary_add_outcome(sb_summary *sum, const sb_run_info *info, unsigned stages, const sb_frame_rec *recs,
                            const sb_stage_times *times, int n) {
    audit_outcome(info);
    sb_report_summary_row(&sum->rows, info, stages, recs, times, n);
    count_status(sum, info->status);
    for (int i = 0; times && i < n; i++) sum->timed_gpu_ms += gpu_ms(&times[i]);
    ref_totals t = ref_sum(recs, recs ? n : 0);
    sum->ref_rays += t.rays;
    sum->ref_reused += t.reused;
    sum->ref_background += t.background;
    sum->unstable += info->stable && !strcmp(info->stable, "no");
}

void sb_summary_add_line(sb_summary *sum, const char *line, sb_status status) {
    sb_csv_line(&sum->rows, line);
    count_status(sum, status);
}

bool sb_summary_flush(sb_summary *sum, sb_err *err) {
    return sb_write_file_atomic(sum->path, sum->rows.buf, sum->rows.len, err);
}

void sb_summary_free(sb_summary *sum) {
    free(sum->path);
    free(sum->calib);
    sb_csv_free(&sum->rows);
    memset(sum, 0, sizeof *sum);
}

bool sb_report_write_columns(const char *dir, sb_err *err) {
    sb_csv c = {0};
    sb_report_columns(&c);
    char path[4200];
    snprintf(path, sizeof path, "%s/columns.csv", dir);
    bool ok = sb_write_file_atomic(path, c.buf, c.len, err);
    sb_csv_free(&c);
    return ok;
}
