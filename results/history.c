/* history.c - what the nights of the history mean (history.h): series, a
 * results set added as a night, the changes found in each series, the notes
 * about a night, and a set checked against the nights' band. Every read and
 * write of the file is history_store.h's. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "history.h"

#include <fnmatch.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "changepoint.h"
#include "columns.h"
#include "compare.h"
#include "context.h"
#include "csv.h"
#include "resultset.h"
#include "runkey.h"
#include "stats.h"

/* ---- a results set as a night ---- */

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

static int count_images(const char *dir) {
    char path[4200];
    snprintf(path, sizeof path, "%s/images", dir);
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* The host and renderer a set's series are kept under. */
static void set_host(const char *meta, const sb_table *t, char *host, size_t hlen, char *renderer, size_t rlen) {
    meta_field(meta, "host", host, hlen);
    if (!host[0]) snprintf(host, hlen, "unknown");
    sb_run_key k;
    sb_run_key_of(t, 0, &k);   /* no rows: every field "" */
    snprintf(renderer, rlen, "%s", k.renderer);
    if (!renderer[0]) meta_field(meta, "gl_renderer", renderer, rlen);
}

/* The renderer row r's series is kept under: the row's own (a merged set may hold another renderer's scored runs
 * beside the tool's), else the meta's GL renderer. */
static const char *row_renderer(const char *meta, const sb_table *t, int r, char *out, size_t len) {
    sb_run_key k;
    sb_run_key_of(t, r, &k);
    snprintf(out, len, "%s", k.renderer);
    if (!out[0]) meta_field(meta, "gl_renderer", out, len);
    return out;
}

/* A results set read for the history: its summary (text and table), its meta and what the night is filed under. */
typedef struct set_in {
    const char *dir;
    char sum_path[4200];
    char *sum_text, *meta;
    size_t sum_len;
    sb_table t;
    char host[256], renderer[512], version[64], commit[128], date[64], set_key[32], absdir[4096];
} set_in;

static void set_free(set_in *s) {
    sb_table_free(&s->t);
    free(s->sum_text);
    free(s->meta);
}

/* Reads and checks the set: whole (resultset.h), a shadowbench summary, as many runs as its meta names. */
static bool set_read(set_in *s, const char *dir, sb_err *err) {
    memset(s, 0, sizeof *s);
    s->dir = dir;
    if (!sb_resultset_verify(dir, err)) return false;
    snprintf(s->sum_path, sizeof s->sum_path, "%s/summary.csv", dir);
    s->sum_text = sb_read_file(s->sum_path, &s->sum_len, err);
    if (!s->sum_text || !sb_table_parse(&s->t, s->sum_path, s->sum_text, err)) return false;
    const char *missing = sb_run_key_missing(&s->t, true);
    if (!missing && sb_table_col(&s->t, "status") < 0) missing = "status";
    if (missing) return sb_fail(err, "%s: not a shadowbench summary (no '%s' column)", s->sum_path, missing);
    s->meta = read_meta(dir);
    set_host(s->meta, &s->t, s->host, sizeof s->host, s->renderer, sizeof s->renderer);
    meta_field(s->meta, "version", s->version, sizeof s->version);
    meta_field(s->meta, "commit", s->commit, sizeof s->commit);
    set_date(dir, s->meta, s->sum_path, s->date, sizeof s->date);
    /* a batch (or shard) says how many runs it has: a summary with fewer is a set still running or stopped */
    char runs_field[128];
    int want = 0;
    meta_field(s->meta, "runs", runs_field, sizeof runs_field);
    if (runs_field[0] && sscanf(runs_field, "%d", &want) == 1 && s->t.nrows < want)
        return sb_fail(err, "%s: %d of the %d runs its meta names are in summary.csv: the set is incomplete (still "
                            "running, or stopped: `batch --resume` it first)", dir, s->t.nrows, want);
    /* the set is its summary's bytes on its host: the same set added twice is found */
    uint64_t key = sb_fnv1a(sb_fnv1a(SB_FNV_SEED, s->sum_text, s->sum_len), s->host, strlen(s->host));
    snprintf(s->set_key, sizeof s->set_key, "%016llx", (unsigned long long)key);
    if (!realpath(dir, s->absdir)) snprintf(s->absdir, sizeof s->absdir, "%s", dir);
    return true;
}

/* One summary row as the store keeps it: its series, its numeric cells and its per-frame CSV. */
static bool store_run(sb_history *h, long long night, const set_in *s, int r, sb_history_added *out, sb_err *err) {
    const sb_table *t = &s->t;
    sb_series se;
    char renderer[512];
    sb_series_of_row(t, r, s->host, row_renderer(s->meta, t, r, renderer, sizeof renderer), &se);
    const char **names = sb_xmalloc(sizeof *names * (size_t)(t->cols ? t->cols : 1));
    double *values = sb_xmalloc(sizeof *values * (size_t)(t->cols ? t->cols : 1));
    int nm = 0;
    for (int c = 0; c < t->cols; c++)
        if (*t->rows[r][c] && sb_parse_double(t->rows[r][c], &values[nm])) names[nm++] = t->header[c];
    sb_run_key k;
    sb_run_key_of(t, r, &k);
    const char *run_id = k.run_id;
    char fpath[4200];
    snprintf(fpath, sizeof fpath, "%s/%s.csv", s->dir, run_id);
    char *frames = *run_id ? sb_read_file(fpath, NULL, NULL) : NULL;
    sb_history_run_in in = {.run_id = run_id, .series = &se, .status = sb_table_get(t, r, "status"),
                            .reason = sb_table_get(t, r, "reason"), .stable = sb_table_get(t, r, "stable"),
                            .warnings = sb_table_get(t, r, "warnings"), .line = t->lines[r],
                            .run_index = atoi(sb_table_get(t, r, "run_index")), .nmetrics = nm,
                            .metric_names = names, .metric_values = values, .frames_csv = frames};
    bool ok = sb_history_insert_run(h, night, &in, err);
    out->runs += ok;
    out->frames_files += ok && frames;
    free(frames);
    free(names);
    free(values);
    return ok;
}

static bool store_set(sb_history *h, const set_in *s, sb_history_added *out, sb_err *err) {
    size_t hdr_len = strcspn(s->sum_text, "\r\n");
    char *hdr = sb_xmalloc(hdr_len + 1), added[64];
    memcpy(hdr, s->sum_text, hdr_len);
    hdr[hdr_len] = 0;
    sb_utc_now(added, sizeof added);
    sb_history_night_in n = {.set_key = s->set_key, .dir = s->absdir, .date = s->date, .host = s->host,
                             .renderer = s->renderer, .version = s->version, .commit = s->commit, .header = hdr,
                             .meta = s->meta, .added = added, .images = count_images(s->dir)};
    bool ok = sb_history_begin(h, err);
    long long id = ok ? sb_history_insert_night(h, &n, err) : -1;
    ok = ok && id > 0;
    out->night = id;
    for (int r = 0; ok && r < s->t.nrows; r++) ok = store_run(h, id, s, r, out, err);
    free(hdr);
    if (ok) return sb_history_commit(h, err);
    sb_history_rollback(h);
    return false;
}

bool sb_history_add(sb_history *h, const char *dir, sb_history_added *out, sb_err *err) {
    memset(out, 0, sizeof *out);
    set_in s;
    bool ok = set_read(&s, dir, err);
    long long existing = ok ? sb_history_night_of_set(h, s.set_key, err) : -1;
    ok = ok && existing >= 0;
    if (ok && existing > 0) {
        out->existed = true;
        out->night = existing;
    } else if (ok) {
        ok = store_set(h, &s, out, err);
    }
    set_free(&s);
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

/* The least night-to-night timing noise assumed for a renderer, as a fraction: q's floor, else 1 % on a GPU
 * and 5 % on a software rasterizer, whose times move with everything else on the CPU (the stability tests
 * widen alike). */
static double noise_floor(const sb_history_query *q, const char *renderer) {
    if (q->noise_floor_pct > 0) return q->noise_floor_pct / 100;
    return sb_renderer_is_software(renderer) ? 0.05 : 0.01;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The metrics a query asks for (its own, else the history's defaults), each checked against the column table. */
static int query_metrics(const sb_history_query *q, const char **out, sb_err *err) {
    int nm = 0;
    if (q->nmetrics)
        for (int i = 0; i < q->nmetrics && nm < 32; i++) out[nm++] = q->metrics[i];
    else
        nm = sb_columns_default_metrics(SB_USE_HISTORY, out, 32);
    for (int i = 0; i < nm; i++) {
        sb_metric_cols mc;
        if (!sb_columns_metric(out[i], &mc)) {
            const char *examples[4];
            int ne = sb_columns_default_metrics(SB_USE_HISTORY, examples, 4);
            char list[256] = "";
            for (int k = 0; k < ne; k++) {
                size_t l = strlen(list);
                snprintf(list + l, sizeof list - l, "%s%s", k ? ", " : "", examples[k]);
            }
            return sb_fail(err, "unknown metric '%s' (a summary metric, e.g. %s; shadowbench columns lists them)",
                           out[i], list), -1;
        }
    }
    return nm;
}

/* What the detector walks: the nights (their rank among their host's from the newest) and one series' figures. */
typedef struct walk {
    const sb_history_query *q;
    const char *metric;
    sb_metric_cols mc;
    sb_history_night *nights;
    int nn, *rank, recent;
    sb_series series;           /* the series walked (none before the first: !started) */
    bool started;
    char key[4096];             /* its key text */
    double *x, *w, *ci, *tmp;
    int *at_night, k;
    sb_history_change *ch;
    int nch, chcap;
} walk;

static void add_change(walk *wk, const sb_cp_change *cp) {
    if (wk->nch == wk->chcap) wk->ch = sb_xrealloc(wk->ch, sizeof *wk->ch * (size_t)(wk->chcap = wk->chcap ? 2 * wk->chcap : 16));
    sb_history_change *o = &wk->ch[wk->nch++];
    memset(o, 0, sizeof *o);
    snprintf(o->key, sizeof o->key, "%s", wk->key);
    o->series = wk->series;
    snprintf(o->metric, sizeof o->metric, "%s", wk->metric);
    const sb_history_night *a = &wk->nights[wk->at_night[cp->at - 1]], *b = &wk->nights[wk->at_night[cp->at]];
    o->night_before = a->id;
    o->night_after = b->id;
    snprintf(o->date_after, sizeof o->date_after, "%s", b->date);
    snprintf(o->commit_before, sizeof o->commit_before, "%s", a->commit);
    snprintf(o->commit_after, sizeof o->commit_after, "%s", b->commit);
    o->before = cp->before;
    o->after = cp->after;
    o->rel = cp->rel;
    o->z = cp->z;
    o->p = cp->p;
    o->regression = wk->mc.lower_worse ? cp->after < cp->before : cp->after > cp->before;
    o->recent = wk->rank[wk->at_night[cp->at]] < wk->recent;
}

/* The series walked so far is complete: its changes. A night whose own CI is more than twice the series' usual
 * counts less. */
static void detect(walk *wk) {
    if (wk->k < 2 * SB_CP_MIN_SEG) return;
    int nci = 0;
    for (int i = 0; i < wk->k; i++)
        if (wk->ci[i] > 0) wk->tmp[nci++] = wk->ci[i];
    double typical = 0;
    if (nci) {
        qsort(wk->tmp, (size_t)nci, sizeof *wk->tmp, cmp_double);
        typical = wk->tmp[nci / 2];
    }
    for (int i = 0; i < wk->k; i++)
        if (typical > 0 && wk->ci[i] > 2 * typical) wk->w[i] *= (2 * typical / wk->ci[i]) * (2 * typical / wk->ci[i]);
    sb_cp_opts o = {.relative = true, .noise_floor = wk->mc.ci[0] ? noise_floor(wk->q, wk->series.renderer) : 0};
    sb_cp_change cps[64];
    int nc = sb_changepoints(wk->x, wk->w, wk->k, &o, cps, 64, NULL);
    for (int c = 0; c < nc && c < 64; c++) add_change(wk, &cps[c]);
}

static void take_figure(const sb_series *series, const sb_history_point *p, void *arg) {
    walk *wk = arg;
    if (!wk->started || !sb_series_equal(series, &wk->series)) {
        detect(wk);
        wk->series = *series;
        sb_series_key(series, wk->key, sizeof wk->key);
        wk->started = true;
        wk->k = 0;
    }
    int ni = 0;
    while (ni < wk->nn && wk->nights[ni].id != p->night) ni++;
    if (ni == wk->nn) return;
    int k = wk->k;
    if (k > 0 && wk->at_night[k - 1] == ni) k--;   /* one figure a night: the later run */
    wk->at_night[k] = ni;
    wk->x[k] = p->value;
    wk->ci[k] = isnan(p->ci) ? 0 : p->ci / fabs(p->value ? p->value : 1);
    wk->w[k] = p->stable ? 1.0 : 0.25;
    wk->k = k + 1;
}

/* The nights from q->since on, and each one's rank among its host's nights counted from the newest. */
static bool walk_nights(sb_history *h, walk *wk, sb_err *err) {
    sb_history_night *all = NULL;
    int na = sb_history_nights(h, &all, err);
    if (na < 0) return false;
    wk->nights = all;
    wk->nn = 0;
    for (int i = 0; i < na; i++)   /* the dates compare as SQLite's did (byte order) */
        if (!wk->q->since || strcmp(all[i].date, wk->q->since) >= 0) {
            sb_history_night tmp = all[wk->nn];
            all[wk->nn++] = all[i];
            all[i] = tmp;
        }
    for (int i = wk->nn; i < na; i++) free(all[i].header), free(all[i].meta), all[i].header = all[i].meta = NULL;
    wk->rank = sb_xcalloc((size_t)wk->nn + 1, sizeof *wk->rank);
    for (int i = 0; i < wk->nn; i++)
        for (int j = i + 1; j < wk->nn; j++)
            if (!strcmp(all[i].host, all[j].host)) wk->rank[i]++;
    size_t m = (size_t)(wk->nn > 0 ? wk->nn : 1);
    wk->x = sb_xmalloc(sizeof *wk->x * m), wk->w = sb_xmalloc(sizeof *wk->w * m);
    wk->ci = sb_xmalloc(sizeof *wk->ci * m), wk->tmp = sb_xmalloc(sizeof *wk->tmp * m);
    wk->at_night = sb_xmalloc(sizeof *wk->at_night * m);
    return true;
}

static void walk_free(walk *wk) {
    for (int i = 0; i < wk->nn; i++) free(wk->nights[i].header), free(wk->nights[i].meta);
    free(wk->nights);
    free(wk->rank);
    free(wk->x), free(wk->w), free(wk->ci), free(wk->tmp), free(wk->at_night);
}

/* Each change's label (as the report names its series) and what is known of its night (machine, annotations). */
static bool describe_changes(sb_history *h, sb_history_change *ch, int nch, sb_err *err) {
    int ns = 0;
    sb_series *all = sb_history_series(h, &ns);
    char **labels = sb_history_labels(all, ns);
    for (int c = 0; c < nch; c++)
        for (int i = 0; i < ns; i++)
            if (sb_series_equal(&all[i], &ch[c].series)) snprintf(ch[c].label, sizeof ch[c].label, "%s", labels[i]);
    for (int i = 0; i < ns; i++) free(labels[i]);
    free(all);
    free(labels);
    sb_history_note *notes = NULL;
    int nnotes = sb_history_notes(h, &notes, err);
    if (nnotes < 0) return false;
    for (int c = 0; c < nch; c++)
        for (int i = 0; i < nnotes; i++) {
            const sb_history_note *x = &notes[i];
            if (x->night != ch[c].night_after || !sb_history_note_matches(x, ch[c].key, ch[c].label)) continue;
            char *to = x->machine ? ch[c].machine : ch[c].note;
            size_t l = strlen(to);
            snprintf(to + l, sizeof ch[c].note - l, "%s%s", l ? "; " : "", x->machine ? x->aside : x->text);
            ch[c].accepted |= x->accept;
        }
    free(notes);
    return true;
}

int sb_history_changes(sb_history *h, const sb_history_query *q, sb_history_change **out, sb_err *err) {
    *out = NULL;
    const char *metrics[32];
    int nm = query_metrics(q, metrics, err);
    if (nm < 0) return -1;
    walk wk = {.q = q, .recent = q->recent > 0 ? q->recent : 3};
    if (!walk_nights(h, &wk, err)) return -1;
    bool ok = true;
    for (int mi = 0; ok && mi < nm; mi++) {
        wk.metric = metrics[mi];
        sb_columns_metric(metrics[mi], &wk.mc);
        wk.started = false;
        wk.k = 0;
        ok = sb_history_each_figure(h, wk.mc.center, wk.mc.ci, q->since, take_figure, &wk, err);
        if (ok) detect(&wk);
    }
    walk_free(&wk);
    if (!ok || !describe_changes(h, wk.ch, wk.nch, err)) {
        free(wk.ch);
        return -1;
    }
    *out = wk.ch;
    return wk.nch;
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

/* The items of a series' parameters that not every series of its technique shares (":a=1:b=2"). */
static void own_items(const sb_series *f, const char (*ptext)[2048], int n, int i, char *kept, size_t len) {
    kept[0] = 0;
    for (const char *p = ptext[i]; *p;) {
        size_t l = strcspn(p, ":");
        bool shared = true;   /* by every series of this technique */
        for (int j = 0; j < n && shared; j++)
            if (j != i && !strcmp(f[j].technique, f[i].technique) && !has_item(ptext[j], p, l)) shared = false;
        if (!shared) {
            size_t k = strlen(kept);
            snprintf(kept + k, len - k, ":%.*s", (int)l, p);
        }
        p += l;
        if (*p) p++;
    }
}

char **sb_history_labels(const sb_series *f, int n) {
    char **out = sb_xcalloc((size_t)(n ? n : 1), sizeof *out);
    char(*ptext)[2048] = sb_xmalloc(sizeof *ptext * (size_t)(n ? n : 1));
    bool hosts = false;
    for (int i = 0; i < n; i++) {
        sb_series_params_text(&f[i], ptext[i], sizeof ptext[i]);
        if (i && strcmp(f[i].host, f[0].host)) hosts = true;
    }
    for (int i = 0; i < n; i++) {
        char kept[1024], buf[4096], where[2100];
        own_items(f, (const char(*)[2048])ptext, n, i, kept, sizeof kept);
        if (!strcmp(f[i].scene, f[i].path)) snprintf(where, sizeof where, "%s", f[i].scene);
        else snprintf(where, sizeof where, "%s/%s", f[i].scene, f[i].path);
        snprintf(buf, sizeof buf, "%s %s%s %s%s%s", where, f[i].technique, kept, f[i].size, hosts ? " @" : "",
                 hosts ? f[i].host : "");
        out[i] = sb_strdup(buf);
    }
    free(ptext);
    return out;
}

static const char *verdict_of(const sb_history_change *c) {
    if (c->regression)
        return c->accepted ? (c->recent ? "accepted (recent)" : "accepted")
                           : c->recent ? "REGRESSION (recent)" : "regression";
    return c->recent ? "improvement (recent)" : "improvement";
}

static void print_change_csv(const sb_history_change *c, FILE *out) {
    sb_csv row = {0};
    sb_csv_str(&row, c->label);
    sb_csv_str(&row, c->series.host);
    sb_csv_str(&row, c->metric);
    sb_csv_int(&row, c->night_before);
    sb_csv_int(&row, c->night_after);
    sb_csv_str(&row, c->date_after);
    sb_csv_num(&row, c->before);
    sb_csv_num(&row, c->after);
    sb_csv_num(&row, 100 * c->rel);
    sb_csv_num(&row, c->z);
    sb_csv_num(&row, c->p);
    sb_csv_str(&row, c->commit_before);
    sb_csv_str(&row, c->commit_after);
    sb_csv_str(&row, verdict_of(c));
    char note[3 * sizeof c->note], machine[3 * sizeof c->machine];   /* a note's line breaks and escapes as \xNN */
    sb_csv_str(&row, sb_controls_escaped(c->note, note, sizeof note));
    sb_csv_str(&row, sb_controls_escaped(c->machine, machine, sizeof machine));
    sb_csv_end_row(&row);
    fputs(row.buf, out);
    sb_csv_free(&row);
}

static void print_change_text(const sb_history_change *c, FILE *out) {
    char commits[160];
    if (!strcmp(c->commit_before, c->commit_after)) snprintf(commits, sizeof commits, "%.60s (both)", c->commit_after);
    else snprintf(commits, sizeof commits, "%.60s..%.60s", c->commit_before, c->commit_after);
    fprintf(out, "%-40s %-14s %-6lld %-20s %10.4g %10.4g %+7.1f%% %6.1f %8.2g  %-25s %s\n", c->label, c->metric,
            c->night_after, c->date_after, c->before, c->after, 100 * c->rel, c->z, c->p, commits, verdict_of(c));
    if (c->machine[0]) {
        fputs("    ", out);
        sb_put_controls_escaped(out, c->machine);
        fputc('\n', out);
    }
    if (c->note[0]) {   /* a note is the user's text: a newline or a terminal escape in it is shown, not obeyed */
        fputs("    note: ", out);
        sb_put_controls_escaped(out, c->note);
        fputc('\n', out);
    }
}

void sb_history_print_changes(const sb_history_change *c, int n, int format, FILE *out) {
    if (format == SB_OUTPUT_CSV)
        fprintf(out, "series,host,metric,night_before,night_after,date_after,before,after,change_pct,z,p,"
                     "commit_before,commit_after,verdict,note,machine\n");
    else
        fprintf(out, "%-40s %-14s %-6s %-20s %10s %10s %8s %6s %8s  %-25s %s\n", "series", "metric", "night",
                "first night after", "before", "after", "change", "z", "p", "commits", "verdict");
    for (int i = 0; i < n; i++) {
        if (format == SB_OUTPUT_CSV) print_change_csv(&c[i], out);
        else print_change_text(&c[i], out);
    }
}

int sb_history_points(sb_history *h, const sb_series *series, const char *metric, sb_history_point **out,
                      sb_err *err) {
    *out = NULL;
    sb_metric_cols mc;
    if (!sb_columns_metric(metric, &mc)) return sb_fail(err, "unknown metric '%s'", metric), -1;
    return sb_history_points_of(h, series, mc.center, mc.ci, out, err);
}

/* ---- annotations and what changed on the machine ---- */

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

static sb_history_note *push_note(sb_history_note **out, int *n) {
    *out = sb_xrealloc(*out, sizeof **out * (size_t)(*n + 1));
    sb_history_note *x = &(*out)[(*n)++];
    memset(x, 0, sizeof *x);
    return x;
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
        char what[2048] = "";
        if (prev >= 0) machine_change(nights[prev].meta, nights[i].meta, " changed", what, sizeof what);
        if (!what[0]) continue;
        sb_history_note *x = push_note(out, &n);
        x->night = nights[i].id;
        x->machine = true;
        snprintf(x->date, sizeof x->date, "%s", nights[i].date);
        snprintf(x->commit, sizeof x->commit, "%s", nights[i].commit);
        snprintf(x->text, sizeof x->text, "%s", what);
        machine_change(nights[prev].meta, nights[i].meta, " changed here too", x->aside, sizeof x->aside);
    }
    sb_history_nights_free(nights, nn);
    sb_history_annotation *a = NULL;
    int na = sb_history_annotations(h, &a, err);
    if (na < 0) {
        free(*out);
        *out = NULL;
        return -1;
    }
    for (int i = 0; i < na; i++) {
        sb_history_note *x = push_note(out, &n);
        x->night = a[i].night;
        x->accept = a[i].accept;
        snprintf(x->date, sizeof x->date, "%s", a[i].date);
        snprintf(x->commit, sizeof x->commit, "%s", a[i].commit);
        snprintf(x->series, sizeof x->series, "%s", a[i].series);
        snprintf(x->text, sizeof x->text, "%s", a[i].text);
    }
    free(a);
    return n;
}

bool sb_history_note_matches(const sb_history_note *note, const char *key, const char *label) {
    const char *p = note->series;
    if (!p[0]) return true;
    return !fnmatch(p, label, 0) || !fnmatch(p, key, 0) || strstr(label, p) || strstr(key, p);
}

/* ---- a results set against the nights ---- */

typedef struct band {
    double center, lo, hi, z, rel;
    bool outside, worse;
} band;

/* The detector's noise model over a series' last k nights: a log scale for positive figures, sigma from
 * night-to-night differences floored at the noise floor for timings; the band is median ± sqrt(penalty) sigma. */
static band band_of(const sb_history_point *p, int k, double x, const sb_metric_cols *mc, double floor) {
    double *raw = sb_xmalloc(sizeof *raw * (size_t)k), *v = sb_xmalloc(sizeof *v * (size_t)k);
    bool logs = true;   /* as the detector reads them: a log scale when every night's figure is > 0 */
    for (int i = 0; i < k; i++) raw[i] = p[i].value, logs = logs && raw[i] > 0;
    for (int i = 0; i < k; i++) v[i] = logs ? log(raw[i]) : raw[i];
    double sigma = 0;
    sb_cp_opts o = {.relative = true, .noise_floor = mc->ci[0] ? floor : 0};
    sb_changepoints(raw, NULL, k, &o, NULL, 0, &sigma);
    qsort(v, (size_t)k, sizeof *v, cmp_double);
    double med = sb_percentile(v, k, 0.5);
    double xs = logs ? (x > 0 ? log(x) : -INFINITY) : x, half = sqrt(SB_CP_PENALTY) * sigma * sqrt(1 + 1.0 / k);
    band b = {.z = sigma > 0 ? (xs - med) / (sigma * sqrt(1 + 1.0 / k)) : 0,
              .lo = logs ? exp(med - half) : med - half, .hi = logs ? exp(med + half) : med + half,
              .center = logs ? exp(med) : med, .outside = fabs(xs - med) > half,
              .worse = mc->lower_worse ? xs < med : xs > med};
    b.rel = b.center ? x / b.center - 1 : NAN;
    free(raw);
    free(v);
    return b;
}

/* One figure of one run against its series' newest nights: printed; 1 when beyond the band on the worse side,
 * 0 within or better, -1 not compared, -2 on a database error. */
static int check_figure(sb_history *h, const sb_series *series, const char *label, const char *metric, double x,
                        int nights, double floor, FILE *out, sb_err *err) {
    sb_metric_cols mc;
    sb_columns_metric(metric, &mc);
    sb_history_point *p = NULL;
    int np = sb_history_points_of(h, series, mc.center, mc.ci, &p, err);
    if (np < 0) return -2;
    int from = np > nights ? np - nights : 0, k = np - from;
    if (k < 3) {
        fprintf(out, "%-44.44s %-14s %10.4g  %d night(s): too few for a band\n", label, metric, x, k);
        free(p);
        return -1;
    }
    band b = band_of(p + from, k, x, &mc, floor);
    free(p);
    char range[64];
    snprintf(range, sizeof range, "[%.4g, %.4g]", b.lo, b.hi);
    fprintf(out, "%-44.44s %-14s %10.4g %10.4g %23s %+7.1f%% %6.1f  %s\n", label, metric, x, b.center, range,
            100 * b.rel, b.z, !b.outside ? "within" : b.worse ? "REGRESSION" : "improvement");
    return b.outside && b.worse;
}

int sb_history_check(sb_history *h, const char *dir, const sb_history_query *q, int nights, FILE *out, sb_err *err) {
    set_in s;
    const char *metrics[32];
    int nm = query_metrics(q, metrics, err);
    if (nm < 0 || !set_read(&s, dir, err)) return nm < 0 ? -1 : (set_free(&s), -1);
    int ns = 0, regressions = 0, compared = 0, rc = 0;
    sb_series *all = sb_history_series(h, &ns);
    char **labels = sb_history_labels(all, ns);
    fprintf(out, "%-44s %-14s %10s %10s %23s %8s %6s  %s\n", "series", "metric", "this set", "nights", "band",
            "change", "z", "verdict");
    for (int r = 0; rc >= 0 && r < s.t.nrows; r++) {
        sb_series se;
        char renderer[512];
        sb_series_of_row(&s.t, r, s.host, row_renderer(s.meta, &s.t, r, renderer, sizeof renderer), &se);
        double floor = noise_floor(q, se.renderer);   /* the row's renderer's, not the set's first row's */
        const char *label = NULL;
        for (int i = 0; i < ns; i++)
            if (sb_series_equal(&all[i], &se)) label = labels[i];
        sb_status st = sb_status_of(sb_table_get(&s.t, r, "status"));
        if (!label)
            fprintf(out, "%s %s %s: no series in the history (a new run): nothing to compare\n", se.scene,
                    se.technique, se.size);
        else if (st != SB_STATUS_OK)
            fprintf(out, "%-44.44s %-14s %s: not compared\n", label, "-", sb_status_names[st]);
        for (int mi = 0; label && st == SB_STATUS_OK && rc >= 0 && mi < nm; mi++) {
            sb_metric_cols mc;
            double x;
            if (!sb_columns_metric(metrics[mi], &mc) || !sb_parse_double(sb_table_get(&s.t, r, mc.center), &x)) continue;
            rc = check_figure(h, &se, label, metrics[mi], x, nights, floor, out, err);
            regressions += rc > 0;
            compared += rc >= 0;
            rc = rc == -2 ? -1 : 0;
        }
    }
    for (int i = 0; i < ns; i++) free(labels[i]);
    free(all);
    free(labels);
    set_free(&s);
    if (rc < 0) return -1;
    sb_log("%s: %d figure(s) compared with up to %d night(s) of their series, %d regression(s) beyond the band", dir,
           compared, nights, regressions);
    return regressions;
}
