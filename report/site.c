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
#include "json.h"
#include "site_assets.h"
#include "table.h"

bool sb_site_available(void) { return sb_asset_dygraph_min_js_len > 0; }

/* ---- data files: JSON through the one writer (json.h) ---- */

/* a CSV cell as a JSON number when it is one, else a string (empty: null) */
static void jcell(sb_jw *j, const char *s) {
    double v;
    if (!*s) sb_jw_null(j);
    else if (sb_parse_double(s, &v) && isfinite(v)) sb_jw_num(j, v);
    else sb_jw_str(j, s);
}

static void jstrings(sb_jw *j, const char *const *v, int n) {
    sb_jw_arr(j);
    for (int i = 0; i < n; i++) sb_jw_str(j, v[i]);
    sb_jw_end_arr(j);
}

/* data/NAME: the document as a script (file:// pages cannot fetch JSON). */
static bool write_data(const char *site, const char *name, sb_jw *j, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/data/%s", site, name);
    sb_jw f = {0};
    sb_jw_raw(&f, "SB.data(");
    sb_jw_raw(&f, j->buf ? j->buf : "null");
    sb_jw_raw(&f, ");\n");
    bool ok = sb_write_file_atomic(path, f.buf, f.len, err);
    sb_jw_free(&f);
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

/* A table as JSON, the one shape of every table of the site: "columns":[...],"rows":[[...],...], each cell a
 * number where it is one (cell(src, -1, c) is column c's name). */
static void jtable(sb_jw *j, int ncols, int nrows, const char *(*cell)(const void *src, int r, int c), const void *src) {
    sb_jw_key(j, "columns");
    sb_jw_arr(j);
    for (int c = 0; c < ncols; c++) sb_jw_str(j, cell(src, -1, c));
    sb_jw_end_arr(j);
    sb_jw_key(j, "rows");
    sb_jw_arr(j);
    for (int r = 0; r < nrows; r++) {
        sb_jw_arr(j);
        for (int c = 0; c < ncols; c++) jcell(j, cell(src, r, c));
        sb_jw_end_arr(j);
    }
    sb_jw_end_arr(j);
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
 * cached virtual map, cached against drawn every frame: under motion on the movers scene, per-light cube maps
 * against the lamp atlas: on street-lamps), as compare --pair makes them. */
static void night_pairs(const sb_table *summary, sb_jw *j) {
    static const char *const keys[] = {"technique=pssm,sdsm", "layered=off,on", "layered=off,gs",
                                       "technique=pssm:res=2048:layered=off:stable=off,virtual:cache=on",
                                       "cache=off,on", "technique=cube:res=128,atlas:res=128:policy=fixed:cache=off"};
    sb_jw_arr(j);
    for (size_t k = 0; k < SB_COUNT(keys); k++) {
        sb_compare_opts o = {.pair = keys[k], .threshold_pct = 5};
        sb_pair_table pt;
        sb_err e;
        if (sb_compare_pair_table(summary, &o, &pt, &e) > 0) {
            sb_jw_obj(j);
            sb_jw_kstr(j, "key", keys[k]);
            jtable(j, pt.ncols, pt.nrows, pair_cell, &pt);
            sb_jw_kstr(j, "shared", pt.shared);
            sb_jw_end_obj(j);
        }
        sb_pair_table_free(&pt);
    }
    sb_jw_end_arr(j);
}

/* The night's images: copied into images/ID/, listed by run and frame. */
static void night_images(const char *site, long long id, const char *dir, sb_jw *j) {
    char from[4400], to[4400];
    snprintf(from, sizeof from, "%s/images", dir);
    DIR *d = opendir(from);
    sb_jw_arr(j);
    snprintf(to, sizeof to, "%s/images/%lld", site, id);
    sb_err e;
    if (d && sb_mkdir_p(to, &e)) {
        struct dirent *de;
        while ((de = readdir(d))) {
            size_t l = strlen(de->d_name);
            if (l < 5 || strcmp(de->d_name + l - 4, ".png")) continue;
            char a[4800], b[4800];
            snprintf(a, sizeof a, "%s/%s", from, de->d_name);
            snprintf(b, sizeof b, "%s/%s", to, de->d_name);
            if (link_or_copy(a, b, &e)) sb_jw_str(j, de->d_name);
        }
    }
    if (d) closedir(d);
    sb_jw_end_arr(j);
}

/* What the pages show of the column table (columns.h): the night table's columns, the summary columns of each
 * role (the fronts' axes, the memory budget). The page script names no column. */
static void jcolumns(sb_jw *j) {
    const char *night[64];
    int n = sb_columns_night(night, 64);
    sb_jw_key(j, "night_columns");
    jstrings(j, night, n);
    sb_jw_key(j, "roles");
    sb_jw_obj(j);
    static const struct { sb_col_role role; const char *name; } roles[] = {
        {SB_ROLE_TIME, "time"}, {SB_ROLE_ERROR, "error"}, {SB_ROLE_FLICKER, "flicker"}, {SB_ROLE_MEMORY, "memory"}};
    for (size_t r = 0; r < SB_COUNT(roles); r++) {
        sb_metric_cols mc;
        sb_jw_kstr(j, roles[r].name, sb_columns_metric(sb_columns_role(roles[r].role), &mc) ? mc.center : "");
    }
    sb_jw_end_obj(j);
}

/* ---- a night's per-frame figures: the stage times and the charted columns (sb_frame_col.chart) ---- */

enum { MAX_FRAME_COLS = 64 };

/* The columns the run page draws: every stage time (stages), then each charted column (charted). */
static int frame_cols(const char **stages, int *nstages, const char **charted, const char **titles) {
    int nf, ns = 0, nc = 0;
    const sb_frame_col *fc = sb_frame_cols(&nf);
    for (int k = 0; k < nf && ns < MAX_FRAME_COLS; k++)
        if (fc[k].flags & SB_COL_STAGE_TIME) stages[ns++] = fc[k].name;
    for (int k = 0; k < nf && nc < MAX_FRAME_COLS; k++)
        if (fc[k].chart) titles[nc] = fc[k].chart, charted[nc++] = fc[k].name;
    *nstages = ns;
    return nc;
}

typedef struct {
    sb_jw *j;
    const char **cols;
    int ncols;
} frames_json;

static void frame_run(const char *run_id, const char *csv, void *arg) {
    frames_json *fj = arg;
    sb_table t;
    sb_err e;
    if (!sb_table_parse(&t, "frames", csv, &e)) return;
    int idx[2 * MAX_FRAME_COLS];
    for (int c = 0; c < fj->ncols; c++) idx[c] = sb_table_col(&t, fj->cols[c]);
    sb_jw_key(fj->j, run_id);
    sb_jw_arr(fj->j);
    for (int r = 0; r < t.nrows; r++) {
        sb_jw_arr(fj->j);
        for (int c = 0; c < fj->ncols; c++) {
            if (idx[c] < 0) sb_jw_null(fj->j);
            else jcell(fj->j, t.rows[r][idx[c]]);
        }
        sb_jw_end_arr(fj->j);
    }
    sb_jw_end_arr(fj->j);
    sb_table_free(&t);
}

/* "charts":[{"title":..,"columns":[..]}], charted columns of one title together, in table order */
static void jcharts(sb_jw *j, const char **charted, const char **titles, int nc) {
    sb_jw_key(j, "charts");
    sb_jw_arr(j);
    for (int c = 0; c < nc; c++) {
        bool first = true;
        for (int d = 0; d < c && first; d++) first = strcmp(titles[d], titles[c]) != 0;
        if (!first) continue;
        sb_jw_obj(j);
        sb_jw_kstr(j, "title", titles[c]);
        sb_jw_key(j, "columns");
        sb_jw_arr(j);
        for (int d = c; d < nc; d++)
            if (!strcmp(titles[d], titles[c])) sb_jw_str(j, charted[d]);
        sb_jw_end_arr(j);
        sb_jw_end_obj(j);
    }
    sb_jw_end_arr(j);
}

static bool write_frames(sb_history *h, const char *site, long long id, sb_err *err) {
    const char *stages[MAX_FRAME_COLS], *charted[MAX_FRAME_COLS], *titles[MAX_FRAME_COLS], *cols[2 * MAX_FRAME_COLS];
    int nstages, nc = frame_cols(stages, &nstages, charted, titles), ncols = 0;
    for (int k = 0; k < nstages; k++) cols[ncols++] = stages[k];
    for (int k = 0; k < nc; k++) cols[ncols++] = charted[k];
    sb_jw j = {0};
    sb_jw_obj(&j);
    sb_jw_kstr(&j, "kind", "frames");
    sb_jw_key(&j, "columns");
    jstrings(&j, cols, ncols);
    sb_jw_key(&j, "stages");   /* the stacked chart's series, in stage order */
    jstrings(&j, stages, nstages);
    jcharts(&j, charted, titles, nc);
    sb_jw_key(&j, "runs");
    sb_jw_obj(&j);
    frames_json fj = {&j, cols, ncols};
    bool ok = sb_history_night_frames(h, id, frame_run, &fj, err);
    sb_jw_end_obj(&j);
    sb_jw_end_obj(&j);
    char name[64];
    snprintf(name, sizeof name, "frames-%lld.js", id);
    ok = ok && write_data(site, name, &j, err);
    sb_jw_free(&j);
    return ok;
}

/* ---- notes and nights ---- */

/* The notes (annotations and machine changes) that pass `keep`, as a JSON list. */
static void jnotes(sb_jw *j, const sb_history_note *notes, int n, bool (*keep)(const sb_history_note *, const void *),
                   const void *arg) {
    sb_jw_arr(j);
    for (int i = 0; i < n; i++) {
        if (keep && !keep(&notes[i], arg)) continue;
        sb_jw_obj(j);
        sb_jw_knum(j, "night", (double)notes[i].night);
        sb_jw_kstr(j, "date", notes[i].date);
        sb_jw_kstr(j, "commit", notes[i].commit);
        sb_jw_kstr(j, "series", notes[i].series);
        sb_jw_kstr(j, "text", notes[i].text);
        sb_jw_kbool(j, "accept", notes[i].accept);
        sb_jw_kbool(j, "machine", notes[i].machine);
        sb_jw_end_obj(j);
    }
    sb_jw_end_arr(j);
}
static bool note_of_night(const sb_history_note *n, const void *arg) { return n->night == *(const long long *)arg; }
typedef struct { const char *key, *label; } series_ref;
static bool note_of_series(const sb_history_note *n, const void *arg) {
    const series_ref *r = arg;
    return sb_history_note_matches(n, r->key, r->label);
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
    sb_jw j = {0};
    sb_jw_obj(&j);
    sb_jw_kstr(&j, "kind", "night");
    sb_jw_knum(&j, "id", (double)n->id);
    const char *keys[] = {"date", "host", "commit", "renderer", "version", "meta", "dir"};
    const char *vals[] = {n->date, n->host, n->commit, n->renderer, n->version, n->meta, n->dir};
    for (size_t k = 0; k < SB_COUNT(keys); k++) sb_jw_kstr(&j, keys[k], vals[k]);
    jtable(&j, t.cols, t.nrows, summary_cell, &t);
    jcolumns(&j);
    sb_jw_key(&j, "pairs");
    night_pairs(&t, &j);
    sb_jw_key(&j, "images");
    night_images(site, n->id, n->dir, &j);
    sb_jw_key(&j, "notes");
    jnotes(&j, notes, nnotes, note_of_night, &n->id);
    sb_jw_end_obj(&j);
    sb_table_free(&t);
    free(text);
    char name[64];
    snprintf(name, sizeof name, "night-%lld.js", n->id);
    bool ok = write_data(site, name, &j, err) && write_frames(h, site, n->id, err);
    sb_jw_free(&j);
    return ok;
}

/* ---- series and changes ---- */

static void jchange(sb_jw *j, const sb_history_change *c, int sid) {
    sb_jw_obj(j);
    sb_jw_knum(j, "sid", sid);
    sb_jw_kstr(j, "series", c->key);
    sb_jw_kstr(j, "label", c->label);
    sb_jw_kstr(j, "metric", c->metric);
    sb_jw_knum(j, "night_before", (double)c->night_before);
    sb_jw_knum(j, "night_after", (double)c->night_after);
    sb_jw_kstr(j, "date_after", c->date_after);
    sb_jw_kstr(j, "commit_before", c->commit_before);
    sb_jw_kstr(j, "commit_after", c->commit_after);
    const char *nums[] = {"before", "after", "rel", "z", "p"};
    const double vals[] = {c->before, c->after, c->rel, c->z, c->p};
    for (size_t k = 0; k < SB_COUNT(nums); k++) sb_jw_knum(j, nums[k], vals[k]);
    sb_jw_kbool(j, "regression", c->regression);
    sb_jw_kbool(j, "accepted", c->accepted);
    sb_jw_kstr(j, "note", c->note);
    sb_jw_kstr(j, "machine", c->machine);
    sb_jw_kbool(j, "recent", c->recent);
    sb_jw_end_obj(j);
}

static int series_index(char **keys, int ns, const char *key) {
    int lo = 0, hi = ns - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2, c = strcmp(keys[mid], key);
        if (!c) return mid;
        if (c < 0) lo = mid + 1;
        else hi = mid - 1;
    }
    return -1;
}

/* What the site writes from the history, asked once. */
typedef struct site_data {
    sb_history_change *ch;
    int nch;
    sb_history_note *notes;
    int nnotes;
    sb_history_night *nights;
    int nn;
    sb_series *series;          /* in the order of their keys */
    char **keys, **labels;      /* their key texts (what the pages name them by) and short names */
    int ns;
} site_data;

/* One metric of a series: its nights ([night, date, value, ci, stable, commit]) and its changes. */
static bool jseries_metric(sb_jw *j, sb_history *h, const site_data *d, int s, const char *metric, sb_err *err) {
    sb_history_point *pt = NULL;
    int np = sb_history_points(h, &d->series[s], metric, &pt, err);
    if (np < 0) return false;
    sb_jw_key(j, metric);
    sb_jw_obj(j);
    sb_jw_key(j, "nights");
    sb_jw_arr(j);
    for (int k = 0; k < np; k++) {
        sb_jw_arr(j);
        sb_jw_num(j, (double)pt[k].night);
        sb_jw_str(j, pt[k].date);
        sb_jw_num(j, pt[k].value);
        sb_jw_num(j, pt[k].ci);
        sb_jw_bool(j, pt[k].stable);
        sb_jw_str(j, pt[k].commit);
        sb_jw_end_arr(j);
    }
    free(pt);
    sb_jw_end_arr(j);
    sb_jw_key(j, "changes");
    sb_jw_arr(j);
    for (int c = 0; c < d->nch; c++)
        if (!strcmp(d->ch[c].key, d->keys[s]) && !strcmp(d->ch[c].metric, metric)) jchange(j, &d->ch[c], s);
    sb_jw_end_arr(j);
    sb_jw_end_obj(j);
    return true;
}

static bool write_series(sb_history *h, const char *site, const site_data *d, sb_err *err) {
    const char *trend_metrics[32];   /* the SB_USE_REPORT metrics of the column table */
    int ntrend = sb_columns_default_metrics(SB_USE_REPORT, trend_metrics, 32);
    bool ok = true;
    for (int s = 0; ok && s < d->ns; s++) {
        sb_jw j = {0};
        sb_jw_obj(&j);
        sb_jw_kstr(&j, "kind", "series");
        sb_jw_kstr(&j, "series", d->keys[s]);
        sb_jw_kstr(&j, "label", d->labels[s]);
        sb_jw_key(&j, "notes");
        series_ref ref = {d->keys[s], d->labels[s]};
        jnotes(&j, d->notes, d->nnotes, note_of_series, &ref);
        sb_jw_key(&j, "metrics");
        sb_jw_obj(&j);
        for (int m = 0; ok && m < ntrend; m++) ok = jseries_metric(&j, h, d, s, trend_metrics[m], err);
        sb_jw_end_obj(&j);
        sb_jw_end_obj(&j);
        char name[64];
        snprintf(name, sizeof name, "series-%d.js", s);
        ok = ok && write_data(site, name, &j, err);
        sb_jw_free(&j);
    }
    return ok;
}

/* ---- the site ---- */

static void site_data_free(site_data *d) {
    for (int s = 0; s < d->ns; s++) free(d->keys[s]), free(d->labels[s]);
    free(d->keys);
    free(d->labels);
    free(d->series);
    free(d->ch);
    free(d->notes);
    if (d->nn > 0) sb_history_nights_free(d->nights, d->nn);
}

/* Changes first: the index lists them and the series pages draw them. */
static bool site_data_read(sb_history *h, int recent, site_data *d, sb_err *err) {
    memset(d, 0, sizeof *d);
    sb_history_query q = {.recent = recent};
    d->nch = sb_history_changes(h, &q, &d->ch, err);
    if (d->nch >= 0) d->nnotes = sb_history_notes(h, &d->notes, err);
    if (d->nch >= 0 && d->nnotes >= 0) d->nn = sb_history_nights(h, &d->nights, err);
    if (d->nch < 0 || d->nnotes < 0 || d->nn < 0) return false;
    d->series = sb_history_series(h, &d->ns);
    d->keys = sb_xcalloc((size_t)(d->ns ? d->ns : 1), sizeof *d->keys);
    for (int s = 0; s < d->ns; s++) {
        char key[8192];
        sb_series_key(&d->series[s], key, sizeof key);
        d->keys[s] = sb_strdup(key);
    }
    d->labels = sb_history_labels(d->series, d->ns);
    return true;
}

static void jnight_entry(sb_jw *j, const sb_history_night *n) {
    sb_jw_obj(j);
    sb_jw_knum(j, "id", (double)n->id);
    const char *keys[] = {"date", "host", "commit", "renderer"};
    const char *vals[] = {n->date, n->host, n->commit, n->renderer};
    for (int c = 0; c < 4; c++) sb_jw_kstr(j, keys[c], vals[c]);
    const char *counts[] = {"runs", "ok", "failed", "unstable", "warned"};
    const int nums[] = {n->runs, n->ok, n->failed, n->unstable, n->warned};
    for (int c = 0; c < 5; c++) sb_jw_knum(j, counts[c], nums[c]);
    sb_jw_end_obj(j);
}

static bool write_index(const sb_site_opts *o, bool single, const site_data *d, sb_err *err) {
    sb_jw j = {0};
    sb_jw_obj(&j);
    sb_jw_kstr(&j, "kind", "index");
    sb_jw_kbool(&j, "single", single);
    sb_jw_kstr(&j, "source", o->dir ? o->dir : o->history);
    sb_jw_key(&j, "nights");
    sb_jw_arr(&j);
    for (int k = 0; k < d->nn; k++) jnight_entry(&j, &d->nights[k]);
    sb_jw_end_arr(&j);
    sb_jw_key(&j, "changes");
    sb_jw_arr(&j);
    for (int c = 0; c < d->nch; c++) jchange(&j, &d->ch[c], series_index(d->keys, d->ns, d->ch[c].key));
    sb_jw_end_arr(&j);
    sb_jw_key(&j, "notes");
    jnotes(&j, d->notes, d->nnotes, NULL, NULL);
    sb_jw_key(&j, "series");
    jstrings(&j, (const char *const *)d->keys, d->ns);
    sb_jw_key(&j, "labels");
    jstrings(&j, (const char *const *)d->labels, d->ns);
    sb_jw_end_obj(&j);
    bool ok = write_data(o->out, "index.js", &j, err);
    sb_jw_free(&j);
    return ok;
}

static bool write_site(sb_history *h, const sb_site_opts *o, bool single, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/data", o->out);
    static const char *const kinds[] = {"index", "night", "run", "series"};
    if (!sb_mkdir_p(path, err) || !write_assets(o->out, err) || !write_shells(o->out, kinds, SB_COUNT(kinds), "index", err))
        return false;
    site_data d;
    bool ok = site_data_read(h, o->recent, &d, err);
    for (int k = 0; ok && k < d.nn; k++) ok = write_night(h, o->out, &d.nights[k], d.notes, d.nnotes, err);
    ok = ok && write_index(o, single, &d, err) && write_series(h, o->out, &d, err);
    site_data_free(&d);
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

static void jpoint(sb_jw *j, const sb_site_point *p) {
    sb_jw_obj(j);
    sb_jw_kstr(j, "technique", p->technique);
    sb_jw_kstr(j, "label", p->label);
    sb_jw_knum(j, "x", p->x);
    sb_jw_knum(j, "y", p->y);
    sb_jw_knum(j, "frames", p->frames);
    sb_jw_kbool(j, "front", p->front);
    sb_jw_kbool(j, "chosen", p->chosen);
    sb_jw_end_obj(j);
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
    sb_jw j = {0};
    sb_jw_obj(&j);
    sb_jw_kstr(&j, "kind", "front");
    sb_jw_kstr(&j, "title", f->title);
    sb_jw_kstr(&j, "about", f->about);
    sb_jw_kstr(&j, "xlabel", f->xlabel);
    sb_jw_kstr(&j, "ylabel", f->ylabel);
    sb_jw_knum(&j, "bound", f->bound > 0 ? f->bound : NAN);
    sb_jw_kstr(&j, "bound_on", f->bound_on_x ? "x" : "y");
    sb_jw_kstr(&j, "chosen_is", f->chosen_is ? f->chosen_is : "chosen");
    sb_jw_key(&j, "points");
    sb_jw_arr(&j);
    for (int i = 0; i < f->n; i++) jpoint(&j, &f->points[i]);
    sb_jw_end_arr(&j);
    sb_jw_end_obj(&j);
    bool ok = write_data(f->out, "front.js", &j, err);
    sb_jw_free(&j);
    return ok;
}
