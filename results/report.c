/* report.c - per-frame and summary CSV rows. A stage a technique does not
 * have, or a metric not measured for a frame, is an empty field, not 0. */
#include "report.h"

#include <stdlib.h>
#include <string.h>

#include "stats.h"

/* stages that draw (per-stage draw-call columns) */
static bool draws_in(int s) { return s != SB_STAGE_MINMAX && s != SB_STAGE_RAYS; }

static const char *const error_cols[] = {"err_rate", "err_false_shadow", "err_false_lit", "vis_mae",
                                         "res_err_mean", "res_err_p95", "texel_px_p95"};

static double error_field(const sb_error_metrics *e, int k) {
    const double v[] = {e->err_rate, e->false_shadow, e->false_lit, e->vis_mae,
                        e->res_err_mean, e->res_err_p95, e->texel_px_p95};
    return v[k];
}

void sb_report_frame_header(sb_csv *c) {
    const char *cols[] = {"frame", "repeat", "progress", "draw_calls", "shadow_draw_calls", "triangles",
                          "shadow_triangles", "cascades_rendered", "cascades_skipped", "warp_fallbacks"};
    for (size_t i = 0; i < SB_COUNT(cols); i++) sb_csv_str(c, cols[i]);
    char name[40];
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        snprintf(name, sizeof name, "%s_ms", sb_stage_names[s]);
        sb_csv_str(c, name);
    }
    sb_csv_str(c, "gpu_ms");
    sb_csv_str(c, "cpu_ms");
    sb_csv_str(c, "wall_ms");
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        if (!draws_in(s)) continue;
        snprintf(name, sizeof name, "%s_draw_calls", sb_stage_names[s]);
        sb_csv_str(c, name);
    }
    for (int k = 0; k < SB_MAX_CASCADES; k++) {
        snprintf(name, sizeof name, "split_%d", k + 1);
        sb_csv_str(c, name);
    }
    sb_csv_str(c, "eval_pixels");
    for (size_t k = 0; k < SB_COUNT(error_cols); k++) sb_csv_str(c, error_cols[k]);
    sb_csv_end_row(c);
}

static double gpu_ms(const sb_stage_times *t) {
    double sum = 0;
    for (int s = 0; s < SB_STAGE_COUNT; s++)
        if (t->mask & SB_STAGE_BIT(s)) sum += t->ms[s];
    return sum;
}

void sb_report_frame_row(sb_csv *c, const sb_frame_rec *r, const sb_stage_times *t, unsigned stages) {
    sb_csv_int(c, r->frame);
    sb_csv_int(c, r->repeat);
    sb_csv_num(c, r->progress);
    sb_csv_int(c, r->counters.draw_calls);
    sb_csv_int(c, r->counters.shadow_draw_calls);
    sb_csv_int(c, (long long)r->counters.triangles);
    sb_csv_int(c, (long long)r->counters.shadow_triangles);
    if (stages & SB_STAGE_BIT(SB_STAGE_CASCADE)) {
        sb_csv_int(c, r->counters.cascades_rendered);
        sb_csv_int(c, r->counters.cascades_skipped);
        sb_csv_int(c, r->counters.warp_fallbacks);
    } else {
        sb_csv_empty(c);
        sb_csv_empty(c);
        sb_csv_empty(c);
    }
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        if ((stages & SB_STAGE_BIT(s)) && (t->mask & SB_STAGE_BIT(s))) sb_csv_num(c, t->ms[s]);
        else sb_csv_empty(c);
    }
    sb_csv_num(c, gpu_ms(t));
    sb_csv_num(c, r->cpu_ms);
    sb_csv_num(c, r->wall_ms);
    for (int s = 0; s < SB_STAGE_COUNT; s++) {
        if (!draws_in(s)) continue;
        if (stages & SB_STAGE_BIT(s)) sb_csv_int(c, r->counters.stage_draw_calls[s]);
        else sb_csv_empty(c);
    }
    for (int k = 0; k < SB_MAX_CASCADES; k++) {
        if (k < r->counters.split_count) sb_csv_num(c, r->counters.splits[k]);
        else sb_csv_empty(c);
    }
    if (r->evaluated) sb_csv_int(c, r->err.pixels);
    else sb_csv_empty(c);
    for (size_t k = 0; k < SB_COUNT(error_cols); k++) sb_csv_num(c, r->evaluated ? error_field(&r->err, (int)k) : NAN);
    sb_csv_end_row(c);
}

#define N_SUMMARY_STAGES (SB_STAGE_COUNT + 3) /* stages, gpu, cpu, wall */
static const char *summary_stage_name(int k) {
    static const char *extra[] = {"gpu", "cpu", "wall"};
    return k < SB_STAGE_COUNT ? sb_stage_names[k] : extra[k - SB_STAGE_COUNT];
}

static const char *const counter_cols[] = {"draw_calls_mean", "shadow_draw_calls_mean", "shadow_triangles_mean",
                                           "cascades_rendered_mean", "cascades_skipped_mean", "warp_fallbacks_mean"};

void sb_report_summary_header(sb_csv *c) {
    const char *cols[] = {"run_id", "run_index", "scene", "path", "technique", "params", "backend", "renderer", "timing",
                          "frames", "warmup", "width", "height", "status", "reason", "repeats", "target_ci_pct",
                          "gpu_ci_pct", "stalls", "scene_triangles", "load_ms", "run_wall_s", "harness_share"};
    for (size_t i = 0; i < SB_COUNT(cols); i++) sb_csv_str(c, cols[i]);
    for (size_t i = 0; i < SB_COUNT(counter_cols); i++) sb_csv_str(c, counter_cols[i]);
    const char *st[] = {"mean", "median", "p95", "p99", "std", "ci95"};
    char name[64];
    for (int k = 0; k < N_SUMMARY_STAGES; k++)
        for (size_t j = 0; j < SB_COUNT(st); j++) {
            snprintf(name, sizeof name, "%s_ms_%s", summary_stage_name(k), st[j]);
            sb_csv_str(c, name);
        }
    sb_csv_str(c, "error_frames");
    for (size_t k = 0; k < SB_COUNT(error_cols); k++) {
        snprintf(name, sizeof name, "%s_mean", error_cols[k]);
        sb_csv_str(c, name);
        snprintf(name, sizeof name, "%s_p95", error_cols[k]);
        sb_csv_str(c, name);
    }
    sb_csv_str(c, "ref_rays_per_s");
    sb_csv_end_row(c);
}

double sb_report_gpu_ci_pct(const sb_stage_times *times, int n, int per_repeat) {
    double *v = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
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

void sb_report_summary_row(sb_csv *c, const sb_run_info *in, unsigned stages, const sb_frame_rec *recs,
                           const sb_stage_times *times, int n) {
    if (!recs) n = 0;
    sb_csv_str(c, in->run_id);
    sb_csv_int(c, in->run_index);
    sb_csv_str(c, in->scene);
    sb_csv_str(c, in->path);
    sb_csv_str(c, in->technique);
    sb_csv_str(c, in->params);
    sb_csv_str(c, in->backend);
    sb_csv_str(c, in->renderer);
    sb_csv_str(c, in->timing);
    sb_csv_int(c, in->frames);
    sb_csv_int(c, in->warmup);
    sb_csv_int(c, in->width);
    sb_csv_int(c, in->height);
    sb_csv_str(c, in->status);
    sb_csv_str(c, in->reason);
    sb_csv_int(c, n ? in->repeats : 0);
    sb_csv_num(c, in->target_ci > 0 ? in->target_ci : NAN);
    sb_csv_num(c, n ? sb_report_gpu_ci_pct(times, n, in->frames) : NAN);
    sb_csv_int(c, (long long)in->stalls);
    sb_csv_int(c, (long long)in->scene_triangles);
    sb_csv_num(c, in->load_ms);
    sb_csv_num(c, in->run_wall_s);
    sb_csv_num(c, n && in->run_wall_s > 0 ? 1.0 - in->frames_wall_ms / (in->run_wall_s * 1e3) : NAN);
    double *v = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    bool has_cascades = stages & SB_STAGE_BIT(SB_STAGE_CASCADE);
    for (int field = 0; field < (int)SB_COUNT(counter_cols); field++) {
        for (int i = 0; i < n; i++) {
            const sb_counters *k = &recs[i].counters;
            v[i] = field == 0 ? k->draw_calls : field == 1 ? k->shadow_draw_calls : field == 2 ? (double)k->shadow_triangles
                 : field == 3 ? k->cascades_rendered : field == 4 ? k->cascades_skipped : k->warp_fallbacks;
        }
        if (field >= 3 && !has_cascades) sb_csv_empty(c);
        else sb_csv_num(c, n ? sb_stats_compute(v, n).mean : NAN);
    }
    for (int k = 0; k < N_SUMMARY_STAGES; k++) {
        for (int i = 0; i < n; i++) {
            const sb_stage_times *st = &times[i];
            if (k < SB_STAGE_COUNT)
                v[i] = (stages & SB_STAGE_BIT(k)) && (st->mask & SB_STAGE_BIT(k)) ? st->ms[k] : NAN;
            else if (k == SB_STAGE_COUNT) v[i] = gpu_ms(st);
            else if (k == SB_STAGE_COUNT + 1) v[i] = recs[i].cpu_ms;
            else v[i] = recs[i].wall_ms;
        }
        sb_stats st = sb_stats_compute(v, n);
        sb_csv_num(c, st.mean);
        sb_csv_num(c, st.median);
        sb_csv_num(c, st.p95);
        sb_csv_num(c, st.p99);
        sb_csv_num(c, st.std);
        sb_csv_num(c, st.ci95);
    }
    int ne = 0;
    for (int i = 0; i < n; i++) ne += recs[i].evaluated;
    sb_csv_int(c, ne);
    for (size_t k = 0; k < SB_COUNT(error_cols); k++) {
        int m = 0;
        for (int i = 0; i < n; i++)
            if (recs[i].evaluated) v[m++] = error_field(&recs[i].err, (int)k);
        sb_stats st = sb_stats_compute(v, m);
        sb_csv_num(c, st.mean);
        sb_csv_num(c, st.p95);
    }
    sb_csv_num(c, in->ray_ms > 0 ? in->rays / (in->ray_ms / 1e3) : NAN);
    sb_csv_end_row(c);
    free(v);
}
