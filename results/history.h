/* history.h - results sets kept over the nights, and the changes found in
 * them. The storage (SQLite: the file, its schema and its queries) is
 * history_store.h's; this is what the nights mean.
 *
 * A night is one results set (a run's, a batch's or a merge of shards): its
 * meta, its summary rows with every numeric column, and each run's per-frame
 * CSV. A series is what `compare` joins runs by (scene, path, technique and
 * canonical parameters, a sized light, the submission), on one host and
 * renderer at one size, over the nights. */
#pragma once
#include <stdbool.h>
#include <stdio.h>

#include "history_store.h"
#include "series.h"
#include "table.h"

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
    sb_series series;
    char key[4096];             /* the series' key (sb_series_key) */
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
/* Short names of series [0..n) (each malloc'd): the parameters every series of
 * the same technique shares are left out, and the host unless there are several. */
char **sb_history_labels(const sb_series *series, int n);
/* Prints changes as a table (format: SB_OUTPUT_TEXT or _CSV of compare.h). */
void sb_history_print_changes(const sb_history_change *c, int n, int format, FILE *out);
/* A series' points of a metric (by its name in the column table), oldest first; returns how many (free *out), or -1. */
int sb_history_points(sb_history *h, const sb_series *series, const char *metric, sb_history_point **out,
                      sb_err *err);

/* ---- annotations, and what changed on the machine ---- */

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
/* Whether a note is about a series (its key and its label). */
bool sb_history_note_matches(const sb_history_note *n, const char *key, const char *label);

/* `history check DIR`: each ok run of the results set in dir against its
 * series' last `nights` nights with the detector's noise model (the metrics
 * of q, else the history's defaults). Prints a table; returns how many
 * figures lie beyond the band on the worse side, or -1. */
int sb_history_check(sb_history *h, const char *dir, const sb_history_query *q, int nights, FILE *out, sb_err *err);
