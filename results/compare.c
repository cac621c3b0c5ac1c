/* compare.c - compare, pairs and merge over summary tables. */
#include "compare.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <unistd.h>

#include "csv.h"
#include "columns.h"
#include "resultset.h"
#include "runkey.h"
#include "technique.h"
#include "table.h"

/* A results set's summary (the set's folder, or its summary.csv), the set verified whole first (resultset.h). */
static bool load_summary(sb_table *t, const char *where, sb_err *err) {
    struct stat st;
    char path[4200], dir[4200];
    bool is_dir = stat(where, &st) == 0 && S_ISDIR(st.st_mode);
    if (is_dir) snprintf(path, sizeof path, "%s/summary.csv", where);
    else snprintf(path, sizeof path, "%s", where);
    snprintf(dir, sizeof dir, "%s", is_dir ? where : path);
    char *slash = strrchr(dir, '/');
    if (!is_dir && slash && !strcmp(slash + 1, "summary.csv")) *slash = 0;
    if ((is_dir || (slash && !slash[0])) && !sb_resultset_verify(dir, err)) return false;
    if (!sb_table_load(t, path, err)) return false;
    const char *missing = sb_run_key_missing(t, false);
    if (!missing && sb_table_col(t, "status") < 0) missing = "status";
    if (missing) {
        sb_table_free(t);
        return sb_fail(err, "%s: not a shadowbench summary (no '%s' column)", path, missing);
    }
    return true;
}

typedef struct {
    double center, mean, ci;    /* ci NaN when the metric has none */
    bool ok;
    bool lower_worse;           /* the column table's SB_LOWER_WORSE */
} metric_value;

static double num(const char *s) {
    double v;
    return *s && sb_parse_double(s, &v) ? v : NAN;
}

/* A metric of row r, read the way the column table says (columns.h). */
static metric_value metric(const sb_table *t, int r, const char *m) {
    metric_value v = {NAN, NAN, NAN, false, false};
    sb_metric_cols mc;
    if (!sb_columns_metric(m, &mc)) return v;
    v.lower_worse = mc.lower_worse;
    v.center = num(sb_table_get(t, r, mc.center));
    v.mean = num(sb_table_get(t, r, mc.mean));
    if (mc.ci[0]) v.ci = num(sb_table_get(t, r, mc.ci));
    v.ok = !isnan(v.center);
    return v;
}

/* A metric the table knows and the summary has. */
static bool known_metric(const sb_table *t, const char *m) {
    sb_metric_cols mc;
    return sb_columns_metric(m, &mc) && sb_table_col(t, mc.center) >= 0;
}

static void header(FILE *out, int format, const char *a, const char *b) {
    if (format == SB_OUTPUT_CSV)
        fprintf(out, "scene,path,technique,params,metric,%s,%s,ratio,verdict\n", a, b);
    else if (format == SB_OUTPUT_MARKDOWN)
        fprintf(out, "| scene | path | technique | params | metric | %s | %s | ratio | verdict |\n|---|---|---|---|---|---:|---:|---:|---|\n", a, b);
}

static void row(FILE *out, int format, const sb_run_key *k, const char *params, const char *m, double a, double b,
                const char *verdict) {
    double ratio = a != 0 ? b / a : (b == 0 ? 1 : INFINITY);
    const char *scene = k->scene, *path = k->path, *tech = k->technique;
    if (format == SB_OUTPUT_CSV) {
        sb_csv c = {0};
        sb_csv_str(&c, scene);
        sb_csv_str(&c, path);
        sb_csv_str(&c, tech);
        sb_csv_str(&c, params);
        sb_csv_str(&c, m);
        sb_csv_num(&c, a);
        sb_csv_num(&c, b);
        sb_csv_num(&c, ratio);
        sb_csv_str(&c, verdict);
        sb_csv_end_row(&c);
        fputs(c.buf, out);
        sb_csv_free(&c);
    } else if (format == SB_OUTPUT_MARKDOWN) {
        fprintf(out, "| %s | %s | %s | `%s` | %s | %.4g | %.4g | %.3f | %s |\n", scene, path, tech, params, m, a, b,
                ratio, verdict);
    } else {
        fprintf(out, "%-10s %-10s %-8s %-44s %-18s %12.4g %12.4g %7.3f  %s\n", scene, path, tech, params, m, a, b, ratio,
                verdict);
    }
}

static bool unstable_row(const sb_table *t, int r) { return !strcmp(sb_table_get(t, r, "stable"), "no"); }

int sb_compare(const char *base, const char *next, const sb_compare_opts *o, FILE *out, int *unstable, sb_err *err) {
    sb_table A, B;
    if (!load_summary(&A, base, err)) return -1;
    if (!load_summary(&B, next, err)) {
        sb_table_free(&A);
        return -1;
    }
    const char *metrics[32], *defaults[32];
    int nm = 0;
    if (o->nmetrics) {
        for (int k = 0; k < o->nmetrics; k++) metrics[nm++] = o->metrics[k];
    } else { /* the defaults this summary has */
        int nd = sb_columns_default_metrics(SB_USE_COMPARE, defaults, 32);
        for (int k = 0; k < nd; k++)
            if (known_metric(&A, defaults[k])) metrics[nm++] = defaults[k];
    }
    for (int k = 0; k < nm; k++)
        if (!known_metric(&A, metrics[k])) {
            sb_fail(err, "unknown metric '%s' (summary columns give e.g. final_ms, gpu_ms, shadow_draw_calls, err_rate)",
                    metrics[k]);
            sb_table_free(&A);
            sb_table_free(&B);
            return -1;
        }
    double thr = o->threshold_pct / 100.0;
    int regressions = 0, matched = 0, shaky = 0;
    header(out, o->format, "base", "new");
    sb_run_key *keys_a = sb_run_keys(&A), *keys_b = sb_run_keys(&B);
    char (*text_a)[4096] = sb_xmalloc(sizeof *text_a * (size_t)(A.nrows ? A.nrows : 1));
    for (int r = 0; r < A.nrows; r++) sb_run_key_text(&keys_a[r], text_a[r], sizeof text_a[r]);
    for (int rb = 0; rb < B.nrows; rb++) {
        if (sb_status_of(sb_table_get(&B, rb, "status")) != SB_STATUS_OK) continue;
        char kb[4096];
        sb_run_key_text(&keys_b[rb], kb, sizeof kb);
        int ra = -1;
        for (int r = 0; r < A.nrows && ra < 0; r++)
            if (sb_status_of(sb_table_get(&A, r, "status")) == SB_STATUS_OK && !strcmp(text_a[r], kb)) ra = r;
        if (ra < 0) continue;
        matched++;
        char params[2048];
        sb_run_key_sorted_params(keys_b[rb].params, params, sizeof params);
        const char *light = keys_b[rb].light;   /* a sized light's runs say so beside their parameters */
        if (*light) {
            size_t l = strlen(params);
            snprintf(params + l, sizeof params - l, " (%s)", light);
        }
        for (int k = 0; k < nm; k++) {
            metric_value a = metric(&A, ra, metrics[k]), b = metric(&B, rb, metrics[k]);
            if (!a.ok || !b.ok) continue;
            bool worse = b.lower_worse ? b.center < a.center * (1 - thr) - 1e-12 : b.center > a.center * (1 + thr) + 1e-12;
            /* timings also need the confidence intervals of the means apart */
            bool separated = isnan(a.ci) || isnan(b.ci) ||
                             (b.lower_worse ? b.mean + b.ci < a.mean - a.ci : b.mean - b.ci > a.mean + a.ci);
            if (!isnan(a.ci) && (unstable_row(&A, ra) || unstable_row(&B, rb))) { /* a timing of an unstable run */
                shaky++;
                row(out, o->format, &keys_b[rb], params, metrics[k], a.center, b.center, "UNSTABLE");
                continue;
            }
            bool regressed = worse && separated;
            regressions += regressed;
            row(out, o->format, &keys_b[rb], params, metrics[k], a.center, b.center,
                regressed ? "REGRESSED" : worse ? "worse, within noise" : "ok");
        }
    }
    free(text_a);
    free(keys_a);
    free(keys_b);
    if (o->format == SB_OUTPUT_TEXT && matched)   /* none matched: the one line below says it */
        fprintf(out, "%d run(s) matched, %d regression(s) beyond %.3g%%, %d timing(s) UNSTABLE\n", matched, regressions,
                o->threshold_pct, shaky);
    if (unstable) *unstable = shaky;
    sb_table_free(&A);
    sb_table_free(&B);
    if (matched == 0) {
        sb_fail(err, "no runs of %s match %s (same scene, path, technique, parameters, light, animation and run "
                "options)", next, base);
        return -1;
    }
    return regressions;
}

/* value of key in a params string, into out; false if absent */
static bool param_value(const char *params, const char *key, char *out, size_t len) {
    size_t kl = strlen(key);
    for (const char *p = params; p && *p;) {
        const char *end = strchr(p, ':');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        if (n > kl && !strncmp(p, key, kl) && p[kl] == '=') {
            snprintf(out, len, "%.*s", (int)(n - kl - 1), p + kl + 1);
            return true;
        }
        p = end ? end + 1 : NULL;
    }
    return false;
}

/* value of key in a run's params, where a late parameter at its default is left out of the text
 * (sb_param_def.late): then its default, from the technique's table */
static bool run_param(const char *tech, const char *params, const char *key, char *out, size_t len) {
    if (param_value(params, key, out, len)) return true;
    const sb_technique *t = sb_technique_find(tech);
    for (int i = 0; t && i < t->param_count; i++)
        if (t->params[i].late && !strcmp(t->params[i].name, key)) {
            snprintf(out, len, "%s", t->params[i].def);
            return true;
        }
    return false;
}

/* Do two params strings agree on every key both have, other than `skip`? */
static bool agree(const char *a, const char *b, const char *skip) {
    char buf[2048];
    snprintf(buf, sizeof buf, "%s", a);
    for (char *t = strtok(buf, ":"); t; t = strtok(NULL, ":")) {
        char *eq = strchr(t, '=');
        if (!eq) continue;
        *eq = 0;
        if (skip && !strcmp(t, skip)) continue;
        char v[256];
        if (param_value(b, t, v, sizeof v) && strcmp(v, eq + 1)) return false;
    }
    return true;
}

/* Does a run of technique tech have every key=value of `want` ("res=2048:layered=off")? */
static bool meets(const char *tech, const char *params, const char *want) {
    char buf[512];
    snprintf(buf, sizeof buf, "%s", want);
    char *save = NULL;
    for (char *t = strtok_r(buf, ":", &save); t; t = strtok_r(NULL, ":", &save)) {
        char *eq = strchr(t, '=');
        if (!eq) continue;
        *eq = 0;
        char v[256];
        if (!run_param(tech, params, t, v, sizeof v) || strcmp(v, eq + 1)) return false;
    }
    return true;
}

/* ---- pairs: one table, a row a pair ---- */

enum { PAIR_ITEMS = 64, PAIR_COLS = SB_PAIR_COLS };

typedef struct {
    int a, b;
    char items[PAIR_ITEMS][96];     /* "key=value" of both runs (b's keys a lacks added), without the paired key */
    int nitems;
} pair_row;

static int cmp_item(const void *x, const void *y) { return strcmp((const char *)x, (const char *)y); }

/* prefix: each item as "pssm.res=2048", where the two sides' parameters mean different things */
static void add_items(pair_row *p, const char *params, const char *skip, const char *prefix) {
    char buf[2048];
    snprintf(buf, sizeof buf, "%s", params);
    for (char *tok = strtok(buf, ":"); tok && p->nitems < PAIR_ITEMS; tok = strtok(NULL, ":")) {
        char t[96];
        snprintf(t, sizeof t, "%s%s%s", prefix ? prefix : "", prefix ? "." : "", tok);
        const char *eq = strchr(t, '=');
        size_t kl = eq ? (size_t)(eq - t) : strlen(t);
        if (skip && strlen(skip) == kl && !strncmp(t, skip, kl)) continue;
        bool have = false;
        for (int i = 0; i < p->nitems && !have; i++) have = !strncmp(p->items[i], t, kl) && p->items[i][kl] == '=';
        if (!have) snprintf(p->items[p->nitems++], sizeof p->items[0], "%s", t);
    }
}

/* Whether item is in every pair: then it is said once, above the table, not in every row. */
static bool shared_item(const pair_row *rows, int n, const char *item) {
    for (int i = 0; i < n; i++) {
        bool in = false;
        for (int k = 0; k < rows[i].nitems && !in; k++) in = !strcmp(rows[i].items[k], item);
        if (!in) return false;
    }
    return true;
}

static void table_print(const sb_pair_table *tb, int format, FILE *out) {
    if (format == SB_OUTPUT_CSV) {
        sb_csv c = {0};
        for (int k = 0; k < tb->ncols; k++) sb_csv_str(&c, tb->head[k]);
        sb_csv_end_row(&c);
        for (int r = 0; r < tb->nrows; r++) {
            for (int k = 0; k < tb->ncols; k++) sb_csv_str(&c, tb->cells[r][k]);
            sb_csv_end_row(&c);
        }
        fputs(c.buf ? c.buf : "", out);
        sb_csv_free(&c);
        return;
    }
    int w[PAIR_COLS];
    for (int k = 0; k < tb->ncols; k++) {
        w[k] = (int)strlen(tb->head[k]);
        for (int r = 0; r < tb->nrows; r++)
            if ((int)strlen(tb->cells[r][k]) > w[k]) w[k] = (int)strlen(tb->cells[r][k]);
    }
    bool md = format == SB_OUTPUT_MARKDOWN;
    for (int r = -1; r < tb->nrows; r++) {
        for (int k = 0; k < tb->ncols; k++) {
            const char *v = r < 0 ? tb->head[k] : tb->cells[r][k];
            int width = tb->numeric[k] ? w[k] : -w[k];
            if (md) fprintf(out, "| %*s ", width, v);
            else if (k + 1 == tb->ncols && !tb->numeric[k]) fprintf(out, "%s%s", k ? "  " : "", v);
            else fprintf(out, "%s%*s", k ? "  " : "", width, v);
        }
        fputs(md ? "|\n" : "\n", out);
        if (md && r < 0) {
            for (int k = 0; k < tb->ncols; k++) fputs(tb->numeric[k] ? "|---:" : "|---", out);
            fputs("|\n", out);
        }
    }
}

static void cell_num(char *out, double v) {
    if (isnan(v)) out[0] = 0;
    else snprintf(out, 160, "%.4g", v);
}

/* Do runs ra and rb form a pair for key (A's value va, B's vb)? */
static bool is_pair(const sb_table *t, const sb_run_key *keys, int ra, int rb, const char *key, const char *va,
                    const char *vb) {
    const sb_run_key *A = &keys[ra], *B = &keys[rb];
    const char *pa = A->params, *pb = B->params;
    char v[256];
    if (ra == rb || sb_status_of(sb_table_get(t, ra, "status")) != SB_STATUS_OK ||
        sb_status_of(sb_table_get(t, rb, "status")) != SB_STATUS_OK)
        return false;
    if (strcmp(A->scene, B->scene) || strcmp(A->path, B->path)) return false;
    /* runs of other lights (a section of the set with --lights or a sized light), of another animation or of other
       identity options (run_options) are another comparison, never a pair ("" in a set from before the columns: as
       before) */
    if (strcmp(A->light, B->light) || strcmp(A->anim, B->anim) || strcmp(A->run_options, B->run_options)) return false;
    if (!strcmp(key, "technique")) {
        /* techniques whose parameters mean different things (pssm's res is a cascade's, virtual's a page grid's)
           pair by what each side names: technique=pssm:res=2048:layered=off,virtual:cache=on */
        const char *qa = strchr(va, ':'), *qb = strchr(vb, ':');
        size_t la = qa ? (size_t)(qa - va) : strlen(va), lb = qb ? (size_t)(qb - vb) : strlen(vb);
        const char *ta = A->technique, *tb = B->technique;
        if (strlen(ta) != la || strncmp(ta, va, la) || strlen(tb) != lb || strncmp(tb, vb, lb)) return false;
        return qa || qb ? meets(ta, pa, qa ? qa + 1 : "") && meets(tb, pb, qb ? qb + 1 : "") : agree(pa, pb, NULL);
    }
    const char *tech = A->technique;
    return !strcmp(tech, B->technique) && run_param(tech, pa, key, v, sizeof v) &&
           !strcmp(v, va) && run_param(tech, pb, key, v, sizeof v) && !strcmp(v, vb) && agree(pa, pb, key);
}

/* The table: scene (and path where it is not the scene's), technique (unless it
 * is the key), the parameters that are not the same in every pair, then for each
 * metric A's, B's and their ratio, and a verdict. */
static void pairs_table(const sb_table *t, const sb_run_key *keys, const pair_row *rows, int n, const char *key,
                        const char *la, const char *lb, const char *const *metrics, int nm, sb_pair_table *tb) {
    bool by_tech = !strcmp(key, "technique"), show_path = false;
    for (int i = 0; i < n; i++) show_path |= strcmp(keys[rows[i].a].scene, keys[rows[i].a].path) != 0;
    int k = 0;
    snprintf(tb->head[k++], sizeof tb->head[0], "scene");
    if (show_path) snprintf(tb->head[k++], sizeof tb->head[0], "path");
    if (!by_tech) snprintf(tb->head[k++], sizeof tb->head[0], "technique");
    bool varying = false;   /* a params column only when some pair has parameters the others do not share */
    for (int i = 0; i < n; i++)
        for (int j = 0; j < rows[i].nitems; j++) varying |= !shared_item(rows, n, rows[i].items[j]);
    if (varying) snprintf(tb->head[k++], sizeof tb->head[0], "params");
    int first_metric = k;
    for (int m = 0; m < nm && k + 3 < PAIR_COLS; m++) {
        snprintf(tb->head[k++], sizeof tb->head[0], "%s %s", la, metrics[m]);
        snprintf(tb->head[k++], sizeof tb->head[0], "%s %s", lb, metrics[m]);
        snprintf(tb->head[k++], sizeof tb->head[0], "%s ratio", metrics[m]);
    }
    for (int c = first_metric; c < k; c++) tb->numeric[c] = true;
    snprintf(tb->head[k++], sizeof tb->head[0], "verdict");
    tb->ncols = k;
    tb->nrows = n;
    tb->cells = sb_xcalloc((size_t)(n ? n : 1), sizeof *tb->cells);
    for (int i = 0; i < n; i++) {
        char (*cell)[160] = tb->cells[i];
        const pair_row *p = &rows[i];
        int c = 0;
        snprintf(cell[c++], 160, "%s", keys[p->a].scene);
        if (show_path) snprintf(cell[c++], 160, "%s", keys[p->a].path);
        if (!by_tech) snprintf(cell[c++], 160, "%s", keys[p->a].technique);
        char *lab = cell[c];
        c += varying;
        for (int j = 0; varying && j < p->nitems; j++)
            if (!shared_item(rows, n, p->items[j])) {
                size_t l = strlen(lab);
                snprintf(lab + l, 160 - l, "%s%s", l ? ":" : "", p->items[j]);
            }
        bool shaky = unstable_row(t, p->a) || unstable_row(t, p->b), timing_shaky = false;
        for (int m = 0; m < nm && c + 3 < PAIR_COLS; m++) {
            metric_value a = metric(t, p->a, metrics[m]), b = metric(t, p->b, metrics[m]);
            cell_num(cell[c++], a.center);
            cell_num(cell[c++], b.center);
            cell_num(cell[c++], a.ok && b.ok ? (a.center != 0 ? b.center / a.center : b.center == 0 ? 1 : INFINITY) : NAN);
            timing_shaky |= shaky && !isnan(a.ci);
        }
        snprintf(cell[c], 160, "%s", timing_shaky ? "UNSTABLE" : "ok");
    }
}

int sb_compare_pair_table(const sb_table *t, const sb_compare_opts *o, sb_pair_table *tb, sb_err *err) {
    memset(tb, 0, sizeof *tb);
    char key[128], va[128], vb[128];
    const char *eq = o->pair ? strchr(o->pair, '=') : NULL;
    const char *comma = eq ? strchr(eq, ',') : NULL;
    if (!eq || !comma || eq == o->pair)
        return sb_fail(err, "--pair %s: expected KEY=A,B (e.g. technique=pssm,sdsm or layered=off,gs)",
                       o->pair ? o->pair : ""), -1;
    snprintf(key, sizeof key, "%.*s", (int)(eq - o->pair), o->pair);
    snprintf(va, sizeof va, "%.*s", (int)(comma - eq - 1), eq + 1);
    snprintf(vb, sizeof vb, "%s", comma + 1);
    /* default: the questions a pair answers (the SB_USE_PAIR metrics: time and error) */
    const char *pair_defaults[32];
    int npd = sb_columns_default_metrics(SB_USE_PAIR, pair_defaults, 32);
    const char *const *metrics = o->nmetrics ? o->metrics : pair_defaults;
    int nm = o->nmetrics ? o->nmetrics : npd;
    bool by_tech = !strcmp(key, "technique");
    pair_row *rows = NULL;
    int n = 0;
    sb_run_key *keys = sb_run_keys(t);
    for (int ra = 0; ra < t->nrows; ra++)
        for (int rb = 0; rb < t->nrows; rb++) {
            if (!is_pair(t, keys, ra, rb, key, va, vb)) continue;
            rows = sb_xrealloc(rows, (size_t)(n + 1) * sizeof *rows);
            pair_row *p = &rows[n++];
            memset(p, 0, sizeof *p);
            p->a = ra;
            p->b = rb;
            bool own = by_tech && (strchr(va, ':') || strchr(vb, ':'));   /* parameters of their own meaning */
            add_items(p, keys[ra].params, by_tech ? NULL : key, own ? keys[ra].technique : NULL);
            add_items(p, keys[rb].params, by_tech ? NULL : key, own ? keys[rb].technique : NULL);
            qsort(p->items, (size_t)p->nitems, sizeof p->items[0], cmp_item);
        }
    char la[300], lb[300];
    snprintf(la, sizeof la, by_tech ? "%s%s" : "%s=%s", by_tech ? "" : key, va);
    snprintf(lb, sizeof lb, by_tech ? "%s%s" : "%s=%s", by_tech ? "" : key, vb);
    if (by_tech) { /* a side's qualifiers (pssm:res=2048) are in the caption; its columns are named by technique */
        la[strcspn(la, ":")] = 0;
        lb[strcspn(lb, ":")] = 0;
    }
    pairs_table(t, keys, rows, n, key, la, lb, metrics, nm, tb);
    for (int j = 0; n && j < rows[0].nitems; j++)
        if (shared_item(rows, n, rows[0].items[j])) {
            size_t l = strlen(tb->shared);
            snprintf(tb->shared + l, sizeof tb->shared - l, "%s%s", l ? ":" : "", rows[0].items[j]);
        }
    snprintf(tb->caption, sizeof tb->caption, "%d pair(s) %s=%s against %s=%s", n, key, vb, key, va);
    free(rows);
    free(keys);
    return n;
}

void sb_pair_table_free(sb_pair_table *tb) {
    free(tb->cells);
    tb->cells = NULL;
}

int sb_compare_pairs(const char *dir, const sb_compare_opts *o, FILE *out, sb_err *err) {
    sb_table t;
    if (!load_summary(&t, dir, err)) return -1;
    sb_pair_table tb;
    int n = sb_compare_pair_table(&t, o, &tb, err);
    if (n >= 0) {
        if (o->format != SB_OUTPUT_CSV && tb.shared[0])
            fprintf(out, o->format == SB_OUTPUT_MARKDOWN ? "Every pair: `%s`\n\n" : "every pair: %s\n", tb.shared);
        if (n) table_print(&tb, o->format, out);
        if (o->format == SB_OUTPUT_TEXT) fprintf(out, "%s\n", tb.caption);
    }
    sb_pair_table_free(&tb);
    sb_table_free(&t);
    return n;
}

typedef struct {
    double index;
    const char *line;
} merged_row;

static int by_index(const void *a, const void *b) {
    const merged_row *x = a, *y = b;
    return x->index < y->index ? -1 : x->index > y->index ? 1 : 0;
}

/* A batch shard's place, from its meta ("runs: R of T, shard I/N"); false
 * for a folder that is not a shard (a whole batch, a `run`). */
typedef struct {
    int runs, total, index, count;
} shard_meta;

static bool read_shard(const char *dir, shard_meta *m) {
    char path[4200];
    snprintf(path, sizeof path, "%s/meta", dir);
    sb_err e;
    char *text = sb_read_file(path, NULL, &e);
    if (!text) return false;
    const char *line = strstr(text, "\nruns: ");
    bool ok = line && sscanf(line, "\nruns: %d of %d, shard %d/%d", &m->runs, &m->total, &m->index, &m->count) == 4 &&
              m->count > 0 && m->index >= 1 && m->index <= m->count;
    free(text);
    return ok;
}

/* Shards merge only as a whole: every shard of the batch once, each with all
 * its runs (a shard killed before its end must be resumed first). */
static bool check_shards(const char *const *dirs, int n, const sb_table *t, sb_err *err) {
    shard_meta first = {0};
    int seen_count = 0;
    unsigned char *seen = NULL;
    bool ok = true;
    for (int i = 0; ok && i < n; i++) {
        shard_meta m;
        if (!read_shard(dirs[i], &m)) continue;
        if (!seen) {
            first = m;
            seen = sb_xcalloc((size_t)m.count + 1, 1);
        } else if (m.count != first.count || m.total != first.total) {
            ok = sb_fail(err, "%s: shard %d/%d of %d runs does not belong with %s (shards of %d, %d runs)", dirs[i],
                         m.index, m.count, m.total, dirs[0], first.count, first.total);
            break;
        }
        if (seen[m.index]++) ok = sb_fail(err, "%s: shard %d/%d is given twice", dirs[i], m.index, m.count);
        else if (t[i].nrows != m.runs)
            ok = sb_fail(err, "%s: shard %d/%d has %d of its %d runs: it stopped before its end (resume it with "
                              "`shadowbench batch FILE --shard %d/%d --resume %s`)",
                         dirs[i], m.index, m.count, t[i].nrows, m.runs, m.index, m.count, dirs[i]);
        seen_count++;
    }
    for (int k = 1; ok && seen && k <= first.count; k++)
        if (!seen[k]) ok = sb_fail(err, "shard %d/%d is missing: %d of %d shards given, the merge would lose its runs", k,
                                   first.count, seen_count, first.count);
    free(seen);
    return ok;
}

/* --out of a merge: a new folder, or an empty one (a set there would be mixed with the merge's files). */
static bool fresh_out(const char *out_dir, sb_err *err) {
    DIR *d = opendir(out_dir);
    if (!d) {
        if (errno == ENOENT) return true;
        return sb_fail(err, "%s: --out cannot be used (%s): give a new folder", out_dir,
                       errno == ENOTDIR ? "a file stands there" : strerror(errno));
    }
    bool empty = true;
    for (struct dirent *de; empty && (de = readdir(d));) empty = !strcmp(de->d_name, ".") || !strcmp(de->d_name, "..");
    closedir(d);
    if (!empty) return sb_fail(err, "%s: --out already holds files (an earlier merge?): give a new folder", out_dir);
    return true;
}

/* A folder of plain files this process wrote, removed (a merge that failed). */
static void remove_flat(const char *dir) {
    DIR *d = opendir(dir);
    if (!d) return;
    char path[4700];
    for (struct dirent *de; (de = readdir(d));) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..")) continue;
        snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
        unlink(path);
    }
    closedir(d);
    rmdir(dir);
}

/* Every run once: no input folder given twice by any spelling, no run id in two rows (of one set or two). */
static bool distinct_runs(const char *const *dirs, int n, const sb_table *t, sb_err *err) {
    for (int i = 0; i < n; i++)
        for (int j = 0; j < i; j++)
            if (sb_same_file(dirs[i], dirs[j]))
                return sb_fail(err, "%s: the same results set as %s, given twice: its runs would be counted twice",
                               dirs[i], dirs[j]);
    int total = 0;
    for (int i = 0; i < n; i++) total += t[i].nrows;
    const char **ids = sb_xcalloc((size_t)total + 1, sizeof *ids);
    int *from = sb_xcalloc((size_t)total + 1, sizeof *from), k = 0;
    bool ok = true;
    for (int i = 0; ok && i < n; i++)
        for (int r = 0; ok && r < t[i].nrows; r++) {
            const char *id = sb_table_get(&t[i], r, "run_id");
            for (int q = 0; ok && q < k; q++)
                if (!strcmp(ids[q], id))
                    ok = from[q] == i ? sb_fail(err, "%s: run %s is in its summary twice: the set is damaged", dirs[i], id)
                                      : sb_fail(err, "%s: run %s is also in %s: a run is merged once (was one command "
                                                     "run twice into two sets?)", dirs[i], id, dirs[from[q]]);
            ids[k] = id;
            from[k++] = i;
        }
    free(ids);
    free(from);
    return ok;
}

bool sb_merge(const char *const *dirs, int n, const char *out_arg, sb_err *err) {
    char out_dir[4096];   /* without a trailing '/': the folder written beside it is its sibling, not inside it */
    snprintf(out_dir, sizeof out_dir, "%s", out_arg);
    for (size_t l = strlen(out_dir); l > 1 && out_dir[l - 1] == '/'; l--) out_dir[l - 1] = 0;
    sb_table *t = sb_xcalloc((size_t)n, sizeof *t);
    merged_row *rows = NULL;
    int nrows = 0;
    bool ok = true;
    char *hdr_line = NULL;
    /* the merged set is a folder of its own: never one of its inputs (by any spelling), nor a run's own set */
    char meta[4400];
    snprintf(meta, sizeof meta, "%s/meta", out_dir);
    for (int i = 0; ok && i < n; i++)
        if (sb_path_within(out_dir, dirs[i]))
            ok = sb_fail(err, "%s: --out is the input set %s or in it: the merge would write over it (give a new "
                              "folder)", out_dir, dirs[i]);
    if (ok && access(meta, F_OK) == 0)
        ok = sb_fail(err, "%s: --out holds a run's own results set (its meta): the merge would write over its summary "
                          "(give a new folder)", out_dir);
    for (int i = 0; ok && i < n; i++) {
        if (!(ok = load_summary(&t[i], dirs[i], err))) break;
        if (sb_table_col(&t[i], "run_index") < 0) ok = sb_fail(err, "%s: summary has no run_index column", dirs[i]);
        char hdr[8192] = {0};
        for (int c = 0; c < t[i].cols; c++) {
            size_t l = strlen(hdr);
            snprintf(hdr + l, sizeof hdr - l, "%s%s", c ? "," : "", t[i].header[c]);
        }
        if (!hdr_line) hdr_line = sb_strdup(hdr);
        else if (ok && strcmp(hdr_line, hdr)) ok = sb_fail(err, "%s: summary columns differ from %s's", dirs[i], dirs[0]);
    }
    /* nothing is written until the inputs are known to make a whole: every shard once, no folder twice by any
       spelling, no run id twice (a run counted twice would be stored twice by the history and matched twice by
       compare) */
    ok = ok && check_shards(dirs, n, t, err) && distinct_runs(dirs, n, t, err) && fresh_out(out_dir, err);
    /* written into a folder of its own beside --out, renamed to it whole: a merge that fails leaves nothing */
    char tmp[4400];
    snprintf(tmp, sizeof tmp, "%s.merging-%ld", out_dir, (long)getpid());
    /* SIGINT and SIGTERM wait for the rename (or the removal of what was written): a stop half-way left the folder
       beside --out behind; the merge is a bounded copy, and a signal that came meanwhile acts when it is done */
    sigset_t stop, before;
    sigemptyset(&stop);
    sigaddset(&stop, SIGINT);
    sigaddset(&stop, SIGTERM);
    sigprocmask(SIG_BLOCK, &stop, &before);
    bool made = ok && sb_mkdir_p(tmp, err);
    ok = made;
    for (int i = 0; ok && i < n; i++) {
        for (int r = 0; ok && r < t[i].nrows; r++) {
            sb_run_key key;
            sb_run_key_of(&t[i], r, &key);
            rows = sb_xrealloc(rows, (size_t)(nrows + 1) * sizeof *rows);
            rows[nrows++] = (merged_row){num(sb_table_get(&t[i], r, "run_index")), t[i].lines[r]};
            char from[4400], to[4500];
            snprintf(from, sizeof from, "%s/%s.csv", dirs[i], key.run_id);
            snprintf(to, sizeof to, "%s/%s.csv", tmp, key.run_id);
            if (access(from, R_OK) == 0) ok = sb_copy_file(from, to, err);
        }
        char from[4400], to[4500];
        snprintf(from, sizeof from, "%s/meta", dirs[i]);
        snprintf(to, sizeof to, "%s/meta.%d", tmp, i + 1);
        if (ok && access(from, R_OK) == 0) ok = sb_copy_file(from, to, err);
    }
    if (ok) {
        qsort(rows, (size_t)nrows, sizeof *rows, by_index);
        size_t len = strlen(hdr_line);
        size_t total = len + 2;
        for (int k = 0; k < nrows; k++) total += strlen(rows[k].line) + 1;
        char *text = sb_xmalloc(total + 1), *p = text;
        memcpy(p, hdr_line, len);
        p += len;
        *p++ = '\n';
        for (int k = 0; k < nrows; k++) {
            size_t l = strlen(rows[k].line);
            memcpy(p, rows[k].line, l);
            p += l;
            *p++ = '\n';
        }
        char path[4500];
        snprintf(path, sizeof path, "%s/summary.csv", tmp);
        ok = sb_write_file_atomic(path, text, (size_t)(p - text), err) && sb_columns_write(tmp, err) &&
             sb_resultset_seal(tmp, err);
        free(text);
    }
    if (ok) rmdir(out_dir);   /* an empty folder the user made for it (fresh_out allows no other): replaced */
    if (ok && rename(tmp, out_dir) != 0)
        ok = sb_fail(err, "%s: cannot rename the merged set %s to it: %s", out_dir, tmp, strerror(errno));
    if (!ok && made) remove_flat(tmp);
    sigprocmask(SIG_SETMASK, &before, NULL);
    for (int i = 0; i < n; i++) sb_table_free(&t[i]);
    free(t);
    free(rows);
    free(hdr_line);
    return ok;
}
