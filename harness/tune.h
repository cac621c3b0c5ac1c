/* tune.h - `shadowbench tune`: which technique and settings to ship for a
 * scene and path.
 *
 *   shadowbench tune SCENE [PATH] [SPEC...] --max-err E | --budget-ms B [--max-flicker F]
 *                    [--techniques LIST] [--time-limit D] [--seed N] [--resume DIR]
 *
 * With --max-err: the cheapest setting (median gpu_ms) whose mean err_rate is
 * at most E; with --budget-ms: the most accurate one whose median gpu_ms is at
 * most B; with --max-flicker F as well, only settings whose mean flicker_rate
 * (error.md, Flicker) is at most F meet the bound. The candidates are the SPECs' grids, or every technique of LIST (by
 * default every technique but `none` and `raycast`) over tune's axes (res,
 * cascades, lambda, filter: see tune.c). The search is successive halving:
 * every candidate measured on a few frames of the path, the promising ones on
 * more, the finalists on all of them in five interleaved passes, so that the
 * search stays within a quarter of the grid's frames besides the leaders'
 * passes; the reference is cast once per camera and shared (the frames of a
 * short rung are frames of the long ones). The answer says how much better the
 * choice is than the next best within the bound, with its 95 % CI from the
 * paired passes, or that the two tie within the noise and what broke the tie. */
#pragma once
#include "run.h"

enum { SB_TUNE_FLICKER, SB_TUNE_FLIP, SB_TUNE_SIDES };

typedef struct sb_tune_cmd {
    const char *scene, *path;           /* path NULL: auto */
    const char *const *specs;           /* the grid as specs (NULL: the default axes) */
    int nspecs;
    const char *techniques;             /* --techniques a,b,c (NULL: all but none and raycast) */
    double max_err, budget_ms;          /* exactly one > 0 */
    /* > 0: a setting also keeps the mean of a side figure within it: [SB_TUNE_FLICKER] flicker_rate (--max-flicker),
       [SB_TUNE_FLIP] flip_mean (--max-flip) */
    double max_side[2];
    double max_mb;                      /* > 0: a setting's shadow storage (shadow_mb) stays within it, MiB */
    double time_limit_s;                /* 0: none */
    const sb_run_opts *opts;            /* frames: the full measurement; seed: the plan's */
    const char *out, *resume;           /* results base folder; or a tune folder to resume */
    const char *identity;               /* the command's "set: " lines (sb_cli_set_identity): the folder's `meta`,
                                           and what --resume must match */
} sb_tune_cmd;

/* Runs the search and prints the recommendation, the Pareto front and a batch
 * line; writes tune.csv, front.html (the report's chart), tune.bench and each rung's results under
 * OUT/tune-SCENE/<UTC time>/. Returns 0 (a recommendation), 1 (nothing met
 * the bound, or a failure) or 2 (bad input). */
int sb_tune_main(const sb_tune_cmd *cmd);
