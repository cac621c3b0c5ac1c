/* columns.h - the CSV contract: one table of per-frame columns and one of
 * per-run (summary) columns, each row a name and a getter. Headers, rows,
 * `compare`'s metric lookup and `shadowbench columns` (columns.csv beside
 * every results set) are all produced from these two tables: adding a column
 * is adding one row to columns.c.
 *
 * A per-run column is either a scalar (run_id, load_ms, ...) or a series: a
 * per-frame column summarised by a set of statistics, named
 * <frame column>_<statistic> (gpu_ms_median, err_rate_p95, ...). */
#pragma once
#include "stability.h"
#include "csv.h"
#include "error.h"
#include "stage.h"
#include "timing.h"

typedef struct sb_frame_rec {
    int frame, repeat;          /* path frame, repetition of the path */
    int seq;                    /* the frame's sequence number in its technique instance */
    double progress;
    double start_s;             /* when the frame began, seconds since the process started */
    double gpu_clock_mhz;       /* the graphics clock at the frame's end (NaN: not readable) */
    uint64_t throttle;          /* clock event (throttle) reason bits then */
    sb_counters counters;
    double cpu_ms, wall_ms;
    double anim_ms;             /* posing the scene at the frame's time (NaN: nothing moves) */
    bool evaluated;
    bool untimed;               /* a frame of a run that times nothing (another renderer's, `score`): only the frame
                                   and its error figures are known */
    sb_error_metrics err;
} sb_frame_rec;

/* A run's status, ordered by severity (the summary's `status` column holds its name). */
typedef enum sb_status {
    SB_STATUS_OK,
    SB_STATUS_SKIPPED,          /* not supported here (a reason says why); nothing to measure */
    SB_STATUS_INTERRUPTED,      /* SIGINT/SIGTERM stopped it; --resume renders it again */
    SB_STATUS_FAILED,
    SB_STATUS_COUNT
} sb_status;
extern const char *const sb_status_names[SB_STATUS_COUNT];
/* The status a summary's cell names; a name that is none of them reads as failed (the most severe). */
sb_status sb_status_of(const char *name);

typedef struct sb_run_info {
    const char *run_id, *scene, *path, *technique, *params, *backend, *renderer, *timing, *reason;
    sb_status status;
    const char *clocks;         /* "free", "locked at N MHz" */
    const char *order;          /* --order */
    const char *submit;         /* --submit: "direct", "indirect" */
    const char *anim;           /* what of the scene's clips plays (sb_scene.anim; NULL or "": the default) */
    uint64_t seed;              /* shuffle's seed (0: none) */
    const char *stable;         /* "yes", "no", "" (not measured) */
    char unstable_reason[512];
    double calib_ms_before, calib_ms_after;
    int run_index;              /* position in the expanded matrix */
    int attempt;                /* which attempt of the run the figures are (1; 2 and on: run again, unstable) */
    int frames, warmup, width, height, repeats;
    double target_ci;           /* percent, 0: none */
    uint64_t scene_triangles;
    double load_ms, run_wall_s, frames_wall_ms;   /* frames: every rendered frame, warm-up included */
    double shadow_mb;           /* the shadow storage the run holds (sb_params_shadow_bytes), MiB */
    double eval_s;              /* wall time of the untimed evaluation pass (its frames, twins, reference) */
    double ref_refit_ms;        /* a moving scene: the reference's refit to a pose, mean (NaN: none) */
    char warnings[512];         /* what the tool cannot stand behind in an ok run ("; "-separated, "" if nothing) */
    char replayed[64];          /* the test seams its timings came from ("timings", "frame-costs"; "" measured) */
    char auto_params[160];      /* values calibrated for "auto" parameters ("bias=0.5:normal=0.125"; "" if none) */
    char light[1200];           /* the light's size when it has one ("sun 0.53 deg, 64 rays"; "" a light of no size) */
    char run_options[640];      /* the identity options without a column of their own ("--sun 30,45"; "": defaults) */
} sb_run_info;

/* Adds a note to the run's warnings. */
void sb_run_warn(sb_run_info *info, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Marks the run's timings as replayed by a test seam ("timings", "frame-costs"): the replayed column. */
void sb_run_mark_replayed(sb_run_info *info, const char *what);

/* A cell of a row: empty, an integer, a number (%.6g) or text. */
typedef enum sb_cell_kind { SB_CELL_EMPTY, SB_CELL_INT, SB_CELL_NUM, SB_CELL_STR } sb_cell_kind;
typedef struct sb_cell {
    sb_cell_kind kind;
    long long i;
    double num;
    const char *str;
} sb_cell;

/* What a per-frame column reads. */
typedef struct sb_frame_row {
    const sb_frame_rec *rec;
    const sb_stage_times *t;
    unsigned stages;            /* the run's stages: SB_STAGE_BIT(slot) each (sb_technique_stage_mask) */
} sb_frame_row;

/* What a per-run column reads: the run and its n measured frames (none when
 * it failed or was skipped). */
typedef struct sb_run_row {
    const sb_run_info *info;
    const sb_frame_rec *recs;
    const sb_stage_times *times;
    int n;
    unsigned stages;
} sb_run_row;

/* The statistics (SB_STAT_*) and a column's uses (SB_USE_*, SB_LOWER_WORSE) are techniques/stage.h's: a
 * technique's own counters (sb_counter_def) declare theirs with them. A column's own flag: */
enum {
    SB_COL_STAGE_TIME = 1u << 0,    /* a per-frame stage time (<stage>_ms): plots stack these */
};
extern const char *const sb_stat_names[SB_STAT_COUNT];   /* "mean", "median", ... in bit order */

/* What a column stands for, where a consumer needs one figure of a kind
 * (tune's time and error, the report's fronts and memory budget): the one
 * column of the table with that role. */
typedef enum sb_col_role {
    SB_ROLE_NONE,
    SB_ROLE_TIME,               /* the frame time (gpu_ms) */
    SB_ROLE_ERROR,              /* the shadow error against the reference (err_rate) */
    SB_ROLE_FLICKER,            /* the flicker of the twins (flicker_rate) */
    SB_ROLE_MEMORY,             /* the shadow storage a run holds (shadow_mb) */
    SB_ROLE_PERCEPTUAL,         /* the error as a viewer sees it (flip_mean, with --flip) */
    SB_ROLE_COUNT
} sb_col_role;

/* A per-frame column. With stats, it is also a metric of the summary: the
 * series `<name>_<stat>` for each statistic (one row declares both). */
typedef struct sb_frame_col {
    const char *name;
    sb_cell (*get)(const sb_frame_row *r, int arg);
    int arg;
    unsigned flags;             /* SB_COL_STAGE_TIME, SB_USE_*, SB_LOWER_WORSE */
    const char *doc;
    unsigned stats;             /* the summary's statistics of it (SB_STAT_* bits; 0: not in the summary) */
    const char *unit;           /* "ms", "share", "count", ... (NULL: not a number) */
    sb_col_role role;
    const char *chart;          /* the report's run page draws it in the chart of this title (NULL: none) */
    const sb_stage_def *stage;  /* a stage's column (its time, its draws): arg is the stage's slot */
} sb_frame_col;

/* A per-run column of the summary. The series rows (get NULL, stats set) are
 * made from the frame columns that have stats, where the run table's one
 * SB_RUN_SERIES row stands. */
typedef struct sb_run_col {
    const char *name;           /* a scalar column, or the frame column a series summarises */
    sb_cell (*get)(const sb_run_row *r, int arg);   /* NULL: a series */
    int arg;
    unsigned stats;             /* a series: SB_STAT_* bits */
    unsigned flags;
    const char *doc;
    const char *unit;           /* a scalar that is a metric: its unit (NULL: not a metric) */
    sb_col_role role;
} sb_run_col;

/* The per-frame columns in order (every technique's own counters and every declared stage's time among them; a table
 * made once, in static storage). */
const sb_frame_col *sb_frame_cols(int *count);
/* The summary's columns in order, the series expanded (a table built once, in static storage). */
const sb_run_col *sb_run_cols(int *count);

void sb_columns_frame_header(sb_csv *c);
void sb_columns_frame_row(sb_csv *c, const sb_frame_rec *r, const sb_stage_times *t, unsigned stages);
void sb_columns_summary_header(sb_csv *c);
/* recs/times: the n measured frames (NULL for a run that failed or was skipped). */
void sb_columns_summary_row(sb_csv *c, const sb_run_info *info, unsigned stages, const sb_frame_rec *recs,
                           const sb_stage_times *times, int n);
/* The column table as CSV (scope, name, kind, statistics, flags, doc): `shadowbench columns`, columns.csv. */
void sb_columns_csv(sb_csv *c);
/* The same table as markdown (`shadowbench columns --format markdown`): the
 * generated part of docs/csv.md, which the csv unit test holds to it. */
void sb_columns_markdown(FILE *out);

/* How a summary metric is read (compare): a series with a median and a
 * confidence interval is a timing (centre: median; separation: mean ± ci95),
 * another series its mean, else the scalar column itself. Returns false for a
 * name the table does not have. */
typedef struct sb_metric_cols {
    char center[96], mean[96], ci[96];   /* column names; ci empty when the metric has none */
    bool lower_worse;                    /* SB_LOWER_WORSE */
    const char *unit;
} sb_metric_cols;
bool sb_columns_metric(const char *name, sb_metric_cols *out);
/* The metrics a command uses by default (use: one SB_USE_* bit), in table order; returns how many (<= max). */
int sb_columns_default_metrics(unsigned use, const char **out, int max);
/* Every metric (a series, or a scalar with a unit), in table order; returns how many (<= max). */
int sb_columns_metrics(const char **out, int max);
/* The column with a role: its name (gpu_ms: a frame column's, or a run column's). */
const char *sb_columns_role(sb_col_role role);
/* A statistic of the role's series (gpu_ms_median for SB_STAT_MEDIAN); a run column: its name. */
void sb_columns_role_stat(sb_col_role role, unsigned stat, char *out, size_t len);
/* The summary columns the report's night table shows (SB_USE_NIGHT: a series' centre statistic, or the
 * scalar), in table order; returns how many (<= max); names in static storage. */
int sb_columns_night(const char **out, int max);

/* Relative half-width (percent) of the 95% confidence interval of the mean
 * gpu_ms. With two or more complete repetitions of the path (per_repeat frames
 * each) the samples are the repetitions' means: that measures how well the
 * path's time is known, not how much frames differ along the path. With one,
 * the samples are the frames. */
double sb_columns_gpu_ci_pct(const sb_stage_times *times, int n, int per_repeat);
/* A frame's gpu_ms: the sum of its measured stages. */
double sb_columns_gpu_ms(const sb_stage_times *t);

/* The summary rows of one invocation (summary.csv), rewritten atomically
 * after every run. */
typedef struct sb_summary {
    char *path;
    sb_csv rows;
    int count, failed, skipped, unstable, interrupted;
    int rerun, recovered;       /* runs run again for being unstable; of them, stable at a later attempt */
    double timed_gpu_ms;        /* the measured frames' GPU time, summed over the runs added */
    uint64_t ref_rays;          /* reference rays the runs cast */
    int ref_reused;             /* evaluated frames whose reference was reused */
    int ref_background;         /* evaluated frames whose reference was cast in the background */
    double *calib;              /* the runs' calib_ms_before so far (the batch median) */
    int ncalib;
} sb_summary;

void sb_summary_open(sb_summary *sum, const char *path);
/* Records one run: its row, counted by info->status; recs/times as sb_columns_summary_row. */
void sb_summary_add_outcome(sb_summary *sum, const sb_run_info *info, unsigned stages, const sb_frame_rec *recs,
                            const sb_stage_times *times, int n);
/* Notes a run's probe for the batch median (NaN ignored). */
void sb_summary_add_calib(sb_summary *sum, double calib_ms);
/* A row kept as it was from an earlier summary (resume), counted by its status. */
void sb_summary_add_line(sb_summary *sum, const char *line, sb_status status);
bool sb_summary_flush(sb_summary *sum, sb_err *err);
/* The set's ok runs in order, for the re-run plan (stability.h): ids[i] (strdup'd) and runs[i] (its wall time and
 * whether it ended unstable); both arrays malloc'd. */
int sb_summary_rerun_runs(const sb_summary *sum, char ***ids, sb_rerun_run **runs);
/* Takes a run's row out (it runs again); its counts with it. False when there is none. */
bool sb_summary_drop(sb_summary *sum, const char *run_id);
/* Whether the run's row says stable=yes. */
bool sb_summary_stable(const sb_summary *sum, const char *run_id);
void sb_summary_free(sb_summary *sum);
/* Writes DIR/columns.csv (sb_columns_csv): a results set describes its own columns. */
bool sb_columns_write(const char *dir, sb_err *err);
