/* compare.h - regression checks between results sets, pairs within one set,
 * and merging shard outputs. */
#pragma once
#include <stdio.h>

#include "util.h"

/* How a table is written (--format). */
typedef enum sb_output_format { SB_OUTPUT_TEXT, SB_OUTPUT_CSV, SB_OUTPUT_MARKDOWN } sb_output_format;

typedef struct sb_compare_opts {
    const char *metrics[32];    /* none: the column table's SB_USE_COMPARE metrics (SB_USE_PAIR with pair) */
    int nmetrics;
    double threshold_pct;       /* default 5 */
    int format;
    const char *pair;           /* "technique=pssm,sdsm" or "layered=off,gs"; NULL for BASE/NEW */
} sb_compare_opts;

/* Compares NEW against BASE (results folders or summary.csv files): runs are
 * joined by scene, path, technique and parameters (in any order). A metric
 * regresses when it is worse by more than the threshold and, for timings, the
 * two 95% confidence intervals of the mean do not overlap. A timing of a pair
 * in which either run is marked stable=no is UNSTABLE instead: neither a
 * regression nor ok (*unstable counts them; may be NULL). Returns the number
 * of regressions, or -1 with err set. */
int sb_compare(const char *base, const char *next, const sb_compare_opts *o, FILE *out, int *unstable, sb_err *err);
/* Pairs runs within one results set that differ only in the given parameter
 * (or technique, matching the parameters both techniques have). Returns the
 * number of pairs, or -1. */
int sb_compare_pairs(const char *dir, const sb_compare_opts *o, FILE *out, sb_err *err);

/* The same pairs as a table in memory (what sb_compare_pairs prints; the report's pair tables): the column
 * names, which are numbers, the rows' cells, the parameters every pair shares, and a caption. Returns the number
 * of pairs (free with sb_pair_table_free), or -1. */
#define SB_PAIR_COLS 40
typedef struct sb_pair_table {
    char head[SB_PAIR_COLS][384];
    bool numeric[SB_PAIR_COLS];
    int ncols, nrows;
    char (*cells)[SB_PAIR_COLS][160];
    char shared[2048];
    char caption[1024];
} sb_pair_table;
struct sb_table;
int sb_compare_pair_table(const struct sb_table *summary, const sb_compare_opts *o, sb_pair_table *out, sb_err *err);
void sb_pair_table_free(sb_pair_table *t);
struct sb_table;
/* Merges results folders (shards) into out_dir: per-run CSVs copied, summary
 * rows in matrix order (run_index). */
bool sb_merge(const char *const *dirs, int n, const char *out_dir, sb_err *err);
