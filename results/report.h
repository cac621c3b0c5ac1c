/* report.h - the CSV contract: per-frame rows and the per-run summary row. */
#pragma once
#include "csv.h"
#include "error.h"
#include "gpu.h"
#include "timing.h"

typedef struct sb_frame_rec {
    int frame, repeat;          /* path frame, repetition of the path */
    double progress;
    sb_counters counters;
    double cpu_ms, wall_ms;
    bool evaluated;
    sb_error_metrics err;
} sb_frame_rec;

void sb_report_frame_header(sb_csv *c);
void sb_report_frame_row(sb_csv *c, const sb_frame_rec *r, const sb_stage_times *t, unsigned stages);

typedef struct sb_run_info {
    const char *run_id, *scene, *path, *technique, *params, *backend, *renderer, *timing, *status, *reason;
    int run_index;              /* position in the expanded matrix */
    int frames, warmup, width, height, repeats;
    double target_ci;           /* percent, 0: none */
    uint64_t stalls, scene_triangles;
    double load_ms, run_wall_s, frames_wall_ms;   /* frames: every rendered frame, warm-up included */
    uint64_t rays;
    double ray_ms;
} sb_run_info;

void sb_report_summary_header(sb_csv *c);
/* recs/times: the n measured frames (NULL for a run that failed or was skipped). */
void sb_report_summary_row(sb_csv *c, const sb_run_info *info, unsigned stages, const sb_frame_rec *recs,
                           const sb_stage_times *times, int n);
/* Relative half-width (percent) of the 95% confidence interval of the mean
 * gpu_ms. With two or more complete repetitions of the path (per_repeat frames
 * each) the samples are the repetitions' means: that measures how well the
 * path's time is known, not how much frames differ along the path. With one,
 * the samples are the frames. */
double sb_report_gpu_ci_pct(const sb_stage_times *times, int n, int per_repeat);
