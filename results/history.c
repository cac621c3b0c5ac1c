/* history.c - the results history in SQLite (history.h). */
#define _XOPEN_SOURCE 700 /* realpath */
#include "history.h"

#include <errno.h>
#include <fnmatch.h>
#include <math.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "changepoint.h"
#include "stats.h"
#include "compare.h"
#include "csv.h"
#include "columns.h"
#include "table.h"

struct sb_history {
    sqlite3 *db;
    char path[4096];
};

const char *sb_history_default_path(const char *default_out, char *buf, size_t len) {
    const char *env = getenv("SB_HISTORY");
    if (env && *env) snprintf(buf, len, "%s", env);
    else snprintf(buf, len, "%s/history.sqlite", default_out);
    return buf;
}

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

/* The schema, one step a version: step k takes a file from version k-1 to k.
   Version 1 kept the summary rows; 2 added each run's per-frame CSV and the
   night's image count; 3 the annotations (`history annotate`). */
static const char *const migrations[SB_HISTORY_SCHEMA] = {
    "CREATE TABLE nights(id INTEGER PRIMARY KEY, set_key TEXT UNIQUE NOT NULL, dir TEXT, date TEXT, host TEXT,"
    " renderer TEXT, version TEXT, git_commit TEXT, header TEXT, meta TEXT, added TEXT);"
    "CREATE TABLE runs(id INTEGER PRIMARY KEY, night INTEGER NOT NULL REFERENCES nights(id), run_id TEXT,"
    " run_index INTEGER, series TEXT, scene TEXT, path TEXT, technique TEXT, params TEXT, size TEXT, status TEXT,"
    " reason TEXT, stable TEXT, warnings TEXT, line TEXT);"
    "CREATE TABLE metrics(run INTEGER NOT NULL, name TEXT NOT NULL, value REAL, PRIMARY KEY(run, name)) WITHOUT ROWID;"
    "CREATE INDEX runs_night ON runs(night);"
    "CREATE INDEX runs_series ON runs(series);",
    "CREATE TABLE frames(run INTEGER PRIMARY KEY, csv TEXT);"
    "ALTER TABLE nights ADD COLUMN images INTEGER NOT NULL DEFAULT 0;",
    "CREATE TABLE annotations(id INTEGER PRIMARY KEY, night INTEGER NOT NULL REFERENCES nights(id), git_commit TEXT,"
    " series TEXT NOT NULL DEFAULT '', text TEXT NOT NULL, accept INTEGER NOT NULL DEFAULT 0, added TEXT);",
};

static bool migrate(sb_history *h, sb_err *err) {
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "PRAGMA user_version", -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading the schema version");
    int v = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int(st, 0) : 0;
    sqlite3_finalize(st);
    if (v > SB_HISTORY_SCHEMA)
        return sb_fail(err, "%s: history schema version %d, newer than this shadowbench's %d: use a newer shadowbench",
                       h->path, v, SB_HISTORY_SCHEMA);
    for (; v < SB_HISTORY_SCHEMA; v++) {
        char sql[256];
        snprintf(sql, sizeof sql, "PRAGMA user_version = %d", v + 1);
        if (!exec(h, "BEGIN IMMEDIATE", err)) return false;
        if (!exec(h, migrations[v], err) || !exec(h, sql, err)) {
            sqlite3_exec(h->db, "ROLLBACK", NULL, NULL, NULL);
            return false;
        }
        if (!exec(h, "COMMIT", err)) return false;
    }
    return true;
}

sb_history *sb_history_open(const char *path, bool write, sb_err *err) {
    sb_history *h = sb_xcalloc(1, sizeof *h);
    snprintf(h->path, sizeof h->path, "%s", path);
    struct stat st;
    if (!write && stat(path, &st) != 0) {
        sb_fail(err, "%s: no history here (%s); `shadowbench history add DIR` makes one", path, strerror(errno));
        free(h);
        return NULL;
    }
    if (write) {
        char dir[4096];
        snprintf(dir, sizeof dir, "%s", path);
        char *slash = strrchr(dir, '/');
        if (slash && slash != dir) {
            *slash = 0;
            if (!sb_mkdir_p(dir, err)) {
                free(h);
                return NULL;
            }
        }
    }
    int flags = write ? SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE : SQLITE_OPEN_READONLY;
    if (sqlite3_open_v2(path, &h->db, flags, NULL) != SQLITE_OK) {
        db_fail(h, err, "cannot open");
        sb_history_close(h);
        return NULL;
    }
    sqlite3_busy_timeout(h->db, 10000);
    /* a file that is not a database fails on its first read */
    if (!exec(h, "SELECT count(*) FROM sqlite_master", err) || (write && !migrate(h, err))) {
        sb_history_close(h);
        return NULL;
    }
    if (!write) {
        sqlite3_stmt *q;
        int v = 0;
        if (sqlite3_prepare_v2(h->db, "PRAGMA user_version", -1, &q, NULL) == SQLITE_OK) {
            if (sqlite3_step(q) == SQLITE_ROW) v = sqlite3_column_int(q, 0);
            sqlite3_finalize(q);
        }
        if (v != SB_HISTORY_SCHEMA) {
            sb_fail(err, "%s: history schema version %d, this shadowbench reads %d (%s)", path, v, SB_HISTORY_SCHEMA,
                    v < SB_HISTORY_SCHEMA ? "`shadowbench history add` migrates it" : "use a newer shadowbench");
            sb_history_close(h);
            return NULL;
        }
    }
    return h;
}

void sb_history_close(sb_history *h) {
    if (!h) return;
    if (h->db) sqlite3_close(h->db);
    free(h);
}

/* ---- adding a results set ---- */

/* The set's meta (a merged set: its first shard's), as text, and one field of it. */
static char *read_meta(const char *dir) {
    char path[4200];
    snprintf(path, sizeof path, "%s/meta", dir);
    char *t = sb_read_file(path, NULL, NULL);
    if (!t) {
        snprintf(path, sizeof path, "%s/meta.1", dir);
        t = sb_read_file(path, NULL, NULL);
    }
    return t ? t : sb_strdup("");
}

static void meta_field(const char *meta, const char *key, char *out, size_t len) {
    out[0] = 0;
    size_t kl = strlen(key);
    for (const char *p = meta; p && *p;) {
        if (!strncmp(p, key, kl) && p[kl] == ':' && p[kl + 1] == ' ') {
            size_t n = strcspn(p + kl + 2, "\n");
            snprintf(out, len, "%.*s", (int)n, p + kl + 2);
            return;
        }
        p = strchr(p, '\n');
        if (p) p++;
    }
}

/* The set's date: the meta's, else the folder's stamp (YYYYMMDDTHHMMSSZ), else summary.csv's mtime. */
static void set_date(const char *dir, const char *meta, const char *summary, char *out, size_t len) {
    meta_field(meta, "date", out, len);
    if (out[0]) return;
    const char *base = strrchr(dir, '/');
    base = base ? base + 1 : dir;
    int y, mo, d, hh, mi, ss;
    if (sscanf(base, "%4d%2d%2dT%2d%2d%2dZ", &y, &mo, &d, &hh, &mi, &ss) == 6) {
        snprintf(out, len, "%04d-%02d-%02dT%02d:%02d:%02dZ", y, mo, d, hh, mi, ss);
        return;
    }
    struct stat st;
    struct tm tm;
    time_t t = stat(summary, &st) == 0 ? st.st_mtime : time(NULL);
    gmtime_r(&t, &tm);
    strftime(out, len, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

static bool bind_text(sqlite3_stmt *st, int i, const char *s) {
    return sqlite3_bind_text(st, i, s ? s : "", -1, SQLITE_TRANSIENT) == SQLITE_OK;
}

static int count_images(const char *dir) {
    char path[4200];
    snprintf(path, sizeof path, "%s/images", dir);
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) return 0;
    return 1;
}

/* A summary row's series (history.h), its size (WxH) and its sorted parameters. */
static void series_of(const sb_table *t, int r, const char *host, const char *renderer, char *series, size_t len,
                      char *size, size_t size_len, char *params, size_t params_len) {
    char key[3072];
    sb_compare_run_key(t, r, key, sizeof key);
    snprintf(size, size_len, "%sx%s", sb_table_get(t, r, "width"), sb_table_get(t, r, "height"));
    /* the key's parameters, sorted (its last field) */
    const char *kp = key;
    for (int bars = 0; bars < 3 && (kp = strchr(kp, '|')); bars++) kp++;
    snprintf(params, params_len, "%s", kp ? kp : "");
    snprintf(series, len, "%s|%s|%s|%s|%s|%s|%s", host, renderer, sb_table_get(t, r, "scene"),
             sb_table_get(t, r, "path"), size, sb_table_get(t, r, "technique"), params);
}

/* The host and renderer a set's series are kept under. */
static void set_host(const char *meta, const sb_table *t, char *host, size_t hlen, char *renderer, size_t rlen) {
    meta_field(meta, "host", host, hlen);
    if (!host[0]) snprintf(host, hlen, "unknown");
    snprintf(renderer, rlen, "%s", t->nrows ? sb_table_get(t, 0, "renderer") : "");
    if (!renderer[0]) meta_field(meta, "gl_renderer", renderer, rlen);
}

bool sb_history_add(sb_history *h, const char *dir, sb_history_added *out, sb_err *err) {
    memset(out, 0, sizeof *out);
    char sum_path[4200];
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    size_t sum_len = 0;
    char *sum_text = sb_read_file(sum_path, &sum_len, err);
    if (!sum_text) return false;
    sb_table t;
    if (!sb_table_parse(&t, sum_path, sum_text, err)) {
        free(sum_text);
        return false;
    }
    const char *need[] = {"run_id", "scene", "path", "technique", "params", "status", "width", "height"};
    for (size_t i = 0; i < SB_COUNT(need); i++)
        if (sb_table_col(&t, need[i]) < 0) {
            sb_table_free(&t);
            free(sum_text);
            return sb_fail(err, "%s: not a shadowbench summary (no '%s' column)", sum_path, need[i]);
        }
    char *meta = read_meta(dir);
    char host[256], renderer[512], version[64], commit[128], date[64];
    set_host(meta, &t, host, sizeof host, renderer, sizeof renderer);
    meta_field(meta, "version", version, sizeof version);
    meta_field(meta, "commit", commit, sizeof commit);
    set_date(dir, meta, sum_path, date, sizeof date);
    /* a batch (or shard) says how many runs it has: a summary with fewer is a set still running or stopped */
    char runs_field[128];
    meta_field(meta, "runs", runs_field, sizeof runs_field);
    int want = 0;
    if (runs_field[0] && sscanf(runs_field, "%d", &want) == 1 && t.nrows < want) {
        sb_fail(err, "%s: %d of the %d runs its meta names are in summary.csv: the set is incomplete (still running, "
                     "or stopped: `batch --resume` it first)", dir, t.nrows, want);
        sb_table_free(&t);
        free(sum_text);
        free(meta);
        return false;
    }
    /* the set is its summary's bytes on its host: the same set added twice is found */
    uint64_t key = sb_fnv1a(sb_fnv1a(1469598103934665603ull, sum_text, sum_len), host, strlen(host));
    char set_key[32];
    snprintf(set_key, sizeof set_key, "%016llx", (unsigned long long)key);
    char absdir[4096];
    if (!realpath(dir, absdir)) snprintf(absdir, sizeof absdir, "%s", dir);
    char added[64];
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    strftime(added, sizeof added, "%Y-%m-%dT%H:%M:%SZ", &tm);

    bool ok = exec(h, "BEGIN IMMEDIATE", err);
    sqlite3_stmt *q = NULL, *ins_night = NULL, *ins_run = NULL, *ins_metric = NULL, *ins_frames = NULL;
    if (ok) {
        ok = sqlite3_prepare_v2(h->db, "SELECT id FROM nights WHERE set_key = ?", -1, &q, NULL) == SQLITE_OK &&
             bind_text(q, 1, set_key);
        if (!ok) db_fail(h, err, "looking the set up");
        else if (sqlite3_step(q) == SQLITE_ROW) {
            out->existed = true;
            out->night = sqlite3_column_int64(q, 0);
        }
    }
    if (ok && !out->existed) {
        ok = sqlite3_prepare_v2(h->db,
                                "INSERT INTO nights(set_key, dir, date, host, renderer, version, git_commit, header, meta,"
                                " added, images) VALUES (?,?,?,?,?,?,?,?,?,?,?)",
                                -1, &ins_night, NULL) == SQLITE_OK &&
             sqlite3_prepare_v2(h->db,
                                "INSERT INTO runs(night, run_id, run_index, series, scene, path, technique, params, size,"
                                " status, reason, stable, warnings, line) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)",
                                -1, &ins_run, NULL) == SQLITE_OK &&
             sqlite3_prepare_v2(h->db, "INSERT INTO metrics(run, name, value) VALUES (?,?,?)", -1, &ins_metric,
                                NULL) == SQLITE_OK &&
             sqlite3_prepare_v2(h->db, "INSERT INTO frames(run, csv) VALUES (?,?)", -1, &ins_frames, NULL) == SQLITE_OK;
        if (!ok) db_fail(h, err, "preparing the insert");
        size_t hdr_len = strcspn(sum_text, "\r\n");
        char *hdr = sb_xmalloc(hdr_len + 1);
        memcpy(hdr, sum_text, hdr_len);
        hdr[hdr_len] = 0;
        if (ok) {
            ok = bind_text(ins_night, 1, set_key) && bind_text(ins_night, 2, absdir) && bind_text(ins_night, 3, date) &&
                 bind_text(ins_night, 4, host) && bind_text(ins_night, 5, renderer) &&
                 bind_text(ins_night, 6, version) && bind_text(ins_night, 7, commit) && bind_text(ins_night, 8, hdr) &&
                 bind_text(ins_night, 9, meta) && bind_text(ins_night, 10, added) &&
                 sqlite3_bind_int(ins_night, 11, count_images(dir)) == SQLITE_OK &&
                 sqlite3_step(ins_night) == SQLITE_DONE;
            if (!ok) db_fail(h, err, "adding the night");
            out->night = sqlite3_last_insert_rowid(h->db);
        }
        free(hdr);
        for (int r = 0; ok && r < t.nrows; r++) {
            char series[4096], size[64], params[2048];
            series_of(&t, r, host, renderer, series, sizeof series, size, sizeof size, params, sizeof params);
            const char *run_id = sb_table_get(&t, r, "run_id");
            sqlite3_reset(ins_run);
            ok = sqlite3_bind_int64(ins_run, 1, out->night) == SQLITE_OK && bind_text(ins_run, 2, run_id) &&
                 sqlite3_bind_int(ins_run, 3, atoi(sb_table_get(&t, r, "run_index"))) == SQLITE_OK &&
                 bind_text(ins_run, 4, series) && bind_text(ins_run, 5, sb_table_get(&t, r, "scene")) &&
                 bind_text(ins_run, 6, sb_table_get(&t, r, "path")) &&
                 bind_text(ins_run, 7, sb_table_get(&t, r, "technique")) && bind_text(ins_run, 8, params) &&
                 bind_text(ins_run, 9, size) && bind_text(ins_run, 10, sb_table_get(&t, r, "status")) &&
                 bind_text(ins_run, 11, sb_table_get(&t, r, "reason")) &&
                 bind_text(ins_run, 12, sb_table_get(&t, r, "stable")) &&
                 bind_text(ins_run, 13, sb_table_get(&t, r, "warnings")) && bind_text(ins_run, 14, t.lines[r]) &&
                 sqlite3_step(ins_run) == SQLITE_DONE;
            if (!ok) {
                db_fail(h, err, "adding a run");
                break;
            }
            long long rid = sqlite3_last_insert_rowid(h->db);
            out->runs++;
            for (int c = 0; ok && c < t.cols; c++) {
                double v;
                const char *cell = t.rows[r][c];
                if (!*cell || !sb_parse_double(cell, &v)) continue;
                sqlite3_reset(ins_metric);
                ok = sqlite3_bind_int64(ins_metric, 1, rid) == SQLITE_OK && bind_text(ins_metric, 2, t.header[c]) &&
                     sqlite3_bind_double(ins_metric, 3, v) == SQLITE_OK && sqlite3_step(ins_metric) == SQLITE_DONE;
                if (!ok) db_fail(h, err, "adding a metric");
            }
            char fpath[4200];
            snprintf(fpath, sizeof fpath, "%s/%s.csv", dir, run_id);
            char *frames = *run_id ? sb_read_file(fpath, NULL, NULL) : NULL;
            if (ok && frames) {
                sqlite3_reset(ins_frames);
                ok = sqlite3_bind_int64(ins_frames, 1, rid) == SQLITE_OK && bind_text(ins_frames, 2, frames) &&
                     sqlite3_step(ins_frames) == SQLITE_DONE;
                if (!ok) db_fail(h, err, "adding a run's frames");
                out->frames_files++;
            }
            free(frames);
        }
    }
    sqlite3_finalize(q);
    sqlite3_finalize(ins_night);
    sqlite3_finalize(ins_run);
    sqlite3_finalize(ins_metric);
    sqlite3_finalize(ins_frames);
    if (ok) ok = exec(h, "COMMIT", err);
    if (!ok) sqlite3_exec(h->db, "ROLLBACK", NULL, NULL, NULL);
    sb_table_free(&t);
    free(sum_text);
    free(meta);
    return ok;
}

bool sb_history_list(sb_history *h, FILE *out, sb_err *err) {
    sb_history_night *n = NULL;
    int nn = sb_history_nights(h, &n, err);
    if (nn < 0) return false;
    fprintf(out, "%-5s %-20s %-16s %-20s %5s %5s %8s  %s\n", "night", "date", "host", "commit", "runs", "ok",
            "unstable", "folder");
    for (int i = 0; i < nn; i++)
        fprintf(out, "%-5lld %-20s %-16s %-20s %5d %5d %8d  %s\n", n[i].id, n[i].date, n[i].host, n[i].commit, n[i].runs,
                n[i].ok, n[i].unstable, n[i].dir);
    sb_history_nights_free(n, nn);
    return true;
}

/* ---- changes ---- */

void sb_history_series_field(const char *series, int k, char *out, size_t len) {
    const char *p = series;
    for (int i = 0; i < k && p; i++) {
        p = strchr(p, '|');
        if (p) p++;
    }
    size_t n = !p ? 0 : k < 6 ? strcspn(p, "|") : strlen(p);
    snprintf(out, len, "%.*s", (int)n, p ? p : "");
}

/* "host|renderer|scene|path|WxH|technique|params" split into its seven fields */
typedef struct { char f[7][1024]; } series_fields;
static void split_series(const char *series, series_fields *o) {
    for (int i = 0; i < 7; i++) sb_history_series_field(series, i, o->f[i], sizeof o->f[i]);
}



typedef struct {
    long long night;
    char date[32], commit[64], host[256];
} night_info;

/* The least night-to-night timing noise assumed for a renderer, as a fraction: q's floor, else 1 % on a GPU
 * and 5 % on a software rasterizer, whose times move with everything else on the CPU (the stability tests
 * widen alike). */
static double noise_floor(const sb_history_query *q, const char *renderer) {
    if (q->noise_floor_pct > 0) return q->noise_floor_pct / 100;
    bool soft = strstr(renderer, "llvmpipe") || strstr(renderer, "softpipe") || strstr(renderer, "SwiftShader") ||
                strstr(renderer, "lavapipe");
    return soft ? 0.05 : 0.01;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}


int sb_history_changes(sb_history *h, const sb_history_query *q, sb_history_change **out, sb_err *err) {
    *out = NULL;
    int recent = q->recent > 0 ? q->recent : 3;
    /* the nights, oldest first, and each host's newest */
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "SELECT id, date, git_commit, host FROM nights WHERE date >= ? ORDER BY date, id", -1,
                           &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading the nights"), -1;
    bind_text(st, 1, q->since ? q->since : "");
    night_info *nights = NULL;
    int nn = 0, cap = 0;
    while (sqlite3_step(st) == SQLITE_ROW) {
        if (nn == cap) nights = sb_xrealloc(nights, sizeof *nights * (size_t)(cap = cap ? cap * 2 : 64));
        night_info *ni = &nights[nn++];
        ni->night = sqlite3_column_int64(st, 0);
        snprintf(ni->date, sizeof ni->date, "%s", (const char *)sqlite3_column_text(st, 1));
        snprintf(ni->commit, sizeof ni->commit, "%s", (const char *)sqlite3_column_text(st, 2));
        snprintf(ni->host, sizeof ni->host, "%s", (const char *)sqlite3_column_text(st, 3));
    }
    sqlite3_finalize(st);
    /* a night's rank among its host's nights counted from the newest (0: newest) */
    int *rank = sb_xcalloc((size_t)nn + 1, sizeof *rank);
    for (int i = 0; i < nn; i++)
        for (int j = i + 1; j < nn; j++)
            if (!strcmp(nights[i].host, nights[j].host)) rank[i]++;

    const char *metrics[32];
    int nm = 0;
    if (q->nmetrics)
        for (int i = 0; i < q->nmetrics && nm < 32; i++) metrics[nm++] = q->metrics[i];
    else
        nm = sb_columns_default_metrics(SB_USE_HISTORY, metrics, 32);
    for (int i = 0; i < nm; i++) {
        sb_metric_cols mc;
        if (!sb_columns_metric(metrics[i], &mc)) {
            free(nights);
            free(rank);
            sb_fail(err, "unknown metric '%s' (summary columns give e.g. gpu_ms, final_ms, draw_calls, err_rate)",
                    metrics[i]);
            return -1;
        }
    }
    sb_history_change *ch = NULL;
    int nch = 0, chcap = 0;
    int maxn = nn > 0 ? nn : 1;
    double *x = sb_xmalloc(sizeof *x * (size_t)maxn), *w = sb_xmalloc(sizeof *w * (size_t)maxn),
           *ci = sb_xmalloc(sizeof *ci * (size_t)maxn), *tmp = sb_xmalloc(sizeof *tmp * (size_t)maxn);
    int *at_night = sb_xmalloc(sizeof *at_night * (size_t)maxn);
    bool ok = true;
    for (int mi = 0; ok && mi < nm; mi++) {
        sb_metric_cols mc;
        sb_columns_metric(metrics[mi], &mc);
        ok = sqlite3_prepare_v2(h->db,
                                "SELECT r.series, r.night, r.stable, c.value, i.value FROM runs r "
                                "JOIN nights n ON n.id = r.night "
                                "JOIN metrics c ON c.run = r.id AND c.name = ?1 "
                                "LEFT JOIN metrics i ON i.run = r.id AND i.name = ?2 "
                                "WHERE r.status = 'ok' AND n.date >= ?3 ORDER BY r.series, n.date, n.id",
                                -1, &st, NULL) == SQLITE_OK;
        if (!ok) {
            db_fail(h, err, "reading a metric");
            break;
        }
        bind_text(st, 1, mc.center);
        bind_text(st, 2, mc.ci[0] ? mc.ci : "-");
        bind_text(st, 3, q->since ? q->since : "");
        char series[1024] = "";
        int k = 0;
        bool more = true;
        while (more) {
            more = sqlite3_step(st) == SQLITE_ROW;
            const char *s = more ? (const char *)sqlite3_column_text(st, 0) : "";
            if (!more || strcmp(s, series)) {
                /* the series so far is complete: find its changes */
                if (k >= 2 * SB_CP_MIN_SEG) {
                    /* a night whose own CI is more than twice the series' usual counts less */
                    int nci = 0;
                    for (int i = 0; i < k; i++)
                        if (ci[i] > 0) tmp[nci++] = ci[i];
                    double typical = 0;
                    if (nci) {
                        qsort(tmp, (size_t)nci, sizeof *tmp, cmp_double);
                        typical = tmp[nci / 2];
                    }
                    for (int i = 0; i < k; i++)
                        if (typical > 0 && ci[i] > 2 * typical) w[i] *= (2 * typical / ci[i]) * (2 * typical / ci[i]);
                    series_fields sf;
                    split_series(series, &sf);
                    sb_cp_opts o = {.relative = true, .noise_floor = mc.ci[0] ? noise_floor(q, sf.f[1]) : 0};
                    sb_cp_change cps[64];
                    int nc = sb_changepoints(x, w, k, &o, cps, 64, NULL);
                    for (int c = 0; c < nc && c < 64; c++) {
                        if (nch == chcap) ch = sb_xrealloc(ch, sizeof *ch * (size_t)(chcap = chcap ? 2 * chcap : 16));
                        sb_history_change *o2 = &ch[nch++];
                        memset(o2, 0, sizeof *o2);
                        snprintf(o2->series, sizeof o2->series, "%s", series);
                        snprintf(o2->metric, sizeof o2->metric, "%s", metrics[mi]);
                        const night_info *a = &nights[at_night[cps[c].at - 1]], *b = &nights[at_night[cps[c].at]];
                        o2->night_before = a->night;
                        o2->night_after = b->night;
                        snprintf(o2->date_after, sizeof o2->date_after, "%s", b->date);
                        snprintf(o2->commit_before, sizeof o2->commit_before, "%s", a->commit);
                        snprintf(o2->commit_after, sizeof o2->commit_after, "%s", b->commit);
                        o2->before = cps[c].before;
                        o2->after = cps[c].after;
                        o2->rel = cps[c].rel;
                        o2->z = cps[c].z;
                        o2->p = cps[c].p;
                        o2->regression = mc.lower_worse ? cps[c].after < cps[c].before : cps[c].after > cps[c].before;
                        o2->recent = rank[at_night[cps[c].at]] < recent;
                    }
                }
                if (!more) break;
                snprintf(series, sizeof series, "%s", s);
                k = 0;
            }
            long long night = sqlite3_column_int64(st, 1);
            int ni = 0;
            while (ni < nn && nights[ni].night != night) ni++;
            if (ni == nn) continue;
            if (k > 0 && at_night[k - 1] == ni) k--;   /* one figure a night: the later run */
            at_night[k] = ni;
            x[k] = sqlite3_column_double(st, 3);
            ci[k] = sqlite3_column_type(st, 4) == SQLITE_NULL ? 0 : sqlite3_column_double(st, 4) / fabs(x[k] ? x[k] : 1);
            const char *stable = (const char *)sqlite3_column_text(st, 2);
            w[k] = stable && !strcmp(stable, "no") ? 0.25 : 1.0;
            k++;
        }
        sqlite3_finalize(st);
    }
    free(x);
    free(w);
    free(ci);
    free(tmp);
    free(at_night);
    free(nights);
    free(rank);
    if (!ok) {
        free(ch);
        return -1;
    }
    int ns = 0;
    char **all = sb_history_series(h, &ns), **labels = sb_history_labels(all, ns);
    for (int c = 0; c < nch; c++)
        for (int i = 0; i < ns; i++)
            if (!strcmp(all[i], ch[c].series)) snprintf(ch[c].label, sizeof ch[c].label, "%s", labels[i]);
    for (int i = 0; i < ns; i++) free(all[i]), free(labels[i]);
    free(all);
    free(labels);
    /* what is known of each change's night: the machine, and the annotations */
    sb_history_note *notes = NULL;
    int nnotes = sb_history_notes(h, &notes, err);
    if (nnotes < 0) {
        free(ch);
        return -1;
    }
    for (int c = 0; c < nch; c++)
        for (int i = 0; i < nnotes; i++) {
            const sb_history_note *x = &notes[i];
            if (x->night != ch[c].night_after || !sb_history_note_matches(x, ch[c].series, ch[c].label)) continue;
            char *to = x->machine ? ch[c].machine : ch[c].note;
            size_t l = strlen(to);
            snprintf(to + l, sizeof ch[c].note - l, "%s%s", l ? "; " : "", x->machine ? x->aside : x->text);
            ch[c].accepted |= x->accept;
        }
    free(notes);
    *out = ch;
    return nch;
}

/* Whether ":item:" is in ":params:" */
static bool has_item(const char *params, const char *item, size_t len) {
    for (const char *p = params; *p;) {
        size_t n = strcspn(p, ":");
        if (n == len && !strncmp(p, item, len)) return true;
        p += n;
        if (*p) p++;
    }
    return false;
}

char **sb_history_labels(char *const *series, int n) {
    char **out = sb_xcalloc((size_t)(n ? n : 1), sizeof *out);
    series_fields *f = sb_xmalloc(sizeof *f * (size_t)(n ? n : 1));
    bool hosts = false;
    for (int i = 0; i < n; i++) {
        split_series(series[i], &f[i]);
        if (i && strcmp(f[i].f[0], f[0].f[0])) hosts = true;
    }
    for (int i = 0; i < n; i++) {
        char kept[1024] = "";
        for (const char *p = f[i].f[6]; *p;) {
            size_t len = strcspn(p, ":");
            bool shared = true;   /* by every series of this technique */
            for (int j = 0; j < n && shared; j++)
                if (j != i && !strcmp(f[j].f[5], f[i].f[5]) && !has_item(f[j].f[6], p, len)) shared = false;
            if (!shared) {
                size_t l = strlen(kept);
                snprintf(kept + l, sizeof kept - l, ":%.*s", (int)len, p);
            }
            p += len;
            if (*p) p++;
        }
        char buf[4096], where[2100];
        if (!strcmp(f[i].f[2], f[i].f[3])) snprintf(where, sizeof where, "%s", f[i].f[2]);
        else snprintf(where, sizeof where, "%s/%s", f[i].f[2], f[i].f[3]);
        snprintf(buf, sizeof buf, "%s %s%s %s%s%s", where, f[i].f[5], kept, f[i].f[4], hosts ? " @" : "",
                 hosts ? f[i].f[0] : "");
        out[i] = sb_strdup(buf);
    }
    free(f);
    return out;
}

char **sb_history_series(sb_history *h, int *n) {
    *n = 0;
    char **out = NULL;
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "SELECT DISTINCT series FROM runs ORDER BY series", -1, &st, NULL) != SQLITE_OK)
        return NULL;
    while (sqlite3_step(st) == SQLITE_ROW) {
        out = sb_xrealloc(out, sizeof *out * (size_t)(*n + 1));
        const char *s = (const char *)sqlite3_column_text(st, 0);
        out[(*n)++] = sb_strdup(s ? s : "");
    }
    sqlite3_finalize(st);
    return out;
}

void sb_history_print_changes(const sb_history_change *c, int n, int format, FILE *out) {
    if (format == SB_OUTPUT_CSV)
        fprintf(out, "series,host,metric,night_before,night_after,date_after,before,after,change_pct,z,p,"
                     "commit_before,commit_after,verdict,note,machine\n");
    else
        fprintf(out, "%-40s %-14s %-6s %-20s %10s %10s %8s %6s %8s  %-25s %s\n", "series", "metric", "night",
                "first night after", "before", "after", "change", "z", "p", "commits", "verdict");
    for (int i = 0; i < n; i++) {
        series_fields f;
        split_series(c[i].series, &f);
        const char *label = c[i].label, *host = f.f[0];
        const char *verdict = c[i].regression ? (c[i].accepted ? (c[i].recent ? "accepted (recent)" : "accepted")
                                                               : c[i].recent ? "REGRESSION (recent)" : "regression")
                                              : (c[i].recent ? "improvement (recent)" : "improvement");
        if (format == SB_OUTPUT_CSV) {
            sb_csv row = {0};
            sb_csv_str(&row, label);
            sb_csv_str(&row, host);
            sb_csv_str(&row, c[i].metric);
            sb_csv_int(&row, c[i].night_before);
            sb_csv_int(&row, c[i].night_after);
            sb_csv_str(&row, c[i].date_after);
            sb_csv_num(&row, c[i].before);
            sb_csv_num(&row, c[i].after);
            sb_csv_num(&row, 100 * c[i].rel);
            sb_csv_num(&row, c[i].z);
            sb_csv_num(&row, c[i].p);
            sb_csv_str(&row, c[i].commit_before);
            sb_csv_str(&row, c[i].commit_after);
            sb_csv_str(&row, verdict);
            sb_csv_str(&row, c[i].note);
            sb_csv_str(&row, c[i].machine);
            sb_csv_end_row(&row);
            fputs(row.buf, out);
            sb_csv_free(&row);
        } else {
            char commits[160];
            if (!strcmp(c[i].commit_before, c[i].commit_after)) snprintf(commits, sizeof commits, "%.60s (both)", c[i].commit_after);
            else snprintf(commits, sizeof commits, "%.60s..%.60s", c[i].commit_before, c[i].commit_after);
            fprintf(out, "%-40s %-14s %-6lld %-20s %10.4g %10.4g %+7.1f%% %6.1f %8.2g  %-25s %s\n", label, c[i].metric,
                    c[i].night_after, c[i].date_after, c[i].before, c[i].after, 100 * c[i].rel, c[i].z, c[i].p,
                    commits, verdict);
            if (c[i].machine[0]) fprintf(out, "    %s\n", c[i].machine);
            if (c[i].note[0]) fprintf(out, "    note: %s\n", c[i].note);
        }
    }
}

/* ---- what the report asks ---- */

static void copy_col(char *dst, size_t len, sqlite3_stmt *st, int i) {
    const char *s = (const char *)sqlite3_column_text(st, i);
    snprintf(dst, len, "%s", s ? s : "");
}

int sb_history_nights(sb_history *h, sb_history_night **out, sb_err *err) {
    *out = NULL;
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db,
                           "SELECT n.id, n.date, n.host, n.git_commit, n.renderer, n.version, n.header, n.meta, n.dir, "
                           "count(r.id), sum(r.status = 'ok'), sum(r.status = 'failed'), sum(r.stable = 'no'), "
                           "sum(r.warnings != '') FROM nights n LEFT JOIN runs r ON r.night = n.id GROUP BY n.id "
                           "ORDER BY n.date, n.id",
                           -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading the nights"), -1;
    int n = 0;
    while (sqlite3_step(st) == SQLITE_ROW) {
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
        sb_history_night *x = &(*out)[n++];
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

int sb_history_points(sb_history *h, const char *series, const char *metric, sb_history_point **out, sb_err *err) {
    *out = NULL;
    sb_metric_cols mc;
    if (!sb_columns_metric(metric, &mc)) return sb_fail(err, "unknown metric '%s'", metric), -1;
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db,
                           "SELECT r.night, n.date, r.stable, c.value, i.value, n.git_commit FROM runs r JOIN nights n "
                           "ON n.id = r.night JOIN metrics c ON c.run = r.id AND c.name = ?2 LEFT JOIN metrics i ON "
                           "i.run = r.id AND i.name = ?3 WHERE r.series = ?1 AND r.status = 'ok' ORDER BY n.date, n.id",
                           -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading a series"), -1;
    bind_text(st, 1, series);
    bind_text(st, 2, mc.center);
    bind_text(st, 3, mc.ci[0] ? mc.ci : "-");
    int n = 0;
    while (sqlite3_step(st) == SQLITE_ROW) {
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
        sb_history_point *p = &(*out)[n++];
        p->night = sqlite3_column_int64(st, 0);
        copy_col(p->date, sizeof p->date, st, 1);
        const char *stable = (const char *)sqlite3_column_text(st, 2);
        p->stable = !stable || strcmp(stable, "no");
        p->value = sqlite3_column_double(st, 3);
        p->ci = sqlite3_column_type(st, 4) == SQLITE_NULL ? NAN : sqlite3_column_double(st, 4);
        copy_col(p->commit, sizeof p->commit, st, 5);
    }
    sqlite3_finalize(st);
    return n;
}

/* ---- annotations and what changed on the machine ---- */

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
    if (sqlite3_prepare_v2(h->db, "SELECT id FROM nights WHERE substr(git_commit, 1, length(?1)) = ?1 OR "
                                  "substr(?1, 1, length(git_commit)) = git_commit AND length(git_commit) >= 7 "
                                  "ORDER BY date, id LIMIT 1",
                           -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "reading the nights"), -1;
    bind_text(st, 1, what);
    long long got = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int64(st, 0) : 0;
    sqlite3_finalize(st);
    return got;
}

bool sb_history_annotate(sb_history *h, long long night, const char *commit, const char *series, const char *text,
                         bool accept, sb_err *err) {
    sqlite3_stmt *st;
    char added[64];
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    strftime(added, sizeof added, "%Y-%m-%dT%H:%M:%SZ", &tm);
    if (sqlite3_prepare_v2(h->db, "INSERT INTO annotations(night, git_commit, series, text, accept, added) "
                                  "VALUES (?,?,?,?,?,?)", -1, &st, NULL) != SQLITE_OK)
        return db_fail(h, err, "adding the annotation");
    sqlite3_bind_int64(st, 1, night);
    bind_text(st, 2, commit);
    bind_text(st, 3, series);
    bind_text(st, 4, text);
    sqlite3_bind_int(st, 5, accept);
    bind_text(st, 6, added);
    bool ok = sqlite3_step(st) == SQLITE_DONE;
    sqlite3_finalize(st);
    return ok || db_fail(h, err, "adding the annotation");
}

/* The fields of a night's meta that say what machine and build it ran on, and what a change of each is called. */
static const struct { const char *key, *name; } fingerprint[] = {
    {"gl_renderer", "the renderer"}, {"gl_version", "the driver"}, {"gpu_driver", "the GPU driver"},
    {"kernel", "the kernel"},        {"cpu", "the CPU"},           {"cores", "the core count"},
    {"clocks", "the clocks"},        {"build", "the build"},
};

/* "a b c d" against "a b x d": "c → x" (the words both share at either end left out). */
static void word_diff(const char *a, const char *b, char *out, size_t len) {
    size_t la = strlen(a), lb = strlen(b), pre = 0, suf = 0;
    for (size_t i = 0; i < la && i < lb && a[i] == b[i]; i++)
        if (a[i] == ' ') pre = i + 1;
    for (size_t i = 0; i < la && i < lb && a[la - 1 - i] == b[lb - 1 - i]; i++)
        if (a[la - 1 - i] == ' ') suf = i + 1;
    if (pre + suf > la || pre + suf > lb) suf = 0;
    if (pre + suf > la || pre + suf > lb) pre = 0;
    snprintf(out, len, "%.*s → %.*s", (int)(la - pre - suf), a + pre, (int)(lb - pre - suf), b + pre);
}

/* What differs between two nights' metas ("" when nothing), each field as "the driver<verb>: a → b". */
static void machine_change(const char *before, const char *after, const char *verb, char *out, size_t len) {
    out[0] = 0;
    for (size_t k = 0; k < SB_COUNT(fingerprint); k++) {
        char x[512], y[512], d[1100];
        meta_field(before, fingerprint[k].key, x, sizeof x);
        meta_field(after, fingerprint[k].key, y, sizeof y);
        if (!strcmp(x, y) || !x[0] || !y[0]) continue;   /* a field an older shadowbench did not write is no change */
        word_diff(x, y, d, sizeof d);
        size_t l = strlen(out);
        snprintf(out + l, len - l, "%s%s%s: %s", l ? "; " : "", fingerprint[k].name, verb, d);
    }
}

int sb_history_notes(sb_history *h, sb_history_note **out, sb_err *err) {
    *out = NULL;
    int n = 0;
    sb_history_night *nights = NULL;
    int nn = sb_history_nights(h, &nights, err);
    if (nn < 0) return -1;
    /* the machine: each night against the one before it on its host */
    for (int i = 0; i < nn; i++) {
        int prev = -1;
        for (int j = i - 1; j >= 0 && prev < 0; j--)
            if (!strcmp(nights[j].host, nights[i].host)) prev = j;
        if (prev < 0) continue;
        char what[2048];
        machine_change(nights[prev].meta, nights[i].meta, " changed", what, sizeof what);
        if (!what[0]) continue;
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
        sb_history_note *x = &(*out)[n++];
        memset(x, 0, sizeof *x);
        x->night = nights[i].id;
        x->machine = true;
        snprintf(x->date, sizeof x->date, "%s", nights[i].date);
        snprintf(x->commit, sizeof x->commit, "%s", nights[i].commit);
        snprintf(x->text, sizeof x->text, "%s", what);
        machine_change(nights[prev].meta, nights[i].meta, " changed here too", x->aside, sizeof x->aside);
    }
    sb_history_nights_free(nights, nn);
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(h->db, "SELECT a.night, n.date, a.git_commit, a.series, a.text, a.accept FROM annotations a "
                                  "JOIN nights n ON n.id = a.night ORDER BY n.date, a.id", -1, &st, NULL) != SQLITE_OK) {
        free(*out);
        *out = NULL;
        return db_fail(h, err, "reading the annotations"), -1;
    }
    while (sqlite3_step(st) == SQLITE_ROW) {
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
        sb_history_note *x = &(*out)[n++];
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

bool sb_history_note_matches(const sb_history_note *note, const char *series, const char *label) {
    const char *p = note->series;
    if (!p[0]) return true;
    return !fnmatch(p, label, 0) || !fnmatch(p, series, 0) || strstr(label, p) || strstr(series, p);
}

/* ---- a results set against the nights ---- */

int sb_history_check(sb_history *h, const char *dir, const sb_history_query *q, int nights, FILE *out, sb_err *err) {
    char sum_path[4200];
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    sb_table t;
    if (!sb_table_load(&t, sum_path, err)) return -1;
    char *meta = read_meta(dir);
    char host[256], renderer[512];
    set_host(meta, &t, host, sizeof host, renderer, sizeof renderer);
    double floor = noise_floor(q, renderer);
    const char *metrics[32];
    int nm = 0;
    if (q->nmetrics)
        for (int i = 0; i < q->nmetrics && nm < 32; i++) metrics[nm++] = q->metrics[i];
    else
        nm = sb_columns_default_metrics(SB_USE_HISTORY, metrics, 32);
    int ns = 0;
    char **all = sb_history_series(h, &ns), **labels = sb_history_labels(all, ns);
    int regressions = 0, compared = 0;
    fprintf(out, "%-44s %-14s %10s %10s %23s %8s %6s  %s\n", "series", "metric", "this set", "nights", "band",
            "change", "z", "verdict");
    for (int r = 0; r < t.nrows; r++) {
        char series[4096], size[64], params[2048];
        series_of(&t, r, host, renderer, series, sizeof series, size, sizeof size, params, sizeof params);
        const char *label = NULL;
        for (int i = 0; i < ns; i++)
            if (!strcmp(all[i], series)) label = labels[i];
        if (!label) {
            fprintf(out, "%s %s %s: no series in the history (a new run): nothing to compare\n",
                    sb_table_get(&t, r, "scene"), sb_table_get(&t, r, "technique"), size);
            continue;
        }
        if (strcmp(sb_table_get(&t, r, "status"), "ok")) {
            fprintf(out, "%-44.44s %-14s %s: not compared\n", label, "-", sb_table_get(&t, r, "status"));
            continue;
        }
        for (int mi = 0; mi < nm; mi++) {
            sb_metric_cols mc;
            double x;
            if (!sb_columns_metric(metrics[mi], &mc) || !sb_parse_double(sb_table_get(&t, r, mc.center), &x)) continue;
            sb_history_point *p = NULL;
            int np = sb_history_points(h, series, metrics[mi], &p, err);
            if (np < 0) {
                free(meta);
                sb_table_free(&t);
                return -1;
            }
            int from = np > nights ? np - nights : 0, k = np - from;
            if (k < 3) {
                fprintf(out, "%-44.44s %-14s %10.4g  %d night(s): too few for a band\n", label, metrics[mi], x, k);
                free(p);
                continue;
            }
            /* the detector's noise model over the last k nights: a log scale for positive figures, sigma
               from night-to-night differences floored at the noise floor for timings */
            if (k > 1024) from = np - (k = 1024);
            double raw[1024], v[1024], sorted[1024];
            bool logs = true;   /* as the detector reads them: a log scale when every night's figure is > 0 */
            for (int i = 0; i < k; i++) raw[i] = p[from + i].value, logs = logs && raw[i] > 0;
            for (int i = 0; i < k; i++) v[i] = logs ? log(raw[i]) : raw[i];
            free(p);
            double sigma = 0;
            sb_cp_opts o = {.relative = true, .noise_floor = mc.ci[0] ? floor : 0};
            sb_changepoints(raw, NULL, k, &o, NULL, 0, &sigma);
            memcpy(sorted, v, sizeof *v * (size_t)k);
            qsort(sorted, (size_t)k, sizeof *sorted, cmp_double);
            double med = sb_percentile(sorted, k, 0.5);
            double xs = logs ? (x > 0 ? log(x) : -INFINITY) : x, half = sqrt(SB_CP_PENALTY) * sigma * sqrt(1 + 1.0 / k);
            double z = sigma > 0 ? (xs - med) / (sigma * sqrt(1 + 1.0 / k)) : 0;
            double lo = logs ? exp(med - half) : med - half, hi = logs ? exp(med + half) : med + half;
            double center = logs ? exp(med) : med;
            bool outside = fabs(xs - med) > half;
            bool worse = mc.lower_worse ? xs < med : xs > med;
            const char *verdict = !outside ? "within" : worse ? "REGRESSION" : "improvement";
            regressions += outside && worse;
            compared++;
            char band[64];
            snprintf(band, sizeof band, "[%.4g, %.4g]", lo, hi);
            double rel = center ? x / center - 1 : NAN;
            fprintf(out, "%-44.44s %-14s %10.4g %10.4g %23s %+7.1f%% %6.1f  %s\n", label, metrics[mi], x, center, band,
                    100 * rel, z, verdict);
        }
    }
    for (int i = 0; i < ns; i++) free(all[i]), free(labels[i]);
    free(all);
    free(labels);
    free(meta);
    sb_table_free(&t);
    sb_log("%s: %d figure(s) compared with up to %d night(s) of their series, %d regression(s) beyond the band", dir,
           compared, nights, regressions);
    return regressions;
}
