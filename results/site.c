/* site.c - the report site (site.h). */
#include "site.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
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

/* The pages' shells: each loads the assets and calls SB.start(kind); home is the header's link. */
static bool write_shells(const char *site, const char *const *kinds, size_t nk, const char *home, sb_err *err) {
    for (size_t k = 0; k < nk; k++) {
        char path[4400], html[2048];
        snprintf(path, sizeof path, "%s/%s.html", site, kinds[k]);
        int n = snprintf(html, sizeof html,
                         "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
                         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                         "<title>shadowbench report</title>\n"
                         "<link rel=\"stylesheet\" href=\"assets/dygraph.min.css\">\n"
                         "<link rel=\"stylesheet\" href=\"assets/app.css\">\n"
                         "<script src=\"assets/dygraph.min.js\"></script>\n"
                         "<script src=\"assets/app.js\"></script>\n"
                         "</head><body data-page=\"%s\">\n<header><a href=\"%s.html\">shadowbench</a> "
                         "<span id=\"crumbs\"></span></header>\n<main id=\"main\"><p>Loading&hellip;</p></main>\n"
                         "<footer>Charts: <a href=\"assets/LICENSE-dygraphs.txt\">dygraphs</a> (MIT).</footer>\n"
                         "<script>SB.start(\"%s\");</script>\n</body></html>\n",
                         kinds[k], home, kinds[k]);
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

/* A table as JSON, the one writer for every table of the site: "columns":[...],"rows":[[...],...], each cell a
 * number where it is one (cell(src, -1, c) is column c's name). */
static void jtable(jbuf *j, int ncols, int nrows, const char *(*cell)(const void *src, int r, int c), const void *src) {
    jput(j, "\"columns\":[");
    for (int c = 0; c < ncols; c++) jput(j, c ? "," : ""), jstr(j, cell(src, -1, c));
    jput(j, "],\"rows\":[");
    for (int r = 0; r < nrows; r++) {
        jput(j, r ? ",[" : "[");
        for (int c = 0; c < ncols; c++) jput(j, c ? "," : ""), jcell(j, cell(src, r, c));
        jput(j, "]");
    }
    jput(j, "]");
}
static const char *summary_cell(const void *src, int r, int c) {
    const sb_table *t = src;
    return r < 0 ? t->header[c] : t->rows[r][c];
}
static const char *pair_cell(const void *src, int r, int c) {
    const sb_pair_table *t = src;
    return r < 0 ? t->head[c] : t->cells[r][c];
}

/* The pairs users compare (PSSM against SDSM, layered against per-cascade, PSSM's four 2048² cascades against a
 * cached virtual map), as compare --pair makes them. */
static void night_pairs(const sb_table *summary, jbuf *j) {
    static const char *const keys[] = {"technique=pssm,sdsm", "layered=off,on", "layered=off,gs",
                                       "technique=pssm:res=2048:layered=off:stable=off,virtual:cache=on"};
    jput(j, "[");
    bool first = true;
    for (size_t k = 0; k < SB_COUNT(keys); k++) {
        sb_compare_opts o = {.pair = keys[k], .threshold_pct = 5};
        sb_pair_table pt;
        sb_err e;
        if (sb_compare_pair_table(summary, &o, &pt, &e) > 0) {
            jput(j, first ? "{" : ",{");
            first = false;
            jkey(j, "key");
            jstr(j, keys[k]);
            jput(j, ",");
            jtable(j, pt.ncols, pt.nrows, pair_cell, &pt);
            jsfield(j, "shared", pt.shared);
            jput(j, "}");
        }
        sb_pair_table_free(&pt);
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

typedef struct {
    jbuf *j;
    const char **cols;
    int ncols;
    bool first;
} frames_json;

static void frame_run(const char *run_id, const char *csv, void *arg) {
    frames_json *fj = arg;
    sb_table t;
    sb_err e;
    if (!sb_table_parse(&t, "frames", csv, &e)) return;
    int idx[MAX_FRAME_COLS];
    for (int c = 0; c < fj->ncols; c++) idx[c] = sb_table_col(&t, fj->cols[c]);
    jput(fj->j, fj->first ? "" : ",");
    fj->first = false;
    jkey(fj->j, run_id);
    jput(fj->j, "[");
    for (int r = 0; r < t.nrows; r++) {
        jput(fj->j, r ? ",[" : "[");
        for (int c = 0; c < fj->ncols; c++) {
            jput(fj->j, c ? "," : "");
            if (idx[c] < 0) jput(fj->j, "null");
            else jcell(fj->j, t.rows[r][idx[c]]);
        }
        jput(fj->j, "]");
    }
    jput(fj->j, "]");
    sb_table_free(&t);
}

static bool write_frames(sb_history *h, const char *site, long long id, sb_err *err) {
    jbuf j = {0};
    const char *cols[MAX_FRAME_COLS], *stages[MAX_FRAME_COLS];
    int ncols = frame_cols(cols, false), nstages = frame_cols(stages, true);
    jput(&j, "{\"kind\":\"frames\",\"columns\":[");
    for (int c = 0; c < ncols; c++) jput(&j, c ? "," : ""), jstr(&j, cols[c]);
    jput(&j, "],\"stages\":[");   /* the stacked chart's series, in stage order */
    for (int c = 0; c < nstages; c++) jput(&j, c ? "," : ""), jstr(&j, stages[c]);
    jput(&j, "],\"runs\":{");
    frames_json fj = {&j, cols, ncols, true};
    bool ok = sb_history_night_frames(h, id, frame_run, &fj, err);
    jput(&j, "}}");
    char name[64];
    snprintf(name, sizeof name, "frames-%lld.js", id);
    ok = ok && write_data(site, name, &j, err);
    free(j.buf);
    return ok;
}

/* The notes (annotations and machine changes) that pass `keep`, as a JSON list. */
static void jnotes(jbuf *j, const sb_history_note *notes, int n, bool (*keep)(const sb_history_note *, const void *),
                   const void *arg) {
    jput(j, "[");
    int k = 0;
    for (int i = 0; i < n; i++) {
        if (keep && !keep(&notes[i], arg)) continue;
        jput(j, k++ ? ",{\"night\":" : "{\"night\":");
        jnum(j, (double)notes[i].night);
        jsfield(j, "date", notes[i].date);
        jsfield(j, "commit", notes[i].commit);
        jsfield(j, "series", notes[i].series);
        jsfield(j, "text", notes[i].text);
        jput(j, notes[i].accept ? ",\"accept\":true" : ",\"accept\":false");
        jput(j, notes[i].machine ? ",\"machine\":true}" : ",\"machine\":false}");
    }
    jput(j, "]");
}
static bool note_of_night(const sb_history_note *n, const void *arg) { return n->night == *(const long long *)arg; }
typedef struct { const char *series, *label; } series_ref;
static bool note_of_series(const sb_history_note *n, const void *arg) {
    const series_ref *r = arg;
    return sb_history_note_matches(n, r->series, r->label);
}

static bool write_night(sb_history *h, const char *site, const sb_history_night *n, const sb_history_note *notes,
                        int nnotes, sb_err *err) {
    /* the summary as it was, for the table and for the pairs */
    char *text = sb_history_night_summary(h, n, err);
    sb_table t;
    if (!text || !sb_table_parse(&t, "summary", text, err)) {
        free(text);
        return false;
    }
    jbuf j = {0};
    jput(&j, "{\"kind\":\"night\",");
    jkey(&j, "id");
    jnum(&j, (double)n->id);
    const char *keys[] = {"date", "host", "commit", "renderer", "version", "meta", "dir"};
    const char *vals[] = {n->date, n->host, n->commit, n->renderer, n->version, n->meta, n->dir};
    for (size_t k = 0; k < SB_COUNT(keys); k++) jsfield(&j, keys[k], vals[k]);
    jput(&j, ",");
    jtable(&j, t.cols, t.nrows, summary_cell, &t);
    jput(&j, ",\"pairs\":");
    night_pairs(&t, &j);
    jput(&j, ",\"images\":");
    night_images(site, n->id, n->dir, &j);
    jput(&j, ",\"notes\":");
    jnotes(&j, notes, nnotes, note_of_night, &n->id);
    jput(&j, "}");
    sb_table_free(&t);
    free(text);
    char name[64];
    snprintf(name, sizeof name, "night-%lld.js", n->id);
    bool ok = write_data(site, name, &j, err) && write_frames(h, site, n->id, err);
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
    jput(j, c->accepted ? ",\"accepted\":true" : ",\"accepted\":false");
    jsfield(j, "note", c->note);
    jsfield(j, "machine", c->machine);
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

static bool write_series(sb_history *h, const char *site, char **series, char **labels, int ns,
                         const sb_history_change *ch, int nch, const sb_history_note *notes, int nnotes, sb_err *err) {
    const char *trend_metrics[32];   /* the SB_USE_REPORT metrics of the column table */
    int ntrend = sb_columns_default_metrics(SB_USE_REPORT, trend_metrics, 32);
    bool ok = true;
    for (int s = 0; ok && s < ns; s++) {
        jbuf j = {0};
        jput(&j, "{\"kind\":\"series\"");
        jsfield(&j, "series", series[s]);
        jsfield(&j, "label", labels[s]);
        jput(&j, ",\"notes\":");
        series_ref ref = {series[s], labels[s]};
        jnotes(&j, notes, nnotes, note_of_series, &ref);
        jput(&j, ",\"metrics\":{");
        for (int m = 0; ok && m < ntrend; m++) {
            sb_history_point *pt = NULL;
            int np = sb_history_points(h, series[s], trend_metrics[m], &pt, err);
            ok = np >= 0;
            jput(&j, m ? "," : "");
            jkey(&j, trend_metrics[m]);
            jput(&j, "{\"nights\":[");
            for (int k = 0; k < np; k++) {
                jput(&j, k ? ",[" : "[");
                jnum(&j, (double)pt[k].night);
                jput(&j, ",");
                jstr(&j, pt[k].date);
                jput(&j, ",");
                jnum(&j, pt[k].value);
                jput(&j, ",");
                jnum(&j, pt[k].ci);
                jput(&j, pt[k].stable ? ",true," : ",false,");
                jstr(&j, pt[k].commit);
                jput(&j, "]");
            }
            free(pt);
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
        ok = ok && write_data(site, name, &j, err);
        free(j.buf);
    }
    return ok;
}

/* ---- the site ---- */

static bool write_site(sb_history *h, const sb_site_opts *o, bool single, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/data", o->out);
    static const char *const kinds[] = {"index", "night", "run", "series"};
    if (!sb_mkdir_p(path, err) || !write_assets(o->out, err) || !write_shells(o->out, kinds, SB_COUNT(kinds), "index", err))
        return false;
    /* changes first: the index lists them and the series pages draw them */
    sb_history_query q = {.recent = o->recent};
    sb_history_change *ch = NULL;
    int nch = sb_history_changes(h, &q, &ch, err);
    if (nch < 0) return false;
    sb_history_note *notes = NULL;
    int nnotes = sb_history_notes(h, &notes, err);
    if (nnotes < 0) {
        free(ch);
        return false;
    }
    sb_history_night *nights = NULL;
    int nn = sb_history_nights(h, &nights, err);
    int ns = 0;
    char **series = sb_history_series(h, &ns), **labels = sb_history_labels(series, ns);
    bool ok = nn >= 0;
    jbuf j = {0};
    jput(&j, "{\"kind\":\"index\",");
    jput(&j, single ? "\"single\":true," : "\"single\":false,");
    jkey(&j, "source");
    jstr(&j, o->dir ? o->dir : o->history);
    jput(&j, ",\"nights\":[");
    for (int k = 0; ok && k < nn; k++) {
        const sb_history_night *n = &nights[k];
        jput(&j, k ? ",{" : "{");
        jput(&j, "\"id\":");
        jnum(&j, (double)n->id);
        const char *keys[] = {"date", "host", "commit", "renderer"};
        const char *vals[] = {n->date, n->host, n->commit, n->renderer};
        for (int c = 0; c < 4; c++) jsfield(&j, keys[c], vals[c]);
        const char *counts[] = {"runs", "ok", "failed", "unstable", "warned"};
        const int nums[] = {n->runs, n->ok, n->failed, n->unstable, n->warned};
        for (int c = 0; c < 5; c++) jnfield(&j, counts[c], nums[c]);
        jput(&j, "}");
        ok = write_night(h, o->out, n, notes, nnotes, err);
    }
    jput(&j, "],\"changes\":[");
    for (int c = 0; c < nch; c++) {
        jput(&j, c ? "," : "");
        jchange(&j, &ch[c], series_index(series, ns, ch[c].series));
    }
    jput(&j, "],\"notes\":");
    jnotes(&j, notes, nnotes, NULL, NULL);
    jput(&j, ",\"series\":[");
    for (int s = 0; s < ns; s++) jput(&j, s ? "," : ""), jstr(&j, series[s]);
    jput(&j, "],\"labels\":[");
    for (int s = 0; s < ns; s++) jput(&j, s ? "," : ""), jstr(&j, labels[s]);
    jput(&j, "]}");
    ok = ok && write_data(o->out, "index.js", &j, err) && write_series(h, o->out, series, labels, ns, ch, nch, notes, nnotes, err);
    free(j.buf);
    for (int s = 0; s < ns; s++) free(series[s]), free(labels[s]);
    free(series);
    free(labels);
    free(ch);
    free(notes);
    if (nn > 0) sb_history_nights_free(nights, nn);
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

bool sb_site_write_front(const sb_site_front *f, sb_err *err) {
    if (!sb_site_available())
        return sb_fail(err, "this shadowbench was built without the charting library (Debian's libjs-dygraphs; "
                            "scripts/setup installs it)");
    char path[4400];
    snprintf(path, sizeof path, "%s/data", f->out);
    static const char *const kinds[] = {"front"};
    if (!sb_mkdir_p(path, err) || !write_assets(f->out, err) || !write_shells(f->out, kinds, 1, "front", err))
        return false;
    jbuf j = {0};
    jput(&j, "{\"kind\":\"front\"");
    jsfield(&j, "title", f->title);
    jsfield(&j, "about", f->about);
    jsfield(&j, "xlabel", f->xlabel);
    jsfield(&j, "ylabel", f->ylabel);
    jnfield(&j, "bound", f->bound > 0 ? f->bound : NAN);
    jsfield(&j, "bound_on", f->bound_on_x ? "x" : "y");
    jsfield(&j, "chosen_is", f->chosen_is ? f->chosen_is : "chosen");
    jput(&j, ",\"points\":[");
    for (int i = 0; i < f->n; i++) {
        const sb_site_point *p = &f->points[i];
        jput(&j, i ? ",{" : "{");
        jkey(&j, "technique");
        jstr(&j, p->technique);
        jsfield(&j, "label", p->label);
        jnfield(&j, "x", p->x);
        jnfield(&j, "y", p->y);
        jnfield(&j, "frames", p->frames);
        jput(&j, p->front ? ",\"front\":true" : ",\"front\":false");
        jput(&j, p->chosen ? ",\"chosen\":true}" : ",\"chosen\":false}");
    }
    jput(&j, "]}");
    bool ok = write_data(f->out, "front.js", &j, err);
    free(j.buf);
    return ok;
}
