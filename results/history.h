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

#define SB_HISTORY_SCHEMA 3

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
    bool regression;            /* worse (up, or down for a SB_LOWER_WORSE metric) */
    bool recent;                /* starts in one of the newest `recent` nights of its host */
    bool accepted;              /* an annotation of its night (and series) with --accept says it was meant */
    char note[1024];            /* the annotations of its night (and series), "; " between */
    char machine[1024];         /* what changed on the machine that night too ("" nothing) */
} sb_history_change;

typedef struct sb_history_query {
    const char *metrics[32];    /* none: the column table's SB_USE_HISTORY metrics */
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
/* Field k (0 host, 1 renderer, 2 scene, 3 path, 4 WxH, 5 technique, 6 params) of a series. */
void sb_history_series_field(const char *series, int k, char *out, size_t len);
/* Short names of series[0..n) (each malloc'd): the parameters every series of
 * the same technique shares are left out, and the host unless there are several. */
char **sb_history_labels(char *const *series, int n);
/* Prints changes as a table (format: SB_OUTPUT_TEXT or _CSV of compare.h). */
void sb_history_print_changes(const sb_history_change *c, int n, int format, FILE *out);

/* ---- what the report asks (no SQL outside history.c) ---- */

/* A night and its runs' counts. */
typedef struct sb_history_night {
    long long id;
    char date[32], host[256], commit[64], renderer[256], version[64], dir[4096];
    char *header, *meta;        /* the summary's header line and the meta file (malloc'd) */
    int runs, ok, failed, unstable, warned;
} sb_history_night;
/* Every night, oldest first; returns how many (free with sb_history_nights_free), or -1. */
int sb_history_nights(sb_history *h, sb_history_night **out, sb_err *err);
void sb_history_nights_free(sb_history_night *n, int count);
/* A night's summary as it was written (its header, then its rows in run order), as CSV text (malloc'd); NULL on failure. */
char *sb_history_night_summary(sb_history *h, const sb_history_night *night, sb_err *err);
/* A night's per-frame CSVs, one call of fn a run. */
bool sb_history_night_frames(sb_history *h, long long night, void (*fn)(const char *run_id, const char *csv, void *arg),
                             void *arg, sb_err *err);

/* One night of a series, for one metric (the ok runs only). */
typedef struct sb_history_point {
    long long night;
    char date[32], commit[64];
    double value, ci;           /* ci: NaN when the metric has none */
    bool stable;
} sb_history_point;
/* A series' points of a metric, oldest first; returns how many (free *out), or -1. */
int sb_history_points(sb_history *h, const char *series, const char *metric, sb_history_point **out, sb_err *err);

/* ---- annotations, and what changed on the machine ---- */

/* NIGHT|COMMIT: a night's id, else the first night that ran a commit starting
 * with `what` (4 characters or more). 0 when none, -1 on a database error. */
long long sb_history_find_night(sb_history *h, const char *what, sb_err *err);
/* Keeps an annotation of night (commit: as the user named it; series: a
 * pattern, "" for every series). An accepted one says a regression starting
 * on that night was meant: `regressions` lists it as accepted, exit 0. */
bool sb_history_annotate(sb_history *h, long long night, const char *commit, const char *series, const char *text,
                         bool accept, sb_err *err);

typedef struct sb_history_note {
    long long night;
    char date[32], commit[64];
    char series[256];           /* a pattern (fnmatch or a substring of the series or its label); "": every series */
    char text[2048];
    char aside[2048];           /* machine: how a change starting that night says it ("the driver changed here too: ...") */
    bool accept;                /* the change starting on this night was meant */
    bool machine;               /* automatic: the night's machine or build differs from its host's night before
                                   (renderer, driver, kernel, CPU, cores, clocks, build options) */
} sb_history_note;
/* The machine changes, night by night, then the annotations; returns how many (free *out), or -1. */
int sb_history_notes(sb_history *h, sb_history_note **out, sb_err *err);
/* Whether a note is about a series (its full name and its label). */
bool sb_history_note_matches(const sb_history_note *n, const char *series, const char *label);

/* `history check DIR`: each ok run of the results set in dir against its
 * series' last `nights` nights with the detector's noise model (the metrics
 * of q, else the history's defaults). Prints a table; returns how many
 * figures lie beyond the band on the worse side, or -1. */
int sb_history_check(sb_history *h, const char *dir, const sb_history_query *q, int nights, FILE *out, sb_err *err);
