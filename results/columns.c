/* columns.c - the two column tables of the CSV contract (see columns.h). A
 * stage a technique does not have, or a metric not measured for a frame, is
 * an empty field, not 0. */
#include "columns.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clocks.h"
#include "stats.h"
#include "table.h"
#include "technique.h"
#include "runkey.h"

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
    for (int s = 0; s < SB_TIMER_STAGES; s++)
        if (t->mask & SB_STAGE_BIT(s)) sum += t->ms[s];
    return sum;
}

/* ---- per-frame columns ---- */

static sb_cell f_frame(const sb_frame_row *r, int a) { (void)a; return integer(r->rec->frame); }
static sb_cell f_repeat(const sb_frame_row *r, int a) { (void)a; return integer(r->rec->repeat); }
static sb_cell f_progress(const sb_frame_row *r, int a) { (void)a; return number(r->rec->progress); }

/* A counter of the frame: arg is its offset in sb_counters. */
#define COUNTER(r, off, T) (*(const T *)((const char *)&(r)->rec->counters + (off)))
static sb_cell f_u32(const sb_frame_row *r, int off) { return integer(COUNTER(r, off, uint32_t)); }
static sb_cell f_u64(const sb_frame_row *r, int off) { return integer((long long)COUNTER(r, off, uint64_t)); }
/* a shadow-map counter: empty for a technique without maps (no cascade stage) */
static sb_cell f_maps(const sb_frame_row *r, int off) {
    return has(r->stages, sb_stage_slot(&sb_stage_cascade)) ? integer(COUNTER(r, off, int)) : empty();
}
/* a motion counter: empty where nothing moves */
static sb_cell f_motion(const sb_frame_row *r, int off) {
    return r->rec->counters.moving ? integer(COUNTER(r, off, int)) : empty();
}
/* A technique's own counter (sb_technique.counters): arg is its place in own_cols; empty in the rows of a technique
 * that does not declare it (and where a row counted only in motion finds nothing moving). */
#define SB_MAX_OWN_COLS 64
static const sb_counter_def *own_cols[SB_MAX_OWN_COLS];
static sb_cell f_own(const sb_frame_row *r, int arg) {
    const sb_counters *c = &r->rec->counters;
    for (int k = 0; k < c->own_count; k++) {
        const sb_counter_def *d = &c->own_defs[k];
        if (d != own_cols[arg] && strcmp(d->name, own_cols[arg]->name)) continue;
        if (d->moving && !c->moving) return empty();
        return d->unit && !strcmp(d->unit, "count") ? integer(llround(c->own[k])) : number(c->own[k]);
    }
    return empty();
}
static sb_cell f_anim_ms(const sb_frame_row *r, int a) { (void)a; return number(r->rec->anim_ms); }

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
/* an error metric: arg is its offset in sb_error_metrics (a double) */
static sb_cell f_error(const sb_frame_row *r, int off) {
    if (!r->rec->evaluated) return empty();
    return number(*(const double *)((const char *)&r->rec->err + off));
}

/* The rows. A metric row says its unit, its summary statistics (its series),
 * which way is worse (SB_LOWER_WORSE; else higher is worse) and which
 * commands use it by default (SB_USE_*): a new metric is one row here (and
 * its figure in the frame record). */
#define COL(n, g, a, d) {.name = n, .get = g, .arg = a, .doc = d}
#define METRIC(n, g, a, u, st, fl, d) {.name = n, .get = g, .arg = a, .unit = u, .stats = st, .flags = fl, .doc = d}
#define ERROR(n, field, u, st, fl, d) METRIC(n, f_error, offsetof(sb_error_metrics, field), u, st, fl, d)
#define SPLIT(k) COL("split_" #k, f_split, k - 1, "view-space far distance of cascade " #k " this frame")
#define ALL_USES (SB_USE_COMPARE | SB_USE_HISTORY | SB_USE_REPORT)
/* a counter of sb_counters: its field, and the getter that reads its type (f_u32, f_u64, f_maps, f_motion) */
#define COUNT(n, g, field, st, fl, d) METRIC(n, g, offsetof(sb_counters, field), "count", st, fl, d)
#define ERR_STATS (SB_STAT_MEAN | SB_STAT_P95)
/* a shared stage's draws: arg is its slot (sb_frame_cols) */
#define STAGE_DRAWS(st, d) {.name = #st "_draw_calls", .get = f_stage_draws, .stage = &sb_stage_##st, .doc = d}

static const sb_frame_col frame_cols[] = {
    COL("frame", f_frame, 0, "frame of the path (0..frames-1)"),
    COL("repeat", f_repeat, 0, "repetition of the path (0-based)"),
    COL("progress", f_progress, 0, "position along the path in [0, 1]"),
    COL("start_s", f_start_s, 0, "when the frame began, seconds since the process started (the order of runs and repeats)"),
    {.name = "draw_calls", .get = f_u32, .arg = offsetof(sb_counters, draw_calls), .unit = "count",
     .stats = SB_STAT_MEAN, .flags = SB_USE_HISTORY | SB_USE_REPORT | SB_USE_NIGHT, .chart = "Draw calls",
     .doc = "draws submitted in the frame (a mesh range with its instances; each its own GL call with --submit direct)"},
    {.name = "shadow_draw_calls", .get = f_u32, .arg = offsetof(sb_counters, shadow_draw_calls), .unit = "count",
     .stats = SB_STAT_MEAN, .flags = ALL_USES | SB_USE_NIGHT, .chart = "Draw calls",
     .doc = "draws of the shadow stages (cascade, volumes)"},
    COUNT("api_calls", f_u32, api_calls, SB_STAT_MEAN, 0,
          "GL draw calls issued in the frame: draw_calls with --submit direct, one per pass, layer and state with "
          "indirect"),
    COUNT("shadow_api_calls", f_u32, shadow_api_calls, SB_STAT_MEAN, 0, "GL draw calls of the shadow stages"),
    {.name = "triangles", .get = f_u64, .arg = offsetof(sb_counters, triangles), .chart = "Triangles",
     .doc = "triangles submitted (instances counted)"},
    {.name = "shadow_triangles", .get = f_u64, .arg = offsetof(sb_counters, shadow_triangles), .unit = "count",
     .stats = SB_STAT_MEAN, .chart = "Triangles", .doc = "triangles submitted in the shadow stages"},
    COUNT("cascades_rendered", f_maps, cascades_rendered, SB_STAT_MEAN, 0, "shadow maps rendered (empty: no shadow maps)"),
    COUNT("cascades_skipped", f_maps, cascades_skipped, SB_STAT_MEAN, 0, "shadow maps skipped for want of receivers"),
    COUNT("cascades_cached", f_maps, cascades_cached, SB_STAT_MEAN, 0,
          "shadow maps kept from an earlier frame, not rendered again (cache=on: the same snapped window and light)"),
    COUNT("warp_fallbacks", f_maps, warp_fallbacks, SB_STAT_MEAN, 0, "warped maps that fell back to the uniform fit"),
    COUNT("casters_moved", f_motion, casters_moved, SB_STAT_MEAN, 0,
          "draws whose box changed since the technique's previous frame (empty: nothing in the scene moves)"),
    /* here: every technique's own counters, in the order of the technique list (sb_frame_cols) */
    {.name = NULL, .get = f_own},
    /* here: every declared stage's time, "<stage>_ms", in slot order (sb_frame_cols; the rows: stage.h) */
    {.name = NULL, .get = f_stage_ms, .unit = "ms", .stats = SB_STATS_TIMING, .flags = SB_COL_STAGE_TIME},
    {.name = "gpu_ms", .get = f_gpu_ms, .unit = "ms", .stats = SB_STATS_TIMING | SB_STAT_MIN, .role = SB_ROLE_TIME,
     .flags = ALL_USES | SB_USE_PAIR | SB_USE_NIGHT, .doc = "sum of the stage times"},
    METRIC("anim_ms", f_anim_ms, 0, "ms", SB_STATS_TIMING, 0,
           "posing the scene at the frame's time on the CPU: the nodes, the moving draws' boxes and the culling "
           "tree, the joints' matrices sent (and the vertices of the placements the GPU leaves to the CPU); the "
           "GPU's posing pass is pose_ms (not in gpu_ms; empty: nothing moves)"),
    METRIC("cpu_ms", f_cpu_ms, 0, "ms", SB_STATS_TIMING, 0, "frame wall time not spent waiting for the GPU"),
    METRIC("wall_ms", f_wall_ms, 0, "ms", SB_STATS_TIMING, 0, "frame wall time"),
    METRIC("cpu_wait_ms", f_cpu_wait_ms, 0, "ms", SB_STAT_MEAN, 0,
           "CPU time blocked on the GPU (the fence of the frame a ring back, or glFinish)"),
    METRIC("gpu_idle_ms", f_gpu_idle_ms, 0, "ms", SB_STAT_MEAN, 0,
           "queries: the frame's GPU span not covered by a stage (the GPU waiting for the CPU)"),
    METRIC("gpu_clock_mhz", f_gpu_clock, 0, "MHz", SB_STAT_MIN | SB_STAT_MEDIAN | SB_STAT_MAX, SB_LOWER_WORSE,
           "the GPU's graphics clock at the frame's end (empty: not readable)"),
    STAGE_DRAWS(zpass, "draw calls of the z-pass"),
    STAGE_DRAWS(cascade, "draw calls of the cascade stage"),
    STAGE_DRAWS(final, "draw calls of the final pass"),
    STAGE_DRAWS(volumes, "draw calls of the volumes stage"),
    SPLIT(1), SPLIT(2), SPLIT(3), SPLIT(4), SPLIT(5), SPLIT(6), SPLIT(7), SPLIT(8),
    COL("eval_pixels", f_eval_pixels, 0, "pixels evaluated against the reference (lit-facing, not sky)"),
    {.name = "err_rate", .get = f_error, .arg = offsetof(sb_error_metrics, err_rate), .unit = "share",
     .stats = SB_STAT_MEAN | SB_STAT_P95 | SB_STAT_CI95, .flags = ALL_USES | SB_USE_PAIR | SB_USE_NIGHT,
     .role = SB_ROLE_ERROR, .doc = "share of evaluated pixels whose shadow state differs from the reference"},
    ERROR("err_false_shadow", false_shadow, "share", ERR_STATS, 0, "share shadowed by the technique, lit in the reference"),
    ERROR("err_false_lit", false_lit, "share", ERR_STATS, 0, "share lit by the technique, shadowed in the reference"),
    ERROR("vis_mae", vis_mae, "visibility", ERR_STATS, 0, "mean absolute visibility difference"),
    ERROR("penumbra_px", penumbra_px, "share", ERR_STATS, 0,
          "share of evaluated pixels the reference puts strictly inside a penumbra (a light with a size; else 0)"),
    ERROR("penumbra_err", penumbra_err, "visibility", ERR_STATS, SB_USE_COMPARE | SB_USE_HISTORY,
          "mean |visibility - reference| over those pixels: how well a soft technique draws the penumbra"),
    ERROR("res_err_mean", res_err_mean, "octaves", ERR_STATS, 0, "mean of max(-log2(shadow texels per pixel), 0)"),
    ERROR("res_err_p95", res_err_p95, "octaves", ERR_STATS, 0, "95th percentile of the resolution error"),
    ERROR("texel_px_p95", texel_px_p95, "texels/px", ERR_STATS, SB_LOWER_WORSE,
          "95th percentile of shadow texels per pixel"),
    {.name = "flicker_rate", .get = f_error, .arg = offsetof(sb_error_metrics, flicker_rate), .unit = "share",
     .stats = ERR_STATS, .flags = ALL_USES | SB_USE_PAIR | SB_USE_NIGHT, .role = SB_ROLE_FLICKER,
     .doc = "share of the evaluated points the twin (--flicker-dt later) also sees whose shadow state flips in its "
            "maps while the reference does not"},
    ERROR("flicker_vis", flicker_vis, "visibility", ERR_STATS, 0,
          "mean |visibility change| at those points between the frame's maps and the twin's"),
    ERROR("ref_flicker", ref_flicker, "share", ERR_STATS, 0,
          "share of those points whose reference changes between frame and twin (a moving light or caster: real, "
          "not flicker)"),
    ERROR("split_jitter", split_jitter, "share", ERR_STATS, SB_USE_PAIR,
          "largest relative change of a cascade split distance between frame and twin"),
    ERROR("stale_px", stale_px, "share", SB_STAT_MEAN | SB_STAT_MAX, SB_USE_COMPARE | SB_USE_HISTORY | SB_USE_REPORT,
          "a cached technique where something moves: share of evaluated pixels whose visibility differs from the same "
          "technique's with its caches bypassed on the same frame (0 is right; empty: nothing cached or moving)"),
    ERROR("lights_px", lights_px, "lights", SB_STAT_MEAN, 0,
          "--lights: mean number of the run's lights that light an evaluated pixel (in range, facing it; empty: one "
          "light)"),
    {.name = "flip_mean", .get = f_error, .arg = offsetof(sb_error_metrics, flip_mean), .unit = "FLIP",
     .stats = ERR_STATS, .role = SB_ROLE_PERCEPTUAL,
     .doc = "--flip: mean LDR-FLIP (0 none .. 1) of the frame shaded with the technique's visibility against it "
            "shaded with the reference's, over every pixel: the shadow error as a viewer sees it (empty: not asked, "
            "--lights)"},
    ERROR("flip_p95", flip_p95, "FLIP", ERR_STATS, 0, "--flip: 95th percentile of that per-pixel FLIP"),
    ERROR("taa_flip_mean", taa_flip_mean, "FLIP", ERR_STATS, 0,
          "--taa on: mean LDR-FLIP of the frame resolved through TAA (jittered, reprojected, clamped, blended over 8 "
          "display frames) shaded with the technique's visibility, against the same resolved with the reference's"),
    ERROR("taa_flicker_rate", taa_flicker_rate, "share", ERR_STATS, 0,
          "--taa on: share of the evaluated points the twin sees again whose resolved shadow changes at the twin "
          "while the reference's does not (flicker a player sees through TAA)"),
    ERROR("geom_mismatch", geom_mismatch, "share", 0, 0,
          "share of sampled pixels where a camera ray's first hit is not the rasterized surface (one geometry?)"),
    ERROR("err_floor", err_floor, "share", 0, 0,
          "share of sampled evaluated pixels whose reference changes when cast from the ray's exact hit point"),
};

/* A technique with more counters of its own than a frame holds (SB_MAX_OWN_COUNTERS), or more in all than the
 * table: the build's own mistake, found by any test that writes a frame. */
static void too_many(const char *tech) {
    fprintf(stderr, "shadowbench: %s: more counters of its own than SB_MAX_OWN_COUNTERS (%d) or the column table "
            "holds (%d in all)\n", tech, SB_MAX_OWN_COUNTERS, SB_MAX_OWN_COLS);
    abort();
}

const sb_frame_col *sb_frame_cols(int *count) {
    static sb_frame_col cols[SB_COUNT(frame_cols) + SB_MAX_OWN_COLS + SB_TIMER_STAGES];
    static char stage_names[SB_TIMER_STAGES][32];
    static int n;
    if (!n)
        for (size_t k = 0; k < SB_COUNT(frame_cols); k++) {
            if (frame_cols[k].get == f_own) {   /* every technique's own counters, each name once */
                int owned = 0;
                for (int t = 0; t < sb_technique_count(); t++) {
                    const sb_technique *tech = sb_technique_at(t);
                    if (tech->counter_count > SB_MAX_OWN_COUNTERS) too_many(tech->name);
                    for (int c = 0; c < tech->counter_count; c++) {
                        const sb_counter_def *d = &tech->counters[c];
                        bool seen = false;
                        for (int o = 0; o < owned && !seen; o++) seen = !strcmp(own_cols[o]->name, d->name);
                        for (int o = 0; o < n && !seen; o++) seen = !strcmp(cols[o].name, d->name);
                        if (seen) continue;
                        if (owned == SB_MAX_OWN_COLS) too_many(tech->name);
                        own_cols[owned] = d;
                        cols[n++] = (sb_frame_col){.name = d->name, .get = f_own, .arg = owned, .unit = d->unit,
                                                   .stats = d->stats, .flags = d->flags, .doc = d->doc};
                        owned++;
                    }
                }
                continue;
            }
            if (frame_cols[k].flags & SB_COL_STAGE_TIME) {   /* every declared stage, in slot order */
                for (int slot = 0; slot < sb_stage_count(); slot++) {
                    const sb_stage_def *d = sb_stage_at(slot);
                    snprintf(stage_names[slot], sizeof stage_names[0], "%s_ms", d->name);
                    cols[n] = frame_cols[k];
                    cols[n].name = stage_names[slot], cols[n].arg = slot, cols[n].stage = d;
                    cols[n].flags |= d->flags, cols[n].doc = d->doc;
                    n++;
                }
                continue;
            }
            cols[n] = frame_cols[k];
            if (cols[n].stage) cols[n].arg = sb_stage_slot(cols[n].stage);
            n++;
        }
    *count = n;
    return cols;
}

/* ---- per-run columns ---- */

/* A field of the run's sb_run_info: arg is its offset. */
#define FIELD(r, off, T) (*(const T *)((const char *)(r)->info + (off)))
static sb_cell r_str(const sb_run_row *r, int off) {   /* a const char * (NULL: empty text) */
    const char *v = FIELD(r, off, const char *);
    return text(v ? v : "");
}
static sb_cell r_chars(const sb_run_row *r, int off) { return text((const char *)r->info + off); }   /* a char array */
static sb_cell r_int(const sb_run_row *r, int off) { return integer(FIELD(r, off, int)); }
static sb_cell r_u64(const sb_run_row *r, int off) { return integer((long long)FIELD(r, off, uint64_t)); }
static sb_cell r_num(const sb_run_row *r, int off) { return number(FIELD(r, off, double)); }
/* a figure of the measured frames: empty for a run that measured none */
static sb_cell r_measured(const sb_run_row *r, int off) { return number(r->n ? FIELD(r, off, double) : NAN); }
static sb_cell r_status(const sb_run_row *r, int a) { (void)a; return text(sb_status_names[r->info->status]); }
static sb_cell r_attempt(const sb_run_row *r, int a) { (void)a; return integer(r->info->attempt > 1 ? r->info->attempt : 1); }
static sb_cell r_seed(const sb_run_row *r, int a) {
    (void)a;
    return r->info->seed ? integer((long long)r->info->seed) : empty();
}
static sb_cell r_throttle(const sb_run_row *r, int a) {
    (void)a;
    static char names[256];
    uint64_t bits = 0;
    for (int i = 0; i < r->n; i++) bits |= r->recs[i].throttle;
    sb_throttle_names(bits, names, sizeof names);
    return text(names);
}
static sb_cell r_repeats(const sb_run_row *r, int a) { (void)a; return integer(r->n ? r->info->repeats : 0); }
static sb_cell r_target_ci(const sb_run_row *r, int a) {
    (void)a;
    return number(r->info->target_ci > 0 ? r->info->target_ci : NAN);
}
static sb_cell r_gpu_ci(const sb_run_row *r, int a) {
    (void)a;
    return number(r->n ? sb_columns_gpu_ci_pct(r->times, r->n, r->info->frames) : NAN);
}
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
static sb_cell r_rays_px(const sb_run_row *r, int a) {
    (void)a;
    int cast = 0;
    for (int i = 0; i < r->n; i++) cast += r->recs[i].evaluated && !r->recs[i].err.reused && !r->recs[i].err.background;
    ref_totals t = ref_sum(r->recs, r->n);
    double px = (double)cast * r->info->width * r->info->height;
    return number(px > 0 ? t.cast_rays / px : NAN);
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

#define RUN(n, g, a, d) {.name = n, .get = g, .arg = a, .doc = d}
#define RUN_METRIC(n, g, a, u, d) {.name = n, .get = g, .arg = a, .unit = u, .doc = d}
/* a field of sb_run_info, read by the getter of its type (r_str, r_chars, r_int, r_u64, r_num, r_measured) */
#define INFO(n, g, field, d) RUN(n, g, offsetof(sb_run_info, field), d)
#define INFO_METRIC(n, g, field, u, d) RUN_METRIC(n, g, offsetof(sb_run_info, field), u, d)
/* Where the series stand: one for each frame column with stats, in frame-table order. */
#define SB_RUN_SERIES {.name = NULL}

static const sb_run_col run_cols[] = {
    INFO("run_id", r_str, run_id, "hash of scene and path contents, technique, parameters, frames, size, backend"),
    INFO("run_index", r_int, run_index, "position in the expanded matrix"),
    INFO("scene", r_str, scene, "scene name"),
    INFO("path", r_str, path, "path name"),
    INFO("technique", r_str, technique, "technique"),
    INFO("params", r_str, params, "every parameter, in table order (one added after series began, such as "
                                  "cache, only when not at its default)"),
    INFO("auto_params", r_chars, auto_params, "the values a run calibrated for its parameters given as auto (bias=auto...)"),
    INFO("light", r_chars, light, "the reference light's size (--sun-size, --lamp-radius: \"sun 0.53 deg, 64 rays\") "
                                  "and the lights shadowed (--lights: \"lights lamps (6)\"); empty: the technique's "
                                  "one light, of no size"),
    INFO("anim", r_str, anim, "what of a file's animation plays (--anim, --anim-speed): empty for a still file or "
                              "every clip at speed 1, none for clips held still, else the clips (all, or their "
                              "names) and \" xS\" at another speed; a series of its own"),
    INFO("run_options", r_chars, run_options, "the run options that make it another run and have no column of their "
                                              "own, as given (\"--sun 30,45 --taa on\"); empty at their defaults; a "
                                              "series of its own"),
    INFO("backend", r_str, backend, "egl or osmesa"),
    INFO("renderer", r_str, renderer, "GL_RENDERER"),
    INFO("timing", r_str, timing, "queries or sync: the timing mode used"),
    INFO("submit", r_str, submit, "direct or indirect: how the passes' draws were issued (--submit)"),
    INFO("clocks", r_str, clocks, "the GPU clock during the run: free, or locked at N MHz (--clocks)"),
    INFO("order", r_str, order, "matrix, interleave or shuffle: the order of runs and repetitions (--order)"),
    RUN("seed", r_seed, 0, "shuffle's seed (--seed reproduces the order); empty for the other orders"),
    INFO("frames", r_int, frames, "frames sampled along the path"),
    INFO("warmup", r_int, warmup, "warm-up frames, excluded"),
    INFO("width", r_int, width, "render width"),
    INFO("height", r_int, height, "render height"),
    RUN("status", r_status, 0, "ok, skipped, interrupted (SIGINT/SIGTERM; --resume redoes it) or failed"),
    INFO("reason", r_str, reason, "why a run failed or was skipped"),
    INFO("stable", r_str, stable, "yes, or no when the timings cannot be trusted (unstable_reason says why)"),
    INFO("unstable_reason", r_chars, unstable_reason, "why stable is no: the calibration probe moved, or the frames drifted"),
    INFO_METRIC("calib_ms_before", r_measured, calib_ms_before, "ms", "the calibration probe just before the timed frames"),
    INFO_METRIC("calib_ms_after", r_measured, calib_ms_after, "ms", "the calibration probe just after them"),
    RUN("attempt", r_attempt, 0, "which attempt of the run these figures are: 1, or 2 and on for a run flagged unstable "
                                 "and run again at the end (--rerun-unstable; the earlier attempts' frames in "
                                 "<run_id>.attempt-K.csv)"),
    INFO("warnings", r_chars, warnings, "what the tool cannot stand behind in this run, \"; \"-separated"),
    INFO("replayed", r_chars, replayed, "where a test replayed its timings instead of measuring them: timings "
                                        "(SB_REPLAY_TIMINGS: the stability verdict's), frame-costs (SB_REPLAY_FRAME_MS), "
                                        "both space-separated; empty: measured (a column of its own, so that no length "
                                        "of the warnings can drop the mark)"),
    RUN("repeats", r_repeats, 0, "repetitions of the path measured"),
    RUN("target_ci_pct", r_target_ci, 0, "--target-ci"),
    {.name = "gpu_ci_pct", .get = r_gpu_ci, .unit = "percent", .flags = SB_USE_NIGHT,
     .doc = "95% CI half-width of mean gpu_ms, percent of the mean"},
    INFO("scene_triangles", r_u64, scene_triangles, "triangles in the scene"),
    INFO_METRIC("load_ms", r_num, load_ms, "ms", "scene load time"),
    {.name = "shadow_mb", .get = r_num, .arg = offsetof(sb_run_info, shadow_mb), .unit = "MiB", .role = SB_ROLE_MEMORY,
     .doc = "shadow storage the run holds resident (maps in their formats, moments and their blur copies, cube "
            "faces, paraboloids): the figure the GPU-memory check reads; 0 for a technique without maps"},
    INFO_METRIC("run_wall_s", r_num, run_wall_s, "s", "wall time of the run"),
    INFO_METRIC("eval_s", r_num, eval_s, "s",
                "wall time of the untimed evaluation pass: its frames, their flicker twins, the reference"),
    INFO_METRIC("ref_refit_ms", r_num, ref_refit_ms, "ms",
                "a moving scene: the reference's refit of its moving draws to a frame's pose (the CPU's copy of the "
                "vertices posed first, where the GPU posed the frame's), mean over the evaluation pass (empty: nothing "
                "moves)"),
    RUN_METRIC("harness_share", r_harness_share, 0, "share", "share of the run's wall time outside rendered frames"),
    RUN("throttle_reasons", r_throttle, 0, "clock event (throttle) reasons seen in the measured frames (NVML)"),
    RUN("error_frames", r_error_frames, 0, "frames evaluated against the reference"),
    SB_RUN_SERIES,
    RUN_METRIC("geom_mismatch", r_pooled, 0, "share",
               "share of sampled pixels (all evaluated frames) where rays and rasterizer disagree on the first surface"),
    RUN_METRIC("err_floor", r_pooled, 1, "share",
               "share of sampled evaluated pixels whose reference flips when cast from the exact hit: the error figures' floor"),
    RUN_METRIC("ref_rays", r_ref, 0, "count", "reference rays cast for this run: 0 when every evaluated frame's answers were reused"),
    RUN_METRIC("ref_rays_px", r_rays_px, 0, "rays/px",
               "reference rays cast per pixel of a frame it cast for (every light of --lights: only toward the points "
               "each one lights; empty when every answer was reused)"),
    RUN("ref_reused", r_ref, 2, "evaluated frames whose reference came from an earlier run of the same frame"),
    RUN("ref_background", r_ref, 3, "evaluated frames whose reference was cast in the background for this run (--overlap; their rays are in ref_rays)"),
    RUN_METRIC("ref_ms", r_ref, 1, "ms", "time the run spent in the reference (casting, geometry check, finding the answers or waiting for the background)"),
    {.name = "ref_rays_per_s", .get = r_rays_per_s, .unit = "rays/s", .flags = SB_LOWER_WORSE,
     .doc = "reference rays per second on this machine (frames that cast)"},
};

const sb_run_col *sb_run_cols(int *count) {
    static sb_run_col cols[SB_COUNT(run_cols) + SB_COUNT(frame_cols) + SB_MAX_OWN_COLS];
    static int n;
    int nf;
    const sb_frame_col *fcols = sb_frame_cols(&nf);
    if (!n)
        for (size_t k = 0; k < SB_COUNT(run_cols); k++) {
            if (run_cols[k].name) {
                cols[n++] = run_cols[k];
                continue;
            }
            for (int f = 0; f < nf; f++) {
                const sb_frame_col *fc = &fcols[f];
                if (fc->stats)
                    cols[n++] = (sb_run_col){.name = fc->name, .stats = fc->stats, .flags = fc->flags,
                                             .doc = fc->doc, .unit = fc->unit, .role = fc->role};
            }
        }
    *count = n;
    return cols;
}

/* ---- writing ---- */

static const sb_frame_col *frame_col(const char *name) {
    int n;
    const sb_frame_col *cols = sb_frame_cols(&n);
    for (int k = 0; k < n; k++)
        if (!strcmp(cols[k].name, name)) return &cols[k];
    return NULL;
}

static void stat_name(char *out, size_t len, const char *series, int bit) {
    snprintf(out, len, "%s_%s", series, sb_stat_names[bit]);
}

void sb_columns_frame_header(sb_csv *c) {
    int n;
    const sb_frame_col *cols = sb_frame_cols(&n);
    for (int k = 0; k < n; k++) sb_csv_str(c, cols[k].name);
    sb_csv_end_row(c);
}

/* A frame's cell: an untimed frame (another renderer's, `score`) has its place on the path and its error figures,
 * nothing the tool would have timed or counted drawing it. */
static sb_cell frame_cell(const sb_frame_col *col, const sb_frame_row *r) {
    if (r->rec->untimed && col->get != f_error && col->get != f_eval_pixels &&
        (!col->name || (strcmp(col->name, "frame") && strcmp(col->name, "repeat") && strcmp(col->name, "progress"))))
        return empty();
    return col->get(r, col->arg);
}

void sb_columns_frame_row(sb_csv *c, const sb_frame_rec *r, const sb_stage_times *t, unsigned stages) {
    const sb_frame_row row = {r, t, stages};
    int n;
    const sb_frame_col *cols = sb_frame_cols(&n);
    for (int k = 0; k < n; k++) put(c, frame_cell(&cols[k], &row));
    sb_csv_end_row(c);
}

void sb_columns_summary_header(sb_csv *c) {
    char name[128];
    int ncols;
    const sb_run_col *cols = sb_run_cols(&ncols);
    for (int k = 0; k < ncols; k++) {
        const sb_run_col *col = &cols[k];
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

void sb_columns_summary_row(sb_csv *c, const sb_run_info *info, unsigned stages, const sb_frame_rec *recs,
                           const sb_stage_times *times, int n) {
    if (!recs) n = 0;
    const sb_run_row row = {info, recs, times, n, stages};
    double *v = sb_xmalloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    int ncols;
    const sb_run_col *cols = sb_run_cols(&ncols);
    for (int k = 0; k < ncols; k++) {
        const sb_run_col *col = &cols[k];
        if (col->get) {
            put(c, col->get(&row, col->arg));
            continue;
        }
        const sb_frame_col *fc = frame_col(col->name);
        for (int i = 0; i < n; i++) {
            const sb_frame_row fr = {&recs[i], &times[i], stages};
            sb_cell cell = frame_cell(fc, &fr);
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

/* "mean|p95" (sep "|") or "mean, p95" */
static void stats_text(unsigned stats, const char *sep, char *out, size_t len) {
    out[0] = 0;
    for (int b = 0; b < SB_STAT_COUNT; b++)
        if (stats & (1u << b)) {
            size_t l = strlen(out);
            snprintf(out + l, len - l, "%s%s", l ? sep : "", sb_stat_names[b]);
        }
}

/* "compare|history|report" (sep "|"): the commands that use a metric by default */
static void uses_text(unsigned flags, const char *sep, char *out, size_t len) {
    static const struct { unsigned bit; const char *name; } uses[] = {
        {SB_USE_COMPARE, "compare"}, {SB_USE_PAIR, "pair"}, {SB_USE_HISTORY, "history"}, {SB_USE_REPORT, "report"},
        {SB_USE_NIGHT, "night"}};
    out[0] = 0;
    for (size_t i = 0; i < SB_COUNT(uses); i++)
        if (flags & uses[i].bit) {
            size_t l = strlen(out);
            snprintf(out + l, len - l, "%s%s", l ? sep : "", uses[i].name);
        }
}

static const char *worse_text(const char *unit, unsigned flags) {
    return !unit ? "" : flags & SB_LOWER_WORSE ? "lower" : "higher";
}

void sb_columns_csv(sb_csv *c) {
    const char *hdr[] = {"scope", "name", "statistics", "unit", "worse", "default_for", "flags", "doc"};
    for (size_t i = 0; i < SB_COUNT(hdr); i++) sb_csv_str(c, hdr[i]);
    sb_csv_end_row(c);
    char stats[96], uses[96];
    int nf;
    const sb_frame_col *fcols = sb_frame_cols(&nf);
    for (int k = 0; k < nf; k++) {
        const sb_frame_col *f = &fcols[k];
        stats_text(f->stats, "|", stats, sizeof stats);
        uses_text(f->flags, "|", uses, sizeof uses);
        const char *row[] = {"frame", f->name, stats, f->unit ? f->unit : "", worse_text(f->unit, f->flags), uses,
                             f->flags & SB_COL_STAGE_TIME ? "stage_time" : "", f->doc};
        for (size_t i = 0; i < SB_COUNT(row); i++) sb_csv_str(c, row[i]);
        sb_csv_end_row(c);
    }
    int n;
    const sb_run_col *cols = sb_run_cols(&n);
    for (int k = 0; k < n; k++) {
        const sb_run_col *r = &cols[k];
        stats_text(r->stats, "|", stats, sizeof stats);
        uses_text(r->flags, "|", uses, sizeof uses);
        const char *row[] = {"run", r->name, stats, r->unit ? r->unit : "", worse_text(r->unit, r->flags), uses, "",
                             r->doc};
        for (size_t i = 0; i < SB_COUNT(row); i++) sb_csv_str(c, row[i]);
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

void sb_columns_markdown(FILE *out) {
    fprintf(out, "### Per frame (`<run_id>.csv`)\n\n| column | unit | meaning |\n|---|---|---|\n");
    int nf;
    const sb_frame_col *fcols = sb_frame_cols(&nf);
    for (int k = 0; k < nf; k++) {
        char name[80];
        snprintf(name, sizeof name, "`%s`", fcols[k].name);
        md_cell(out, name);
        md_cell(out, fcols[k].unit ? fcols[k].unit : "");
        md_cell(out, fcols[k].doc);
        fputs("|\n", out);
    }
    fprintf(out, "\n### Per run (`summary.csv`)\n\nA series is a per-frame column summarised as "
                 "`<column>_<statistic>` for each statistic listed. A metric (a series, or a column with a "
                 "unit) can be named by `compare --metric` and `history regressions --metric`; *worse* says "
                 "which way it regresses, *default for* which commands use it when no `--metric` is given "
                 "(`pair`: `compare --pair` and the report's pair tables; `report`: the report's trend "
                 "charts; `night`: the report's night table).\n\n| column | statistics | unit | worse | default for | meaning |\n"
                 "|---|---|---|---|---|---|\n");
    int n;
    const sb_run_col *cols = sb_run_cols(&n);
    for (int k = 0; k < n; k++) {
        const sb_run_col *r = &cols[k];
        char name[80], stats[120], uses[96];
        snprintf(name, sizeof name, "`%s`", r->name);
        stats_text(r->stats, ", ", stats, sizeof stats);
        uses_text(r->flags, ", ", uses, sizeof uses);
        md_cell(out, name);
        md_cell(out, stats);
        md_cell(out, r->unit ? r->unit : "");
        md_cell(out, worse_text(r->unit, r->flags));
        md_cell(out, uses);
        md_cell(out, r->doc);
        fputs("|\n", out);
    }
}

bool sb_columns_metric(const char *name, sb_metric_cols *out) {
    memset(out, 0, sizeof *out);
    int n;
    const sb_run_col *cols = sb_run_cols(&n);
    for (int k = 0; k < n; k++) {
        const sb_run_col *r = &cols[k];
        if (strcmp(r->name, name)) continue;
        if (r->get && !r->unit) return false;   /* not a number: no metric */
        out->lower_worse = r->flags & SB_LOWER_WORSE;
        out->unit = r->unit;
        if (r->get) {
            snprintf(out->center, sizeof out->center, "%s", name);
            snprintf(out->mean, sizeof out->mean, "%s", name);
        } else if ((r->stats & SB_STAT_MEDIAN) && (r->stats & SB_STAT_CI95)) {
            snprintf(out->center, sizeof out->center, "%s_median", name);
            snprintf(out->mean, sizeof out->mean, "%s_mean", name);
            snprintf(out->ci, sizeof out->ci, "%s_ci95", name);
        } else {
            snprintf(out->center, sizeof out->center, "%s_%s", name,
                     r->stats & SB_STAT_MEAN ? "mean" : r->stats & SB_STAT_MEDIAN ? "median" : "min");
            snprintf(out->mean, sizeof out->mean, "%s", out->center);
        }
        return true;
    }
    return false;
}

int sb_columns_default_metrics(unsigned use, const char **out, int max) {
    int n = 0, ncols;
    const sb_run_col *cols = sb_run_cols(&ncols);
    for (int k = 0; k < ncols && n < max; k++)
        if (cols[k].flags & use) out[n++] = cols[k].name;
    return n;
}

int sb_columns_metrics(const char **out, int max) {
    int n = 0, ncols;
    const sb_run_col *cols = sb_run_cols(&ncols);
    for (int k = 0; k < ncols && n < max; k++)
        if (cols[k].stats || cols[k].unit) out[n++] = cols[k].name;
    return n;
}

const char *sb_columns_role(sb_col_role role) {
    int nf;
    const sb_frame_col *f = sb_frame_cols(&nf);
    for (int k = 0; k < nf; k++)
        if (f[k].role == role) return f[k].name;
    for (size_t k = 0; k < SB_COUNT(run_cols); k++)
        if (run_cols[k].name && run_cols[k].role == role) return run_cols[k].name;
    return "";
}

void sb_columns_role_stat(sb_col_role role, unsigned stat, char *out, size_t len) {
    int nf;
    const sb_frame_col *f = sb_frame_cols(&nf);
    for (int k = 0; k < nf; k++)
        if (f[k].role == role) {
            int b = 0;
            while (b < SB_STAT_COUNT && !(stat & (1u << b))) b++;
            stat_name(out, len, f[k].name, b < SB_STAT_COUNT ? b : 0);
            return;
        }
    snprintf(out, len, "%s", sb_columns_role(role));
}

int sb_columns_night(const char **out, int max) {
    static char names[64][96];
    int n = 0, ncols;
    const sb_run_col *cols = sb_run_cols(&ncols);
    for (int k = 0; k < ncols && n < max && n < 64; k++) {
        if (!(cols[k].flags & SB_USE_NIGHT)) continue;
        sb_metric_cols mc;
        if (!sb_columns_metric(cols[k].name, &mc)) continue;
        snprintf(names[n], sizeof names[n], "%s", mc.center);
        out[n] = names[n];
        n++;
    }
    return n;
}

double sb_columns_gpu_ms(const sb_stage_times *t) { return gpu_ms(t); }

double sb_columns_gpu_ci_pct(const sb_stage_times *times, int n, int per_repeat) {
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

void sb_run_mark_replayed(sb_run_info *info, const char *what) {
    size_t n = strlen(info->replayed), w = strlen(what);
    if (strstr(info->replayed, what) || n + w + 2 > sizeof info->replayed) return;
    snprintf(info->replayed + n, sizeof info->replayed - n, "%s%s", n ? " " : "", what);
}

/* ---- the summary file ---- */

void sb_summary_open(sb_summary *sum, const char *path) {
    memset(sum, 0, sizeof *sum);
    sum->path = sb_strdup(path);
    sb_columns_summary_header(&sum->rows);
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
    sb_columns_summary_row(&sum->rows, info, stages, recs, times, n);
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

/* The rows as a table (the buffer holds the header and every row). */
static bool rows_table(const sb_summary *sum, sb_table *t) {
    sb_err e;
    return sb_table_parse(t, "summary", sum->rows.buf ? sum->rows.buf : "", &e);
}

int sb_summary_rerun_runs(const sb_summary *sum, char ***ids, sb_rerun_run **runs) {
    sb_table t;
    int n = 0;
    *ids = NULL, *runs = NULL;
    if (!rows_table(sum, &t)) return 0;
    for (int r = 0; r < t.nrows; r++)
        if (sb_status_of(sb_table_get(&t, r, "status")) == SB_STATUS_OK) {
            *ids = sb_xrealloc(*ids, sizeof **ids * (size_t)(n + 1));
            *runs = sb_xrealloc(*runs, sizeof **runs * (size_t)(n + 1));
            (*ids)[n] = sb_strdup(sb_run_key_id(&t, r));
            const char *w = sb_table_get(&t, r, "run_wall_s");
            (*runs)[n++] = (sb_rerun_run){*w ? strtod(w, NULL) : NAN, !strcmp(sb_table_get(&t, r, "stable"), "no")};
        }
    sb_table_free(&t);
    return n;
}

bool sb_summary_stable(const sb_summary *sum, const char *run_id) {
    sb_table t;
    bool stable = false;
    if (!rows_table(sum, &t)) return false;
    for (int r = 0; r < t.nrows; r++)
        if (!strcmp(sb_run_key_id(&t, r), run_id)) stable = !strcmp(sb_table_get(&t, r, "stable"), "yes");
    sb_table_free(&t);
    return stable;
}

bool sb_summary_drop(sb_summary *sum, const char *run_id) {
    sb_table t;
    if (!rows_table(sum, &t)) return false;
    sb_csv rows = {0};
    sb_columns_summary_header(&rows);
    bool dropped = false;
    for (int r = 0; r < t.nrows; r++) {
        if (!dropped && !strcmp(sb_run_key_id(&t, r), run_id)) {
            sb_status st = sb_status_of(sb_table_get(&t, r, "status"));
            sum->count--;
            sum->failed -= st == SB_STATUS_FAILED;
            sum->interrupted -= st == SB_STATUS_INTERRUPTED;
            sum->skipped -= st == SB_STATUS_SKIPPED;
            sum->unstable -= !strcmp(sb_table_get(&t, r, "stable"), "no");
            dropped = true;
            continue;
        }
        sb_csv_line(&rows, t.lines[r]);
    }
    sb_table_free(&t);
    sb_csv_free(&sum->rows);
    sum->rows = rows;
    return dropped;
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

bool sb_columns_write(const char *dir, sb_err *err) {
    sb_csv c = {0};
    sb_columns_csv(&c);
    char path[4200];
    snprintf(path, sizeof path, "%s/columns.csv", dir);
    bool ok = sb_write_file_atomic(path, c.buf, c.len, err);
    sb_csv_free(&c);
    return ok;
}
