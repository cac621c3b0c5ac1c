/* history.h - results sets kept over the nights in one SQLite file, and the
 * changes found in them.
 *
 * A night is one results set (a run's, a batch's or a merge of shards): its
 * meta, its summary rows with every numeric column, and each run's per-frame
 * CSV. A series is what `compare` joins runs by (scene, path, technique and
 * canonical parameters), on one host and renderer at one size, over the
 * nights. Every write is one transaction; the schema's version is SQLite's
 * user_version and is migrated forward when the file is opened. */
#pragma once
#include <stdbool.h>
#include <stdio.h>

#include "util.h"

#define SB_HISTORY_SCHEMA 2

typedef struct sb_history sb_history;

/* Opens (creating and migrating when `write`) the history at path. A file
 * made by a newer shadowbench is refused. */
sb_history *sb_history_open(const char *path, bool write, sb_err *err);
void sb_history_close(sb_history *h);
/* The default file: $SB_HISTORY, else history.sqlite in the default results folder. */
const char *sb_history_default_path(const char *default_out, char *buf, size_t len);

typedef struct sb_history_added {
    long long night;        /* its id */
    bool existed;           /* the same set was already in: nothing changed */
    int runs, frames_files;
} sb_history_added;

/* Adds the results set in dir as one night, in one transaction. */
bool sb_history_add(sb_history *h, const char *dir, sb_history_added *out, sb_err *err);

/* The nights, oldest first: id, date, host, commit, runs, folder. */
bool sb_history_list(sb_history *h, FILE *out, sb_err *err);

typedef struct sb_history_change {
    char series[1024];          /* host | renderer | scene | path | WxH | technique | params */
    char label[512];            /* scene[/path] technique[:the parameters that tell it from the technique's other
                                   series] WxH[ @host when the history has several] */
    char metric[64];
    long long night_before, night_after;   /* the last night before and the first after */
    char date_after[32], commit_before[64], commit_after[64];
    double before, after, rel, z, p;
    bool regression;            /* worse (every metric: higher is worse) */
    bool recent;                /* starts in one of the newest `recent` nights of its host */
} sb_history_change;

typedef struct sb_history_query {
    const char *metrics[32];    /* none: gpu_ms, final_ms, cascade_ms, draw_calls, shadow_draw_calls, err_rate */
    int nmetrics;
    const char *since;          /* nights from this date (YYYY-MM-DD...) on; NULL: all */
    int recent;                 /* 0: 3 */
    double noise_floor_pct;     /* timings: the least night-to-night noise assumed; 0: 1 on a GPU, 5 on a
                                   software rasterizer (llvmpipe) */
} sb_history_query;

/* Runs change-point detection per series and metric. *out (freed by the
 * caller) gets every change, series by series. Returns how many, or -1. */
int sb_history_changes(sb_history *h, const sb_history_query *q, sb_history_change **out, sb_err *err);
/* The history's series, sorted (free each and the array); NULL with *n 0 when there are none. */
char **sb_history_series(sb_history *h, int *n);
/* Short names of series[0..n) (each malloc'd): the parameters every series of
 * the same technique shares are left out, and the host unless there are several. */
char **sb_history_labels(char *const *series, int n);
/* Prints changes as a table (format: SB_OUTPUT_TEXT or _CSV of compare.h). */
void sb_history_print_changes(const sb_history_change *c, int n, int format, FILE *out);

/* The database, for the report (site.c) to read. */
struct sqlite3 *sb_history_db(sb_history *h);
