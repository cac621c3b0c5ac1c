/* history_store.h - the results history's storage: one SQLite file, its
 * schema and its queries. The only module that speaks SQL (the layers test
 * holds every other file to asking these); what the nights mean (series,
 * changes, the band of a check) is history.h's.
 *
 * Every write is one transaction; the schema's version is SQLite's
 * user_version and is migrated forward when the file is opened for writing. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "series.h"
#include "util.h"

#define SB_HISTORY_SCHEMA 5

typedef struct sb_history sb_history;

/* Opens (creating and migrating when `write`) the history at path. A file
 * made by a newer shadowbench is refused; so is a missing one when reading.
 * A file this call created is removed again when the open fails, so a
 * refused command leaves nothing behind. */
sb_history *sb_history_open(const char *path, bool write, sb_err *err);
void sb_history_close(sb_history *h);
/* The default file: $SB_HISTORY, else history.sqlite in the default results folder. */
const char *sb_history_default_path(const char *default_out, char *buf, size_t len);
/* The file's path as opened. */
const char *sb_history_path(const sb_history *h);
/* Removes the file when the history made it and nothing was ever stored in it
 * (a refused `history add` leaves no history behind where none was). */
void sb_history_discard_if_new(sb_history *h);

/* ---- adding a night ---- */

/* A night as stored: the set's fields, then its runs one by one. */
typedef struct sb_history_night_in {
    const char *set_key, *dir, *date, *host, *renderer, *version, *commit, *header, *meta, *added;
    int images;
} sb_history_night_in;
typedef struct sb_history_run_in {
    const sb_series *series;           /* kept in typed columns, one a field */
    const char *run_id, *status, *reason, *stable, *warnings, *line;
    int run_index;
    int nmetrics;
    const char *const *metric_names;   /* nmetrics numeric cells of the row */
    const double *metric_values;
    const char *frames_csv;            /* the run's per-frame CSV (NULL: none) */
} sb_history_run_in;

/* The night already stored under set_key (0: none), or -1 on a database error. */
long long sb_history_night_of_set(sb_history *h, const char *set_key, sb_err *err);
/* One transaction: begin, the night, its runs, commit (rollback on any failure). */
bool sb_history_begin(sb_history *h, sb_err *err);
long long sb_history_insert_night(sb_history *h, const sb_history_night_in *n, sb_err *err);   /* its id, or -1 */
bool sb_history_insert_run(sb_history *h, long long night, const sb_history_run_in *r, sb_err *err);
bool sb_history_commit(sb_history *h, sb_err *err);
void sb_history_rollback(sb_history *h);

/* ---- reading ---- */

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
/* The stored series in the order of their key texts (free() the array); NULL with *n 0 when there are none. */
sb_series *sb_history_series(sb_history *h, int *n);

/* One figure of a metric: a night of a series (the ok runs only). */
typedef struct sb_history_point {
    long long night;
    char date[32], commit[64];
    double value, ci;           /* ci: NaN when the metric has none */
    bool stable;
} sb_history_point;
/* A series' points of a metric (its centre column and CI column; ci "" none), oldest first; returns how many (free
 * *out), or -1. */
int sb_history_points_of(sb_history *h, const sb_series *series, const char *center, const char *ci,
                         sb_history_point **out, sb_err *err);
/* Every ok run's figure of a metric from the nights dated `since` on (NULL: all), ordered by series (their key
 * texts), then night date: fn is called once a figure, with its series. */
bool sb_history_each_figure(sb_history *h, const char *center, const char *ci, const char *since,
                            void (*fn)(const sb_series *series, const sb_history_point *p, void *arg), void *arg,
                            sb_err *err);

/* NIGHT|COMMIT: a night's id, else the first night that ran a commit starting
 * with `what` (4 characters or more). 0 when none, -1 on a database error. */
long long sb_history_find_night(sb_history *h, const char *what, sb_err *err);

/* ---- annotations ---- */

typedef struct sb_history_annotation {
    long long night;
    char date[32], commit[64], series[256], text[2048];
    bool accept;
} sb_history_annotation;
/* Adds a note to a night: 1 added, 0 the night already had the same note (series, text, accept), -1 *err. */
int sb_history_store_annotation(sb_history *h, long long night, const char *commit, const char *series,
                                const char *text, bool accept, sb_err *err);
/* Every annotation, by night date; returns how many (free *out), or -1. */
int sb_history_annotations(sb_history *h, sb_history_annotation **out, sb_err *err);
