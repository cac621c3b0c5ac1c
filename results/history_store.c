/* history_store.c - the results history's SQLite file (history_store.h). */
#include "history_store.h"

#include "columns.h"
#include "runkey.h"
#include "table.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

struct sb_history {
    sqlite3 *db;
    char path[4096];
    bool created;               /* this open made the file */
};

const char *sb_history_default_path(const char *default_out, char *buf, size_t len) {
    const char *env = getenv("SB_HISTORY");
    if (env && *env) snprintf(buf, len, "%s", env);
    else snprintf(buf, len, "%s/history.sqlite", default_out);
    return buf;
}

const char *sb_history_path(const sb_history *h) { return h->path; }

static bool db_fail(sb_history *h, sb_err *err, const char *what) {
    return sb_fail(err, "%s: %s: %s", h->path, what, sqlite3_errmsg(h->db));
}

static bool exec(sb_history *h, const char *sql, sb_err *err) {
    char *msg = NULL;
    if (sqlite3_exec(h->db, sql, NULL, NULL, &msg) == SQLITE_OK) return true;
    sb_fail(err, "%s: %s", h->path, msg ? msg : sqlite3_errmsg(h->db));
    sqlite3_free(msg);
    return false;
}

/* ---- a series' columns ---- */

/* The runs' series columns, in the order sb_series_key joins them (the SQL function sb_series_key takes them so). */
#define SERIES_COLS "host, renderer, scene, path, size, technique, params, light, anim, run_options, indirect"
#define SERIES_COLS_R \
    "r.host, r.renderer, r.scene, r.path, r.size, r.technique, r.params, r.light, r.anim, r.run_options, r.indirect"
#define SERIES_NCOLS 11

/* The series' text fields in SERIES_COLS order (indirect, the last column, is a number): where each lies in
 * sb_series and its room. */
#define SERIES_FIELD(m) {offsetof(sb_series, m), sizeof(((sb_series *)0)->m)}
static const struct { size_t at, len; } series_text[SERIES_NCOLS - 1] = {
    SERIES_FIELD(host), SERIES_FIELD(renderer), SERIES_FIELD(scene), SERIES_FIELD(path), SERIES_FIELD(size),
    SERIES_FIELD(technique), SERIES_FIELD(params), SERIES_FIELD(light), SERIES_FIELD(anim), SERIES_FIELD(run_options),
};

static void copy_col(char *dst, size_t len, sqlite3_stmt *st, int i);

/* Columns [first, first + SERIES_NCOLS) of a row as a series. */
static void read_series(sqlite3_stmt *st, int first, sb_series *s) {
    memset(s, 0, sizeof *s);
    for (int k = 0; k < SERIES_NCOLS - 1; k++) copy_col((char *)s + series_text[k].at, series_text[k].len, st, first + k);
    s->indirect = sqlite3_column_int(st, first + SERIES_NCOLS - 1) != 0;
}

static bool bind_text(sqlite3_stmt *st, int i, const char *s);

/* A series into parameters [first, first + SERIES_NCOLS). */
static bool bind_series(sqlite3_stmt *st, int first, const sb_series *s) {
    for (int k = 0; k < SERIES_NCOLS - 1; k++)
        if (!bind_text(st, first + k, (const char *)s + series_text[k].at)) return false;
    return sqlite3_bind_int(st, first + SERIES_NCOLS - 1, s->indirect) == SQLITE_OK;
}

/* sb_series_key(SERIES_COLS): the key text, what series are ordered by (as schema 3 ordered its one column). */
static void sql_series_key(sqlite3_context *ctx, int n, sqlite3_value **v) {
    sb_series s;
    memset(&s, 0, sizeof s);
    for (int k = 0; k < SERIES_NCOLS - 1 && k < n; k++) {
        const char *t = (const char *)sqlite3_value_text(v[k]);
        snprintf((char *)&s + series_text[k].at, series_text[k].len, "%s", t ? t : "");
    }
    s.indirect = n == SERIES_NCOLS && sqlite3_value_int(v[SERIES_NCOLS - 1]) != 0;
    char key[8192];
    sb_series_key(&s, key, sizeof key);
    sqlite3_result_text(ctx, key, -1, SQLITE_TRANSIENT);
}

/* Schema 4: each run's series put in its columns once, from the run's own summary row (the night's header and the
 * run's line: its scene, path, technique and parameters as the summary wrote them; host and renderer the night's,
 * the row's own renderer where it has one), then the joined text dropped. The joined text is never parsed: a
 * scene named "plane|box" split it one field early. A run whose row cannot be read (no line, no header, a line
 * that is no summary row) is left out of the migrated history with a line naming it and why (the backup beside
 * the file keeps it). */
static bool series_columns(sb_history *h, sb_err *err) {
    sqlite3_stmt *q, *u;
    if (sqlite3_prepare_v2(h->db, "SELECT r.id, r.run_id, r.night, n.header, r.line, n.host, n.renderer FROM runs r "
                           "LEFT JOIN nights n ON n.id = r.night", -1, &q, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading the runs' summary rows");
    if (sqlite3_prepare_v2(h->db, "UPDATE runs SET host = ?1, renderer = ?2, scene = ?3, path = ?4, size = ?5, "
                           "technique = ?6, params = ?7, light = ?8, anim = ?9, indirect = ?10 WHERE id = ?11",
                           -1, &u, NULL) != SQLITE_OK) {
        sqlite3_finalize(q);
        return db_fail(h, err, "preparing the runs' series columns");
    }
    bool ok = true;
    long long *left_out = NULL;
    int nleft = 0;
    while (ok && sqlite3_step(q) == SQLITE_ROW) {
        const char *header = (const char *)sqlite3_column_text(q, 3), *line = (const char *)sqlite3_column_text(q, 4);
        const char *host = (const char *)sqlite3_column_text(q, 5), *night_renderer = (const char *)sqlite3_column_text(q, 6);
        const char *run_id = (const char *)sqlite3_column_text(q, 1);
        char *text = NULL, why[SB_ERR_LEN] = "";
        sb_table t;
        bool parsed = false;
        sb_err e;
        if (!header || !*header || !line || !*line) {
            snprintf(why, sizeof why, "no summary %s kept", !line || !*line ? "line" : "header");
        } else {
            size_t n = strlen(header) + strlen(line) + 3;
            text = sb_xmalloc(n);
            snprintf(text, n, "%s\n%s\n", header, line);
            const char *missing = NULL;
            if (!(parsed = sb_table_parse(&t, "the run's summary row", text, &e))) snprintf(why, sizeof why, "%s", e.msg);
            else if (t.nrows != 1) snprintf(why, sizeof why, "its line holds %d summary rows, not one", t.nrows);
            else if ((missing = sb_run_key_missing(&t, true)))
                snprintf(why, sizeof why, "its row has no '%s' column", missing);
            else if (!*sb_table_get(&t, 0, "scene") || !*sb_table_get(&t, 0, "technique"))
                snprintf(why, sizeof why, "its row names no scene or technique");
        }
        if (why[0]) {
            sb_log("%s: run %s of night %lld: %s: left out of the migrated history (the backup beside it keeps it)",
                   h->path, run_id && *run_id ? run_id : "(no id)", sqlite3_column_int64(q, 2), why);
            left_out = sb_xrealloc(left_out, sizeof *left_out * (size_t)(nleft + 1));
            left_out[nleft++] = sqlite3_column_int64(q, 0);
        } else {
            sb_run_key k;
            sb_run_key_of(&t, 0, &k);
            sb_series se;
            sb_series_of_row(&t, 0, host && *host ? host : "unknown", k.renderer[0] ? k.renderer : night_renderer ? night_renderer : "", &se);
            for (int c = 0; ok && c < SERIES_NCOLS - 2; c++)   /* the text fields, run_options (the last) not yet */
                ok = bind_text(u, 1 + c, (const char *)&se + series_text[c].at);
            ok = ok && sqlite3_bind_int(u, 10, se.indirect) == SQLITE_OK &&
                 sqlite3_bind_int64(u, 11, sqlite3_column_int64(q, 0)) == SQLITE_OK && sqlite3_step(u) == SQLITE_DONE;
            sqlite3_reset(u);
        }
        if (parsed) sb_table_free(&t);
        free(text);
    }
    sqlite3_finalize(q);
    sqlite3_finalize(u);
    for (int i = 0; ok && i < nleft; i++) {
        char sql[256];
        snprintf(sql, sizeof sql, "DELETE FROM metrics WHERE run = %lld; DELETE FROM frames WHERE run = %lld; "
                 "DELETE FROM runs WHERE id = %lld;", left_out[i], left_out[i], left_out[i]);
        ok = exec(h, sql, err);
    }
    free(left_out);
    if (!ok) return db_fail(h, err, "writing the runs' series columns");
    return exec(h, "DROP INDEX runs_series; ALTER TABLE runs DROP COLUMN series;"
                   "CREATE INDEX runs_series ON runs(technique, scene, size);", err);
}

/* The schema, one step a version: step k takes a file from version k-1 to k.
   Version 1 kept the summary rows; 2 added each run's per-frame CSV and the
   night's image count; 3 the annotations (`history annotate`); 4 a run's series in typed columns (host,
   renderer, scene, path, size, technique, sorted params, light, anim, indirect) instead of one joined text,
   each run's text parsed into them once (series_columns); 5 the identity options without a column of their own
   (run_options: "--sun 30,45"; '' for every run before it, as every run then was keyed). */
static bool series_columns(sb_history *h, sb_err *err);
static const struct migration {
    const char *sql;
    bool (*then)(sb_history *h, sb_err *err);   /* what SQL alone cannot do (NULL: nothing) */
} migrations[SB_HISTORY_SCHEMA] = {
    {"CREATE TABLE nights(id INTEGER PRIMARY KEY, set_key TEXT UNIQUE NOT NULL, dir TEXT, date TEXT, host TEXT,"
     " renderer TEXT, version TEXT, git_commit TEXT, header TEXT, meta TEXT, added TEXT);"
     "CREATE TABLE runs(id INTEGER PRIMARY KEY, night INTEGER NOT NULL REFERENCES nights(id), run_id TEXT,"
     " run_index INTEGER, series TEXT, scene TEXT, path TEXT, technique TEXT, params TEXT, size TEXT, status TEXT,"
     " reason TEXT, stable TEXT, warnings TEXT, line TEXT);"
     "CREATE TABLE metrics(run INTEGER NOT NULL, name TEXT NOT NULL, value REAL, PRIMARY KEY(run, name)) WITHOUT ROWID;"
     "CREATE INDEX runs_night ON runs(night);"
     "CREATE INDEX runs_series ON runs(series);", NULL},
    {"CREATE TABLE frames(run INTEGER PRIMARY KEY, csv TEXT);"
     "ALTER TABLE nights ADD COLUMN images INTEGER NOT NULL DEFAULT 0;", NULL},
    {"CREATE TABLE annotations(id INTEGER PRIMARY KEY, night INTEGER NOT NULL REFERENCES nights(id), git_commit TEXT,"
     " series TEXT NOT NULL DEFAULT '', text TEXT NOT NULL, accept INTEGER NOT NULL DEFAULT 0, added TEXT);", NULL},
    {"ALTER TABLE runs ADD COLUMN host TEXT NOT NULL DEFAULT '';"
     "ALTER TABLE runs ADD COLUMN renderer TEXT NOT NULL DEFAULT '';"
     "ALTER TABLE runs ADD COLUMN light TEXT NOT NULL DEFAULT '';"
     "ALTER TABLE runs ADD COLUMN anim TEXT NOT NULL DEFAULT '';"
     "ALTER TABLE runs ADD COLUMN indirect INTEGER NOT NULL DEFAULT 0;", series_columns},
    {"ALTER TABLE runs ADD COLUMN run_options TEXT NOT NULL DEFAULT '';", NULL},
};

static int user_version(sb_history *h) {
    sqlite3_stmt *q;
    int v = -1;
    if (sqlite3_prepare_v2(h->db, "PRAGMA user_version", -1, &q, NULL) == SQLITE_OK) {
        if (sqlite3_step(q) == SQLITE_ROW) v = sqlite3_column_int(q, 0);
        sqlite3_finalize(q);
    }
    return v;
}

static bool migrate(sb_history *h, sb_err *err) {
    int v = user_version(h);
    if (v < 0) return db_fail(h, err, "reading the schema version");
    if (v > SB_HISTORY_SCHEMA)
        return sb_fail(err, "%s: history schema version %d, newer than this shadowbench's %d: use a newer shadowbench",
                       h->path, v, SB_HISTORY_SCHEMA);
    if (v > 0 && v < SB_HISTORY_SCHEMA && strcmp(h->path, ":memory:")) {
        /* an older file is migrated in place, a copy of it as it was beside it first (kept: one a version) */
        char backup[4200];
        snprintf(backup, sizeof backup, "%s.schema-%d.bak", h->path, v);
        sb_err e;
        if (access(backup, F_OK) != 0 && !sb_copy_file(h->path, backup, &e))
            return sb_fail(err, "%s: history schema version %d is migrated to %d with a backup beside it, and the "
                           "backup could not be written: %s", h->path, v, SB_HISTORY_SCHEMA, e.msg);
        sb_log("%s: history schema version %d migrated to %d (as it was: %s)", h->path, v, SB_HISTORY_SCHEMA, backup);
    }
    for (; v < SB_HISTORY_SCHEMA; v++) {
        char sql[256];
        snprintf(sql, sizeof sql, "PRAGMA user_version = %d", v + 1);
        if (!exec(h, "BEGIN IMMEDIATE", err)) return false;
        if (!exec(h, migrations[v].sql, err) || (migrations[v].then && !migrations[v].then(h, err)) ||
            !exec(h, sql, err)) {
            sqlite3_exec(h->db, "ROLLBACK", NULL, NULL, NULL);
            return false;
        }
        if (!exec(h, "COMMIT", err)) return false;
    }
    return true;
}

/* A history opened to read must be this shadowbench's schema. */
static bool check_version(sb_history *h, sb_err *err) {
    int v = user_version(h);
    if (v == SB_HISTORY_SCHEMA) return true;
    return sb_fail(err, "%s: history schema version %d, this shadowbench reads %d (%s)", h->path, v < 0 ? 0 : v,
                   SB_HISTORY_SCHEMA,
                   v < SB_HISTORY_SCHEMA ? "`shadowbench history add` migrates it" : "use a newer shadowbench");
}

static bool make_parent(const char *path, sb_err *err) {
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (!slash || slash == dir) return true;
    *slash = 0;
    return sb_mkdir_p(dir, err);
}

/* sb_status(TEXT): the typed status a summary's cell names (columns.h), so no query compares status names. */
static void sql_status(sqlite3_context *ctx, int n, sqlite3_value **v) {
    (void)n;
    sqlite3_result_int(ctx, (int)sb_status_of((const char *)sqlite3_value_text(v[0])));
}

/* The SQL functions the queries use. */
static bool register_functions(sb_history *h, sb_err *err) {
    /* a run's status is read back as the typed status (sb_status_of), in SQL too: sb_status(r.status) */
    return (sqlite3_create_function(h->db, "sb_status", 1, SQLITE_UTF8 | SQLITE_DETERMINISTIC, NULL, sql_status,
                                    NULL, NULL) == SQLITE_OK ||
            db_fail(h, err, "cannot register sb_status")) &&
           (sqlite3_create_function(h->db, "sb_series_key", SERIES_NCOLS, SQLITE_UTF8 | SQLITE_DETERMINISTIC, NULL,
                                    sql_series_key, NULL, NULL) == SQLITE_OK ||
            db_fail(h, err, "cannot register sb_series_key"));
}

sb_history *sb_history_open(const char *path, bool write, sb_err *err) {
    sb_history *h = sb_xcalloc(1, sizeof *h);
    snprintf(h->path, sizeof h->path, "%s", path);
    struct stat st;
    if (!*path) {   /* SQLite would open a temporary database, stored nowhere */
        sb_fail(err, "an empty history path: name the history's file (--history FILE)");
        free(h);
        return NULL;
    }
    bool exists = stat(path, &st) == 0;
    if (exists && S_ISDIR(st.st_mode)) {
        sb_fail(err, "%s: is a folder, not a history file", path);
        free(h);
        return NULL;
    }
    if (exists && !S_ISREG(st.st_mode)) {   /* a FIFO would be waited on for ever, a device read as a database */
        sb_fail(err, "%s: %s, not a history file", path,
                S_ISFIFO(st.st_mode) ? "a FIFO" : S_ISSOCK(st.st_mode) ? "a socket" : "a device");
        free(h);
        return NULL;
    }
    if (!write && !exists) {
        sb_fail(err, "%s: no history here (%s); `shadowbench history add DIR` makes one", path, strerror(errno));
        free(h);
        return NULL;
    }
    if (write && !make_parent(path, err)) {
        free(h);
        return NULL;
    }
    h->created = write && !exists && strcmp(path, ":memory:");
    int flags = write ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE : SQLITE_OPEN_READONLY;
    bool ok = sqlite3_open_v2(path, &h->db, flags, NULL) == SQLITE_OK || db_fail(h, err, "cannot open");
    if (ok) sqlite3_busy_timeout(h->db, 10000);
    ok = ok && register_functions(h, err);
    /* a file that is not a database fails on its first read */
    ok = ok && exec(h, "SELECT count(*) FROM sqlite_master", err);
    /* an older history opened to read is migrated as a write would (a user who upgrades and opens the report
       gets it), where the file can be written; else said */
    int v = ok && !write ? user_version(h) : SB_HISTORY_SCHEMA;
    if (ok && !write && v > 0 && v < SB_HISTORY_SCHEMA) {
        sqlite3_close(h->db);
        h->db = NULL;
        ok = sqlite3_open_v2(path, &h->db, SQLITE_OPEN_READWRITE, NULL) == SQLITE_OK ||
             sb_fail(err, "%s: history schema version %d, this shadowbench reads %d, and the file cannot be opened "
                     "to migrate it (%s): make it writable, or run `shadowbench history add` where it is", path, v,
                     SB_HISTORY_SCHEMA, h->db ? sqlite3_errmsg(h->db) : "no memory");
        if (ok) sqlite3_busy_timeout(h->db, 10000);
        ok = ok && register_functions(h, err) && migrate(h, err);
    } else {
        ok = ok && (write ? migrate(h, err) : check_version(h, err));
    }
    if (!ok) {
        sb_history_discard_if_new(h);
        sb_history_close(h);
        return NULL;
    }
    return h;
}

void sb_history_close(sb_history *h) {
    if (!h) return;
    if (h->db) sqlite3_close(h->db);
    free(h);
}

void sb_history_discard_if_new(sb_history *h) {
    if (!h->created) return;
    sqlite3_stmt *q;
    bool empty = true;
    if (h->db && sqlite3_prepare_v2(h->db, "SELECT count(*) FROM nights", -1, &q, NULL) == SQLITE_OK) {
        empty = sqlite3_step(q) != SQLITE_ROW || sqlite3_column_int64(q, 0) == 0;
        sqlite3_finalize(q);
    }
    if (!empty) return;
    if (h->db) sqlite3_close(h->db);
    h->db = NULL;
    char side[4200];
    unlink(h->path);
    snprintf(side, sizeof side, "%s-journal", h->path);
    unlink(side);
    h->created = false;
}

/* ---- adding a night ---- */

static bool bind_text(sqlite3_stmt *st, int i, const char *s) {
    return sqlite3_bind_text(st, i, s ? s : "", -1, SQLITE_TRANSIENT) == SQLITE_OK;
}

long long sb_history_night_of_set(sb_history *h, const char *set_key, sb_err *err) {
    sqlite3_stmt *q;
    if (sqlite3_prepare_v2(h->db, "SELECT id FROM nights WHERE set_key = ?", -1, &q, NULL) != SQLITE_OK ||
        !bind_text(q, 1, set_key)) {
        sqlite3_finalize(q);
        return db_fail(h, err, "looking the set up"), -1;
    }
    long long id = sqlite3_step(q) == SQLITE_ROW ? sqlite3_column_int64(q, 0) : 0;
    sqlite3_finalize(q);
    return id;
}

bool sb_history_begin(sb_history *h, sb_err *err) { return exec(h, "BEGIN IMMEDIATE", err); }
bool sb_history_commit(sb_history *h, sb_err *err) { return exec(h, "COMMIT", err); }
void sb_history_rollback(sb_history *h) { sqlite3_exec(h->db, "ROLLBACK", NULL, NULL, NULL); }

/* Prepares sql and binds the texts (NULL-terminated after the count); NULL with err on failure. */
static sqlite3_stmt *prepare_texts(sb_history *h, const char *sql, const char *const *texts, int n, sb_err *err) {
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, sql, -1, &st, NULL) != SQLITE_OK) return db_fail(h, err, "preparing"), NULL;
    for (int i = 0; i < n; i++)
        if (!bind_text(st, i + 1, texts[i])) {
            sqlite3_finalize(st);
            return db_fail(h, err, "binding"), NULL;
        }
    return st;
}

long long sb_history_insert_night(sb_history *h, const sb_history_night_in *n, sb_err *err) {
    const char *texts[] = {n->set_key, n->dir, n->date, n->host, n->renderer, n->version, n->commit, n->header,
                           n->meta, n->added};
    sqlite3_stmt *st = prepare_texts(h,
                                     "INSERT INTO nights(set_key, dir, date, host, renderer, version, git_commit, "
                                     "header, meta, added, images) VALUES (?,?,?,?,?,?,?,?,?,?,?)",
                                     texts, (int)SB_COUNT(texts), err);
    if (!st) return -1;
    bool ok = sqlite3_bind_int(st, 11, n->images) == SQLITE_OK && sqlite3_step(st) == SQLITE_DONE;
    sqlite3_finalize(st);
    if (!ok) return db_fail(h, err, "adding the night"), -1;
    return sqlite3_last_insert_rowid(h->db);
}

static bool insert_metrics(sb_history *h, long long run, const sb_history_run_in *r, sb_err *err) {
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "INSERT INTO metrics(run, name, value) VALUES (?,?,?)", -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "preparing a metric");
    bool ok = true;
    for (int c = 0; ok && c < r->nmetrics; c++) {
        sqlite3_reset(st);
        ok = sqlite3_bind_int64(st, 1, run) == SQLITE_OK && bind_text(st, 2, r->metric_names[c]) &&
             sqlite3_bind_double(st, 3, r->metric_values[c]) == SQLITE_OK && sqlite3_step(st) == SQLITE_DONE;
    }
    sqlite3_finalize(st);
    return ok || db_fail(h, err, "adding a metric");
}

static bool insert_frames(sb_history *h, long long run, const char *csv, sb_err *err) {
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "INSERT INTO frames(run, csv) VALUES (?,?)", -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "preparing a run's frames");
    bool ok = sqlite3_bind_int64(st, 1, run) == SQLITE_OK && bind_text(st, 2, csv) && sqlite3_step(st) == SQLITE_DONE;
    sqlite3_finalize(st);
    return ok || db_fail(h, err, "adding a run's frames");
}

bool sb_history_insert_run(sb_history *h, long long night, const sb_history_run_in *r, sb_err *err) {
    const char *texts[] = {r->run_id, r->status, r->reason, r->stable, r->warnings, r->line};
    sqlite3_stmt *st = prepare_texts(h,
                                     "INSERT INTO runs(run_id, status, reason, stable, warnings, line, night, run_index, "
                                     SERIES_COLS ") VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)",
                                     texts, (int)SB_COUNT(texts), err);
    if (!st) return false;
    bool ok = sqlite3_bind_int64(st, 7, night) == SQLITE_OK && sqlite3_bind_int(st, 8, r->run_index) == SQLITE_OK &&
              bind_series(st, 9, r->series) && sqlite3_step(st) == SQLITE_DONE;
    sqlite3_finalize(st);
    if (!ok) return db_fail(h, err, "adding a run");
    long long id = sqlite3_last_insert_rowid(h->db);
    return insert_metrics(h, id, r, err) && (!r->frames_csv || insert_frames(h, id, r->frames_csv, err));
}

/* ---- reading ---- */

static void copy_col(char *dst, size_t len, sqlite3_stmt *st, int i) {
    const char *s = (const char *)sqlite3_column_text(st, i);
    snprintf(dst, len, "%s", s ? s : "");
}

static void read_night(sqlite3_stmt *st, sb_history_night *x) {
    memset(x, 0, sizeof *x);
    x->id = sqlite3_column_int64(st, 0);
    copy_col(x->date, sizeof x->date, st, 1);
    copy_col(x->host, sizeof x->host, st, 2);
    copy_col(x->commit, sizeof x->commit, st, 3);
    copy_col(x->renderer, sizeof x->renderer, st, 4);
    copy_col(x->version, sizeof x->version, st, 5);
    const char *header = (const char *)sqlite3_column_text(st, 6), *meta = (const char *)sqlite3_column_text(st, 7);
    x->header = sb_strdup(header ? header : "");
    x->meta = sb_strdup(meta ? meta : "");
    copy_col(x->dir, sizeof x->dir, st, 8);
    int *counts[] = {&x->runs, &x->ok, &x->failed, &x->unstable, &x->warned};
    for (int c = 0; c < 5; c++) *counts[c] = sqlite3_column_int(st, 9 + c);
}

int sb_history_nights(sb_history *h, sb_history_night **out, sb_err *err) {
    *out = NULL;
    sqlite3_stmt *st;
    char sql[1024];
    snprintf(sql, sizeof sql,
             "SELECT n.id, n.date, n.host, n.git_commit, n.renderer, n.version, n.header, n.meta, n.dir, "
             "count(r.id), sum(sb_status(r.status) = %d), sum(sb_status(r.status) = %d), sum(r.stable = 'no'), "
             "sum(r.warnings != '') FROM nights n LEFT JOIN runs r ON r.night = n.id GROUP BY n.id "
             "ORDER BY n.date, n.id",
             SB_STATUS_OK, SB_STATUS_FAILED);
    if (sqlite3_prepare_v2(h->db, sql, -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading the nights"), -1;
    int n = 0;
    while (sqlite3_step(st) == SQLITE_ROW) {
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
        read_night(st, &(*out)[n++]);
    }
    sqlite3_finalize(st);
    return n;
}

void sb_history_nights_free(sb_history_night *n, int count) {
    for (int i = 0; i < count; i++) free(n[i].header), free(n[i].meta);
    free(n);
}

char *sb_history_night_summary(sb_history *h, const sb_history_night *night, sb_err *err) {
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "SELECT line FROM runs WHERE night = ? ORDER BY run_index, id", -1, &st, NULL) !=
        SQLITE_OK)
        return db_fail(h, err, "reading a night's runs"), NULL;
    sqlite3_bind_int64(st, 1, night->id);
    size_t len = strlen(night->header), cap = len + 2;
    char *text = sb_xmalloc(cap);
    memcpy(text, night->header, len);
    text[len++] = '\n';
    while (sqlite3_step(st) == SQLITE_ROW) {
        const char *line = (const char *)sqlite3_column_text(st, 0);
        size_t n = line ? strlen(line) : 0;
        if (len + n + 2 > cap) text = sb_xrealloc(text, cap = (len + n + 2) * 2);
        memcpy(text + len, line ? line : "", n);
        len += n;
        text[len++] = '\n';
    }
    text[len] = 0;
    sqlite3_finalize(st);
    return text;
}

bool sb_history_night_frames(sb_history *h, long long night, void (*fn)(const char *run_id, const char *csv, void *arg),
                             void *arg, sb_err *err) {
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "SELECT r.run_id, f.csv FROM frames f JOIN runs r ON r.id = f.run WHERE r.night = ?",
                           -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading a night's frames");
    sqlite3_bind_int64(st, 1, night);
    while (sqlite3_step(st) == SQLITE_ROW) {
        const char *id = (const char *)sqlite3_column_text(st, 0), *csv = (const char *)sqlite3_column_text(st, 1);
        fn(id ? id : "", csv ? csv : "", arg);
    }
    sqlite3_finalize(st);
    return true;
}

sb_series *sb_history_series(sb_history *h, int *n) {
    *n = 0;
    sb_series *out = NULL;
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "SELECT DISTINCT " SERIES_COLS " FROM runs ORDER BY sb_series_key(" SERIES_COLS ")",
                           -1, &st, NULL) != SQLITE_OK)
        return NULL;
    while (sqlite3_step(st) == SQLITE_ROW) {
        out = sb_xrealloc(out, sizeof *out * (size_t)(*n + 1));
        read_series(st, 0, &out[(*n)++]);
    }
    sqlite3_finalize(st);
    return out;
}

/* A row of (night, date, stable, value, ci, commit) as a point. */
static void read_point(sqlite3_stmt *st, int first, sb_history_point *p) {
    p->night = sqlite3_column_int64(st, first);
    copy_col(p->date, sizeof p->date, st, first + 1);
    const char *stable = (const char *)sqlite3_column_text(st, first + 2);
    p->stable = !stable || strcmp(stable, "no");
    p->value = sqlite3_column_double(st, first + 3);
    p->ci = sqlite3_column_type(st, first + 4) == SQLITE_NULL ? NAN : sqlite3_column_double(st, first + 4);
    copy_col(p->commit, sizeof p->commit, st, first + 5);
}

int sb_history_points_of(sb_history *h, const sb_series *series, const char *center, const char *ci,
                         sb_history_point **out, sb_err *err) {
    *out = NULL;
    const char *texts[] = {center, ci && ci[0] ? ci : "-"};
    char sql[1024];
    snprintf(sql, sizeof sql,
             "SELECT r.night, n.date, r.stable, c.value, i.value, n.git_commit FROM runs r "
             "JOIN nights n ON n.id = r.night JOIN metrics c ON c.run = r.id AND c.name = ?1 "
             "LEFT JOIN metrics i ON i.run = r.id AND i.name = ?2 WHERE r.host = ?3 AND r.renderer = ?4 AND "
             "r.scene = ?5 AND r.path = ?6 AND r.size = ?7 AND r.technique = ?8 AND r.params = ?9 AND r.light = ?10 "
             "AND r.anim = ?11 AND r.run_options = ?12 AND r.indirect = ?13 AND sb_status(r.status) = %d "
             "ORDER BY n.date, n.id",
             SB_STATUS_OK);
    sqlite3_stmt *st = prepare_texts(h, sql, texts, 2, err);
    if (!st) return -1;
    if (!bind_series(st, 3, series)) {
        sqlite3_finalize(st);
        return db_fail(h, err, "binding a series"), -1;
    }
    int n = 0;
    while (sqlite3_step(st) == SQLITE_ROW) {
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
        read_point(st, 0, &(*out)[n++]);
    }
    sqlite3_finalize(st);
    return n;
}

bool sb_history_each_figure(sb_history *h, const char *center, const char *ci, const char *since,
                            void (*fn)(const sb_series *series, const sb_history_point *p, void *arg), void *arg,
                            sb_err *err) {
    const char *texts[] = {center, ci && ci[0] ? ci : "-", since ? since : ""};
    char sql[1024];
    snprintf(sql, sizeof sql,
             "SELECT r.night, n.date, r.stable, c.value, i.value, n.git_commit, " SERIES_COLS_R " "
             "FROM runs r JOIN nights n ON n.id = r.night JOIN metrics c ON c.run = r.id AND c.name = ?1 "
             "LEFT JOIN metrics i ON i.run = r.id AND i.name = ?2 "
             "WHERE sb_status(r.status) = %d AND n.date >= ?3 ORDER BY sb_series_key(" SERIES_COLS_R "), n.date, n.id",
             SB_STATUS_OK);
    sqlite3_stmt *st = prepare_texts(h, sql, texts, 3, err);
    if (!st) return false;
    sb_series *se = sb_xmalloc(sizeof *se);
    while (sqlite3_step(st) == SQLITE_ROW) {
        sb_history_point p;
        read_point(st, 0, &p);
        read_series(st, 6, se);
        fn(se, &p, arg);
    }
    free(se);
    sqlite3_finalize(st);
    return true;
}

long long sb_history_find_night(sb_history *h, const char *what, sb_err *err) {
    sqlite3_stmt *st;
    char *end;
    long long id = strtoll(what, &end, 10);
    if (*what && !*end) {
        if (sqlite3_prepare_v2(h->db, "SELECT id FROM nights WHERE id = ?", -1, &st, NULL) != SQLITE_OK)
            return db_fail(h, err, "reading the nights"), -1;
        sqlite3_bind_int64(st, 1, id);
        long long got = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int64(st, 0) : 0;
        sqlite3_finalize(st);
        if (got) return got;
    }
    /* a commit: the first night that ran it (its prefix, at least 4 characters) */
    if (strlen(what) < 4) return 0;
    st = prepare_texts(h,
                       "SELECT id FROM nights WHERE substr(git_commit, 1, length(?1)) = ?1 OR "
                       "substr(?1, 1, length(git_commit)) = git_commit AND length(git_commit) >= 7 "
                       "ORDER BY date, id LIMIT 1",
                       &what, 1, err);
    if (!st) return -1;
    long long got = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int64(st, 0) : 0;
    sqlite3_finalize(st);
    return got;
}

/* ---- annotations ---- */

/* The same note on the same night (its series, text and --accept alike) is kept once: a script that puts its
   notes on every night it runs adds each once. */
static int annotation_exists(sb_history *h, long long night, const char *series, const char *text, bool accept,
                             sb_err *err) {
    const char *texts[] = {series, text};
    sqlite3_stmt *st = prepare_texts(h, "SELECT count(*) FROM annotations WHERE series = ? AND text = ? AND night = ? "
                                        "AND accept = ?", texts, 2, err);
    if (!st) return -1;
    int n = -1;
    if (sqlite3_bind_int64(st, 3, night) == SQLITE_OK && sqlite3_bind_int(st, 4, accept) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW)
        n = sqlite3_column_int(st, 0);
    sqlite3_finalize(st);
    if (n < 0) db_fail(h, err, "reading the annotations");
    return n;
}

int sb_history_store_annotation(sb_history *h, long long night, const char *commit, const char *series,
                                const char *text, bool accept, sb_err *err) {
    int had = annotation_exists(h, night, series, text, accept, err);
    if (had != 0) return had > 0 ? 0 : -1;
    char added[64];
    sb_utc_now(added, sizeof added);
    const char *texts[] = {commit, series, text, added};
    sqlite3_stmt *st = prepare_texts(h,
                                     "INSERT INTO annotations(git_commit, series, text, added, night, accept) "
                                     "VALUES (?,?,?,?,?,?)",
                                     texts, 4, err);
    if (!st) return false;
    bool ok = sqlite3_bind_int64(st, 5, night) == SQLITE_OK && sqlite3_bind_int(st, 6, accept) == SQLITE_OK &&
              sqlite3_step(st) == SQLITE_DONE;
    sqlite3_finalize(st);
    return ok ? 1 : (db_fail(h, err, "adding the annotation"), -1);
}

int sb_history_annotations(sb_history *h, sb_history_annotation **out, sb_err *err) {
    *out = NULL;
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "SELECT a.night, n.date, a.git_commit, a.series, a.text, a.accept FROM annotations a "
                                  "JOIN nights n ON n.id = a.night ORDER BY n.date, a.id", -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading the annotations"), -1;
    int n = 0;
    while (sqlite3_step(st) == SQLITE_ROW) {
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
        sb_history_annotation *x = &(*out)[n++];
        memset(x, 0, sizeof *x);
        x->night = sqlite3_column_int64(st, 0);
        copy_col(x->date, sizeof x->date, st, 1);
        copy_col(x->commit, sizeof x->commit, st, 2);
        copy_col(x->series, sizeof x->series, st, 3);
        copy_col(x->text, sizeof x->text, st, 4);
        x->accept = sqlite3_column_int(st, 5) != 0;
    }
    sqlite3_finalize(st);
    return n;
}
