/* site.c - the report site (site.h). */
#include "site.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "compare.h"
#include "history.h"
#include "columns.h"
#include "site_assets.h"
#include "table.h"

bool sb_site_available(void) { return sb_asset_dygraph_min_js_len > 0; }

/* ---- JSON into a growable buffer ---- */

typedef struct {
    char *buf;
    size_t len, cap;
} jbuf;

static void jraw(jbuf *j, const char *s, size_t n) {
    if (j->len + n + 1 > j->cap) {
        j->cap = (j->len + n + 1) * 2;
        j->buf = sb_xrealloc(j->buf, j->cap);
    }
    memcpy(j->buf + j->len, s, n);
    j->len += n;
    j->buf[j->len] = 0;
}
static void jput(jbuf *j, const char *s) { jraw(j, s, strlen(s)); }
static void jstr(jbuf *j, const char *s) {
    jraw(j, "\"", 1);
    for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; p++) {
        char e[8];
        if (*p == '"' || *p == '\\') e[0] = '\\', e[1] = (char)*p, e[2] = 0;
        else if (*p == '\n') strcpy(e, "\\n");
        else if (*p == '<') strcpy(e, "\\u003c");   /* never "</script>" inside a script */
        else if (*p < 0x20) snprintf(e, sizeof e, "\\u%04x", *p);
        else e[0] = (char)*p, e[1] = 0;
        jput(j, e);
    }
    jraw(j, "\"", 1);
}
static void jnum(jbuf *j, double v) {
    char b[40];
    if (!isfinite(v)) snprintf(b, sizeof b, "null");
    else snprintf(b, sizeof b, "%.6g", v);
    jput(j, b);
}
static void jkey(jbuf *j, const char *k) {
    jstr(j, k);
    jraw(j, ":", 1);
}
/* ,"key":"text" and ,"key":number (the first field of an object: start the object with '{' and no comma) */
static void jsfield(jbuf *j, const char *k, const char *v) {
    jput(j, ",");
    jkey(j, k);
    jstr(j, v);
}
static void jnfield(jbuf *j, const char *k, double v) {
    jput(j, ",");
    jkey(j, k);
    jnum(j, v);
}

/* a CSV cell as a JSON number when it is one, else a string (empty: null) */
static void jcell(jbuf *j, const char *s) {
    double v;
    if (!*s) jput(j, "null");
    else if (sb_parse_double(s, &v) && isfinite(v)) jnum(j, v);
    else jstr(j, s);
}

static bool write_data(const char *site, const char *name, jbuf *j, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/data/%s", site, name);
    jbuf f = {0};
    jput(&f, "SB.data(");
    jraw(&f, j->buf ? j->buf : "null", j->buf ? j->len : 4);
    jput(&f, ");\n");
    bool ok = sb_write_file_atomic(path, f.buf, f.len, err);
    free(f.buf);
    return ok;
}

/* ---- files ---- */

static bool link_or_copy(const char *from, const char *to, sb_err *err) {
    unlink(to);
    return link(from, to) == 0 || sb_copy_file(from, to, err);   /* same filesystem: no copy */
}

static const char *const page_kinds[] = {"index", "night", "run", "series"};

static bool write_shells(const char *site, sb_err *err) {
    for (size_t k = 0; k < SB_COUNT(page_kinds); k++) {
        char path[4400], html[2048];
        snprintf(path, sizeof path, "%s/%s.html", site, page_kinds[k]);
        int n = snprintf(html, sizeof html,
                         "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
                         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                         "<title>shadowbench report</title>\n"
                         "<link rel=\"stylesheet\" href=\"assets/dygraph.min.css\">\n"
                         "<link rel=\"stylesheet\" href=\"assets/app.css\">\n"
                         "<script src=\"assets/dygraph.min.js\"></script>\n"
                         "<script src=\"assets/app.js\"></script>\n"
                         "</head><body data-page=\"%s\">\n<header><a href=\"index.html\">shadowbench</a> "
                         "<span id=\"crumbs\"></span></header>\n<main id=\"main\"><p>Loading&hellip;</p></main>\n"
                         "<footer>Charts: <a href=\"assets/LICENSE-dygraphs.txt\">dygraphs</a> (MIT).</footer>\n"
                         "<script>SB.start(\"%s\");</script>\n</body></html>\n",
                         page_kinds[k], page_kinds[k]);
        if (!sb_write_file_atomic(path, html, (size_t)n, err)) return false;
    }
    return true;
}

static bool write_assets(const char *site, sb_err *err) {
    struct { const char *name; const char *data; size_t len; } a[] = {
        {"dygraph.min.js", sb_asset_dygraph_min_js, sb_asset_dygraph_min_js_len},
        {"dygraph.min.css", sb_asset_dygraph_min_css, sb_asset_dygraph_min_css_len},
        {"LICENSE-dygraphs.txt", sb_asset_dygraphs_copyright, sb_asset_dygraphs_copyright_len},
        {"app.js", sb_asset_app_js, sb_asset_app_js_len},
        {"app.css", sb_asset_app_css, sb_asset_app_css_len},
    };
    char path[4400];
    snprintf(path, sizeof path, "%s/assets", site);
    if (!sb_mkdir_p(path, err)) return false;
    for (size_t i = 0; i < SB_COUNT(a); i++) {
        snprintf(path, sizeof path, "%s/assets/%s", site, a[i].name);
        if (!sb_write_file_atomic(path, a[i].data, a[i].len, err)) return false;
    }
    return true;
}

/* ---- the pieces of a page's data ---- */

static const char *col(sqlite3_stmt *st, int i) {
    const char *s = (const char *)sqlite3_column_text(st, i);
    return s ? s : "";
}

static bool prep(sqlite3 *db, const char *sql, sqlite3_stmt **st, sb_err *err) {
    if (sqlite3_prepare_v2(db, sql, -1, st, NULL) == SQLITE_OK) return true;
    return sb_fail(err, "report: %s", sqlite3_errmsg(db));
}

/* The pairs users compare (PSSM against SDSM, layered against per-cascade), as compare --pair makes them. */
static void night_pairs(const char *summary_path, jbuf *j) {
    static const char *const keys[] = {"technique=pssm,sdsm", "layered=off,on", "layered=off,gs"};
    jput(j, "[");
    bool first = true;
    for (size_t k = 0; k < SB_COUNT(keys); k++) {
        char *text = NULL;
        size_t len = 0;
        FILE *mem = open_memstream(&text, &len);
        if (!mem) continue;
        sb_compare_opts o = {.format = SB_OUTPUT_CSV, .pair = keys[k], .threshold_pct = 5};
        sb_err e;
        int n = sb_compare_pairs(summary_path, &o, mem, &e);
        fclose(mem);
        sb_table t;
        if (n > 0 && sb_table_parse(&t, "pairs", text, &e)) {
            jput(j, first ? "" : ",");
            first = false;
            jput(j, "{");
            jkey(j, "key");
            jstr(j, keys[k]);
            jput(j, ",");
            jkey(j, "columns");
            jput(j, "[");
            for (int c = 0; c < t.cols; c++) jput(j, c ? "," : ""), jstr(j, t.header[c]);
            jput(j, "],");
            jkey(j, "rows");
            jput(j, "[");
            for (int r = 0; r < t.nrows; r++) {
                jput(j, r ? ",[" : "[");
                for (int c = 0; c < t.cols; c++) jput(j, c ? "," : ""), jcell(j, t.rows[r][c]);
                jput(j, "]");
            }
            jput(j, "]}");
            sb_table_free(&t);
        }
        free(text);
    }
    jput(j, "]");
}

/* The night's images: copied into images/ID/, listed by run and frame. */
static void night_images(const char *site, long long id, const char *dir, jbuf *j) {
    char from[4400], to[4400];
    snprintf(from, sizeof from, "%s/images", dir);
    DIR *d = opendir(from);
    jput(j, "[");
    if (!d) {
        jput(j, "]");
        return;
    }
    snprintf(to, sizeof to, "%s/images/%lld", site, id);
    sb_err e;
    bool first = true;
    if (sb_mkdir_p(to, &e)) {
        struct dirent *de;
        while ((de = readdir(d))) {
            size_t l = strlen(de->d_name);
            if (l < 5 || strcmp(de->d_name + l - 4, ".png")) continue;
            char a[4800], b[4800];
            snprintf(a, sizeof a, "%s/%s", from, de->d_name);
            snprintf(b, sizeof b, "%s/%s", to, de->d_name);
            if (!link_or_copy(a, b, &e)) continue;
            jput(j, first ? "" : ",");
            first = false;
            jstr(j, de->d_name);
        }
    }
    closedir(d);
    jput(j, "]");
}

/* Per-frame figures of every run of a night, only the columns the run page draws: the stage times
 * (every SB_COL_STAGE_TIME column, named from sb_stage_names) and these. */
static const char *const drawn_cols[] = {"frame", "repeat", "gpu_ms", "draw_calls", "shadow_draw_calls", "triangles",
                                         "shadow_triangles", "err_rate"};
enum { MAX_FRAME_COLS = 32 };

static int frame_cols(const char **out, bool stages_only) {
    int n = 0, nf;
    const sb_frame_col *fc = sb_frame_cols(&nf);
    for (size_t c = 0; c < SB_COUNT(drawn_cols) && !stages_only; c++) out[n++] = drawn_cols[c];
    for (int k = 0; k < nf && n < MAX_FRAME_COLS; k++)
        if (fc[k].flags & SB_COL_STAGE_TIME) out[n++] = fc[k].name;
    return n;
}

static bool write_frames(sqlite3 *db, const char *site, long long id, sb_err *err) {
    sqlite3_stmt *st;
    if (!prep(db, "SELECT r.run_id, f.csv FROM frames f JOIN runs r ON r.id = f.run WHERE r.night = ?", &st, err))
        return false;
    sqlite3_bind_int64(st, 1, id);
    jbuf j = {0};
    const char *cols[MAX_FRAME_COLS], *stages[MAX_FRAME_COLS];
    int ncols = frame_cols(cols, false), nstages = frame_cols(stages, true);
    jput(&j, "{\"kind\":\"frames\",\"columns\":[");
    for (int c = 0; c < ncols; c++) jput(&j, c ? "," : ""), jstr(&j, cols[c]);
    jput(&j, "],\"stages\":[");   /* the stacked chart's series, in stage order */
    for (int c = 0; c < nstages; c++) jput(&j, c ? "," : ""), jstr(&j, stages[c]);
    jput(&j, "],\"runs\":{");
    bool first = true;
    while (sqlite3_step(st) == SQLITE_ROW) {
        sb_table t;
        sb_err e;
        if (!sb_table_parse(&t, "frames", col(st, 1), &e)) continue;
        int idx[MAX_FRAME_COLS];
        for (int c = 0; c < ncols; c++) idx[c] = sb_table_col(&t, cols[c]);
        jput(&j, first ? "" : ",");
        first = false;
        jkey(&j, col(st, 0));
        jput(&j, "[");
        for (int r = 0; r < t.nrows; r++) {
            jput(&j, r ? ",[" : "[");
            for (int c = 0; c < ncols; c++) {
                jput(&j, c ? "," : "");
                if (idx[c] < 0) jput(&j, "null");
                else jcell(&j, t.rows[r][idx[c]]);
            }
            jput(&j, "]");
        }
        jput(&j, "]");
        sb_table_free(&t);
    }
    sqlite3_finalize(st);
    jput(&j, "}}");
    char name[64];
    snprintf(name, sizeof name, "frames-%lld.js", id);
    bool ok = write_data(site, name, &j, err);
    free(j.buf);
    return ok;
}

static bool write_night(sqlite3 *db, const char *site, sqlite3_stmt *n, sb_err *err) {
    long long id = sqlite3_column_int64(n, 0);
    const char *header = col(n, 6), *dir = col(n, 8);
    /* the summary as it was, for the table and for compare --pair */
    jbuf sum = {0};
    jput(&sum, header);
    jput(&sum, "\n");
    sqlite3_stmt *st;
    if (!prep(db, "SELECT line FROM runs WHERE night = ? ORDER BY run_index, id", &st, err)) return false;
    sqlite3_bind_int64(st, 1, id);
    while (sqlite3_step(st) == SQLITE_ROW) jput(&sum, col(st, 0)), jput(&sum, "\n");
    sqlite3_finalize(st);
    char tmp[4400];
    snprintf(tmp, sizeof tmp, "%s/data/.summary-%lld.csv", site, id);
    bool ok = sb_write_file_atomic(tmp, sum.buf, sum.len, err);
    sb_table t;
    ok = ok && sb_table_parse(&t, tmp, sum.buf, err);
    if (!ok) {
        free(sum.buf);
        return false;
    }
    jbuf j = {0};
    jput(&j, "{\"kind\":\"night\",");
    jkey(&j, "id");
    jnum(&j, (double)id);
    const char *keys[] = {"date", "host", "commit", "renderer", "version"};
    const int cols[] = {1, 2, 3, 4, 5};
    for (size_t k = 0; k < SB_COUNT(keys); k++) jsfield(&j, keys[k], col(n, cols[k]));
    jsfield(&j, "meta", col(n, 7));
    jsfield(&j, "dir", dir);
    jput(&j, ",\"columns\":[");
    for (int c = 0; c < t.cols; c++) jput(&j, c ? "," : ""), jstr(&j, t.header[c]);
    jput(&j, "],\"rows\":[");
    for (int r = 0; r < t.nrows; r++) {
        jput(&j, r ? ",[" : "[");
        for (int c = 0; c < t.cols; c++) jput(&j, c ? "," : ""), jcell(&j, t.rows[r][c]);
        jput(&j, "]");
    }
    jput(&j, "],\"pairs\":");
    night_pairs(tmp, &j);
    jput(&j, ",\"images\":");
    night_images(site, id, dir, &j);
    jput(&j, "}");
    unlink(tmp);
    sb_table_free(&t);
    free(sum.buf);
    char name[64];
    snprintf(name, sizeof name, "night-%lld.js", id);
    ok = write_data(site, name, &j, err) && write_frames(db, site, id, err);
    free(j.buf);
    return ok;
}

/* ---- series and changes ---- */


static void jchange(jbuf *j, const sb_history_change *c, int sid) {
    jput(j, "{\"sid\":");
    jnum(j, sid);
    jsfield(j, "series", c->series);
    jsfield(j, "label", c->label);
    jsfield(j, "metric", c->metric);
    jnfield(j, "night_before", (double)c->night_before);
    jnfield(j, "night_after", (double)c->night_after);
    jsfield(j, "date_after", c->date_after);
    jsfield(j, "commit_before", c->commit_before);
    jsfield(j, "commit_after", c->commit_after);
    jnfield(j, "before", c->before);
    jnfield(j, "after", c->after);
    jnfield(j, "rel", c->rel);
    jnfield(j, "z", c->z);
    jnfield(j, "p", c->p);
    jput(j, c->regression ? ",\"regression\":true" : ",\"regression\":false");
    jput(j, c->recent ? ",\"recent\":true}" : ",\"recent\":false}");
}

static int series_index(char **series, int ns, const char *s) {
    int lo = 0, hi = ns - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2, c = strcmp(series[mid], s);
        if (!c) return mid;
        if (c < 0) lo = mid + 1;
        else hi = mid - 1;
    }
    return -1;
}

static bool write_series(sqlite3 *db, const char *site, char **series, char **labels, int ns,
                         const sb_history_change *ch, int nch, sb_err *err) {
    sqlite3_stmt *st;
    if (!prep(db,
              "SELECT r.night, n.date, r.stable, c.value, i.value, n.git_commit FROM runs r JOIN nights n ON "
              "n.id = r.night JOIN metrics c ON c.run = r.id AND c.name = ?2 LEFT JOIN metrics i ON i.run = r.id AND "
              "i.name = ?3 WHERE r.series = ?1 AND r.status = 'ok' ORDER BY n.date, n.id",
              &st, err))
        return false;
    bool ok = true;
    for (int s = 0; ok && s < ns; s++) {
        jbuf j = {0};
        jput(&j, "{\"kind\":\"series\"");
        jsfield(&j, "series", series[s]);
        jsfield(&j, "label", labels[s]);
        jput(&j, ",\"metrics\":{");
        const char *trend_metrics[32];   /* the SB_USE_REPORT metrics of the column table */
        int ntrend = sb_columns_default_metrics(SB_USE_REPORT, trend_metrics, 32);
        for (int m = 0; m < ntrend; m++) {
            sb_metric_cols mc;
            if (!sb_columns_metric(trend_metrics[m], &mc)) continue;
            sqlite3_reset(st);
            sqlite3_bind_text(st, 1, series[s], -1, SQLITE_STATIC);
            sqlite3_bind_text(st, 2, mc.center, -1, SQLITE_STATIC);
            sqlite3_bind_text(st, 3, mc.ci[0] ? mc.ci : "-", -1, SQLITE_STATIC);
            jput(&j, m ? "," : "");
            jkey(&j, trend_metrics[m]);
            jput(&j, "{\"nights\":[");
            int k = 0;
            while (sqlite3_step(st) == SQLITE_ROW) {
                jput(&j, k++ ? ",[" : "[");
                jnum(&j, (double)sqlite3_column_int64(st, 0));
                jput(&j, ",");
                jstr(&j, col(st, 1));
                jput(&j, ",");
                jnum(&j, sqlite3_column_double(st, 3));
                jput(&j, ",");
                if (sqlite3_column_type(st, 4) == SQLITE_NULL) jput(&j, "null");
                else jnum(&j, sqlite3_column_double(st, 4));
                jput(&j, !strcmp(col(st, 2), "no") ? ",false," : ",true,");
                jstr(&j, col(st, 5));
                jput(&j, "]");
            }
            jput(&j, "],\"changes\":[");
            int nc = 0;
            for (int c = 0; c < nch; c++)
                if (!strcmp(ch[c].series, series[s]) && !strcmp(ch[c].metric, trend_metrics[m]))
                    jput(&j, nc++ ? "," : ""), jchange(&j, &ch[c], s);
            jput(&j, "]}");
        }
        jput(&j, "}}");
        char name[64];
        snprintf(name, sizeof name, "series-%d.js", s);
        ok = write_data(site, name, &j, err);
        free(j.buf);
    }
    sqlite3_finalize(st);
    return ok;
}

/* ---- the site ---- */

static bool write_site(sb_history *h, const sb_site_opts *o, bool single, sb_err *err) {
    sqlite3 *db = sb_history_db(h);
    char path[4400];
    snprintf(path, sizeof path, "%s/data", o->out);
    if (!sb_mkdir_p(path, err) || !write_assets(o->out, err) || !write_shells(o->out, err)) return false;
    /* changes first: the index lists them and the series pages draw them */
    sb_history_query q = {.recent = o->recent};
    sb_history_change *ch = NULL;
    int nch = sb_history_changes(h, &q, &ch, err);
    if (nch < 0) return false;
    int ns = 0;
    char **series = sb_history_series(h, &ns), **labels = sb_history_labels(series, ns);
    sqlite3_stmt *st = NULL;
    bool ok = true;
    jbuf j = {0};
    jput(&j, "{\"kind\":\"index\",");
    jput(&j, single ? "\"single\":true," : "\"single\":false,");
    jkey(&j, "source");
    jstr(&j, o->dir ? o->dir : o->history);
    jput(&j, ",\"nights\":[");
    ok = ok && prep(db,
                    "SELECT n.id, n.date, n.host, n.git_commit, n.renderer, n.version, n.header, n.meta, n.dir, "
                    "count(r.id), sum(r.status = 'ok'), sum(r.status = 'failed'), sum(r.stable = 'no'), "
                    "sum(r.warnings != '') FROM nights n LEFT JOIN runs r ON r.night = n.id GROUP BY n.id "
                    "ORDER BY n.date, n.id",
                    &st, err);
    int k = 0;
    while (ok && sqlite3_step(st) == SQLITE_ROW) {
        jput(&j, k++ ? ",{" : "{");
        jput(&j, "\"id\":");
        jnum(&j, (double)sqlite3_column_int64(st, 0));
        const char *keys[] = {"date", "host", "commit", "renderer"};
        for (int c = 0; c < 4; c++) jsfield(&j, keys[c], col(st, c + 1));
        const char *counts[] = {"runs", "ok", "failed", "unstable", "warned"};
        for (int c = 0; c < 5; c++) jnfield(&j, counts[c], sqlite3_column_int(st, c + 9));
        jput(&j, "}");
        ok = write_night(db, o->out, st, err);
    }
    if (st) sqlite3_finalize(st);
    jput(&j, "],\"changes\":[");
    for (int c = 0; c < nch; c++) {
        jput(&j, c ? "," : "");
        jchange(&j, &ch[c], series_index(series, ns, ch[c].series));
    }
    jput(&j, "],\"series\":[");
    for (int s = 0; s < ns; s++) jput(&j, s ? "," : ""), jstr(&j, series[s]);
    jput(&j, "],\"labels\":[");
    for (int s = 0; s < ns; s++) jput(&j, s ? "," : ""), jstr(&j, labels[s]);
    jput(&j, "]}");
    ok = ok && write_data(o->out, "index.js", &j, err) && write_series(db, o->out, series, labels, ns, ch, nch, err);
    free(j.buf);
    for (int s = 0; s < ns; s++) free(series[s]), free(labels[s]);
    free(series);
    free(labels);
    free(ch);
    return ok;
}

bool sb_site_write(const sb_site_opts *o, sb_err *err) {
    if (!sb_site_available())
        return sb_fail(err, "report: this shadowbench was built without the charting library (Debian's "
                            "libjs-dygraphs; scripts/setup installs it), rebuild after installing it");
    sb_history *h;
    if (o->dir) {   /* one results set: a history of one night, in memory */
        h = sb_history_open(":memory:", true, err);
        sb_history_added a;
        if (h && !sb_history_add(h, o->dir, &a, err)) {
            sb_history_close(h);
            return false;
        }
    } else {
        h = sb_history_open(o->history, false, err);
    }
    if (!h) return false;
    bool ok = write_site(h, o, o->dir != NULL, err);
    sb_history_close(h);
    return ok;
}
