/* tune.c - `shadowbench tune`: successive halving over techniques and their
 * settings, for the cheapest setting that meets an error bound (or the most
 * accurate one within a frame-time budget), and how sure the answer is.
 *
 * Rungs: every candidate renders a few frames of the path (rung 0), the
 * promising ones more (rung 1), the finalists all N, five times, the passes
 * interleaved (the last rung). The frames of a rung are frames of the next
 * (path frames i/(n-1): n = (N-1)/8+1, (N-1)/4+1, N), so the reference rays
 * of a camera are cast once. How many go on is planned so that the rungs
 * before the last render at most a quarter of the frames the full grid would
 * (warm-up frames and the session's warm-up run counted), and at least the two
 * leaders reach the last. A candidate goes on when it may meet the bound (its
 * estimate within a margin that narrows with the rung), cheapest first; the
 * best one that clearly meets it always goes on, and those within the noise
 * of the cut (paired with the last one kept, frame by frame) go on as well.
 * The answer is the best finalist meeting the bound against the next best,
 * paired pass by pass: how many times cheaper with its 95 % CI, or a tie
 * broken on memory. Each rung is a results set of its own (rung-K/summary.csv
 * and per-frame CSVs); tune reads its decisions back from those files, which
 * is what makes --resume take up exactly where a search stopped. The plan
 * (the candidates, their order in each rung, the frames) follows from the
 * command line and --seed; only measured figures can change what is chosen. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "tune.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <stdarg.h>

#include "batch.h"
#include "resultset.h"
#include "site.h"
#include "stats.h"
#include "table.h"
#include "runkey.h"

/* A formatted line into a text buffer. */
static void __attribute__((format(printf, 2, 3))) line(sb_csv *c, const char *fmt, ...) {
    char buf[8192];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    sb_csv_line(c, buf);
}

#define RUNGS 3

typedef struct cand {
    sb_run_spec spec;
    char label[512];            /* technique[:param=value...]: the parameters that differ from the defaults */
    char run_id[RUNGS + 1][17];   /* each rung's, and the confirmation's (rung RUNGS at most) */
    int rung;                   /* highest rung measured, -1: none */
    bool alive;                 /* still in the race */
    bool skipped, failed;
    char reason[512];
    double time_ms, time_ci, err, err_ci;   /* at its highest rung: gpu_ms median and CI, err_rate mean and CI */
    double side[SB_TUNE_SIDES]; /* flicker_rate and flip_mean means there (NaN: not measured) */
    int frames;                 /* timed frames of that measurement */
    bool front, chosen;
    double ratio, ratio_lo, ratio_hi;   /* a finalist: its objective over the chosen one's, paired, and its 95% CI */
} cand;

/* b's objective over a's, paired: per pass (each pass's median frame time) where the rung has interleaved
 * passes, else per frame (the same camera); the ratio of the means and its 95% CI from the paired differences. */
typedef struct pairing {
    double ratio, lo, hi;
    int n;                      /* pairs */
    bool by_pass;
} pairing;

/* The answer: the chosen one against the next best that also meets the bound (other), or a tie. */
typedef struct verdict {
    int chosen, other;          /* -1: none */
    int missed;                 /* the runner-up the confirmation measured in full, which missed the bound (-1) */
    bool met, tie;
    pairing p;                  /* other against chosen */
    char picked_on[160];        /* a tie: what decided it */
} verdict;

#define FINAL_PASSES 5          /* interleaved passes of the path each finalist renders */
#define TIE_SHARE 0.05          /* settings whose paired ratio's CI reaches within 5 % of 1 tie */

/* The summary columns tune reads and the names it prints, from the column table's roles (columns.h). */
typedef struct tune_cols {
    char time_min[96], time_median[96], time_ci[96], err_mean[96], err_ci[96];
    char side_mean[SB_TUNE_SIDES][96];   /* the side bounds' columns (sb_tune_cmd.max_side) */
    const char *time, *err, *side[SB_TUNE_SIDES], *memory;
} tune_cols;

static void tune_cols_init(tune_cols *c) {
    sb_columns_role_stat(SB_ROLE_TIME, SB_STAT_MIN, c->time_min, sizeof c->time_min);
    sb_columns_role_stat(SB_ROLE_TIME, SB_STAT_MEDIAN, c->time_median, sizeof c->time_median);
    sb_columns_role_stat(SB_ROLE_TIME, SB_STAT_CI95, c->time_ci, sizeof c->time_ci);
    sb_columns_role_stat(SB_ROLE_ERROR, SB_STAT_MEAN, c->err_mean, sizeof c->err_mean);
    sb_columns_role_stat(SB_ROLE_ERROR, SB_STAT_CI95, c->err_ci, sizeof c->err_ci);
    const sb_col_role side[SB_TUNE_SIDES] = {SB_ROLE_FLICKER, SB_ROLE_PERCEPTUAL};
    for (int k = 0; k < SB_TUNE_SIDES; k++) {
        sb_columns_role_stat(side[k], SB_STAT_MEAN, c->side_mean[k], sizeof c->side_mean[k]);
        c->side[k] = sb_columns_role(side[k]);
    }
    c->time = sb_columns_role(SB_ROLE_TIME);
    c->err = sb_columns_role(SB_ROLE_ERROR);
    c->memory = sb_columns_role(SB_ROLE_MEMORY);
}

typedef struct tune {
    const sb_tune_cmd *cmd;
    tune_cols col;
    sb_session s;
    cand *c;
    int n;
    int rung_frames[RUNGS + 1], nrungs;   /* [nrungs]: the confirmation's */
    int warmup;                 /* warm-up frames per run, for the frame count (auto: as measured) */
    long frames_rendered;       /* warm-up and timed frames of the runs this search used (resumed ones included) */
    char dir[4096];
    double t0;
    bool out_of_time;
    int last_rung;              /* highest rung with a measurement */
    int kept;                   /* runs kept from the resumed folder */
    int warm_frames;            /* frames of the session's warm-up run */
    int final_reps;             /* passes of the path each finalist renders, interleaved */
    int planned;                /* finalists the frame budget plans for (the noise may add some) */
    long final_frames;          /* frames of the last rung (its passes) */
} tune;

/* ---- the candidates ---- */

static void short_label(const sb_run_spec *r, char *out, size_t len) {
    sb_params def;
    sb_params_defaults(&def, r->tech);
    snprintf(out, len, "%s", r->tech->name);
    for (int i = 0; i < r->params.count; i++) {
        if (!strcmp(sb_param_text(&r->params, i), sb_param_text(&def, i))) continue;
        size_t l = strlen(out);
        snprintf(out + l, len - l, ":%s=%s", r->params.v[i].def->name, sb_param_text(&r->params, i));
    }
}

/* "pssm:res=512,1024,2048:cascades=2,3,4:..." from the values each parameter row says tune searches (those the
 * row's range or choices refuse left out). */
static void default_grid(const sb_technique *t, char *out, size_t len) {
    snprintf(out, len, "%s", t->name);
    for (int pi = 0; pi < t->param_count; pi++) {
        if (!t->params[pi].tune) continue;
        char vals[256], list[256] = "";
        snprintf(vals, sizeof vals, "%s", t->params[pi].tune);
        for (char *save = NULL, *v = strtok_r(vals, ",", &save); v; v = strtok_r(NULL, ",", &save)) {
            sb_params probe;
            sb_err e;
            if (!sb_param_set(&probe, 0, &t->params[pi], v, t->name, &e)) continue;
            size_t l = strlen(list);
            snprintf(list + l, sizeof list - l, "%s%s", l ? "," : "", v);
        }
        if (!list[0]) continue;
        size_t l = strlen(out);
        snprintf(out + l, len - l, ":%s=%s", t->params[pi].name, list);
    }
}

static bool in_list(const char *list, const char *name) {
    size_t n = strlen(name);
    for (const char *p = list; p && *p;) {
        const char *comma = strchr(p, ',');
        size_t l = comma ? (size_t)(comma - p) : strlen(p);
        if (l == n && !strncmp(p, name, n)) return true;
        p = comma ? comma + 1 : NULL;
    }
    return false;
}

static bool make_candidates(tune *t, sb_err *err) {
    const sb_tune_cmd *cmd = t->cmd;
    sb_run_spec *runs = NULL;
    int n = 0;
    if (cmd->nspecs) {
        for (int i = 0; i < cmd->nspecs; i++)
            if (!sb_spec_expand(cmd->specs[i], NULL, &runs, &n, err)) {
                free(runs);
                return false;
            }
    } else {
        if (cmd->techniques) {   /* every name must be a technique */
            char list[1024];
            snprintf(list, sizeof list, "%s", cmd->techniques);
            for (char *save = NULL, *v = strtok_r(list, ",", &save); v; v = strtok_r(NULL, ",", &save))
                if (!sb_technique_find(v)) {
                    sb_spec_expand(v, "--techniques", &runs, &n, err);   /* the message lists the known ones */
                    free(runs);
                    return false;
                }
        }
        for (int i = 0; i < sb_technique_count(); i++) {
            const sb_technique *tq = sb_technique_at(i);
            bool want = cmd->techniques ? in_list(cmd->techniques, tq->name)
                                        : !(tq->traits & (SB_TRAIT_NO_SHADOWS | SB_TRAIT_EXACT | SB_TRAIT_FOREIGN));
            if (!want) continue;
            char spec[1024];
            default_grid(tq, spec, sizeof spec);
            if (!sb_spec_expand(spec, "tune", &runs, &n, err)) {
                free(runs);
                return false;
            }
        }
    }
    if (n == 0) {
        free(runs);
        return sb_fail(err, "tune: no candidate to measure");
    }
    t->c = sb_xcalloc((size_t)n, sizeof *t->c);
    t->n = n;
    for (int i = 0; i < n; i++) {
        t->c[i].spec = runs[i];
        t->c[i].rung = -1;
        t->c[i].alive = true;
        short_label(&runs[i], t->c[i].label, sizeof t->c[i].label);
    }
    free(runs);
    return true;
}

/* A memory bound is known from the parameters and the scene's lamps (--lights) alone: a setting over it is never
 * rendered. */
static void memory_bound(tune *t) {
    for (int i = 0; i < t->n && t->cmd->max_mb > 0; i++) {
        double mb = sb_session_shadow_bytes(&t->s, &t->c[i].spec) / 1048576.0;
        if (mb <= t->cmd->max_mb) continue;
        t->c[i].alive = false;
        t->c[i].skipped = true;
        snprintf(t->c[i].reason, sizeof t->c[i].reason, "holds %.4g MiB of shadow storage, over --max-mb %g", mb,
                 t->cmd->max_mb);
    }
}

/* ---- the rungs ---- */

static void plan_frames(tune *t) {
    int N = t->cmd->opts->frames;
    int f[RUNGS] = {(N - 1) / 8 + 1, (N - 1) / 4 + 1, N};
    t->nrungs = 0;
    for (int r = 0; r < RUNGS; r++) {
        if (f[r] < 2 && N >= 2) f[r] = 2;
        if (t->nrungs && f[r] <= t->rung_frames[t->nrungs - 1]) continue;
        t->rung_frames[t->nrungs++] = f[r];
    }
    if (!t->nrungs) t->rung_frames[t->nrungs++] = N;
}

/* Warm-up frames of a run at the rung: none at rung 0, whose figure is the
 * median of its frames (a slow first frame does not move it). */
static int rung_warmup(const tune *t, int rung) { return rung == 0 && t->nrungs > 1 ? 0 : t->cmd->opts->warmup; }

/* The constraint (what the bound limits) and the objective (what is minimised). */
static double constraint_of(const tune *t, const cand *c) { return t->cmd->max_err > 0 ? c->err : c->time_ms; }
static double objective_of(const tune *t, const cand *c) { return t->cmd->max_err > 0 ? c->time_ms : c->err; }
static double bound_of(const tune *t) { return t->cmd->max_err > 0 ? t->cmd->max_err : t->cmd->budget_ms; }

/* The bounds, each named by its column: err_rate at most 0.05, flicker_rate at most 0.01, shadow_mb at most 64. */
static void bounds_text(const tune *t, char *out, size_t len) {
    const sb_tune_cmd *cmd = t->cmd;
    snprintf(out, len, "%s at most %g", cmd->max_err > 0 ? t->col.err : t->col.time, bound_of(t));
    size_t l = strlen(out);
    for (int k = 0; k < SB_TUNE_SIDES && l < len; k++)
        if (cmd->max_side[k] > 0) l += (size_t)snprintf(out + l, len - l, ", %s at most %g", t->col.side[k], cmd->max_side[k]);
    if (cmd->max_mb > 0 && l < len) snprintf(out + l, len - l, ", %s at most %g", t->col.memory, cmd->max_mb);
}

/* The side bounds (flicker, FLIP), with a slack (a share of each): met when there are none, or the candidate's
 * figure is within each (a technique that measures no such figure cannot be vouched for). */
static bool sides_ok(const tune *t, const cand *c, double slack) {
    for (int k = 0; k < SB_TUNE_SIDES; k++)
        if (t->cmd->max_side[k] > 0 && !(c->side[k] <= t->cmd->max_side[k] * (1 + slack))) return false;
    return true;
}

static bool measured_at(const cand *c, int rung) { return c->rung == rung && !c->skipped && !c->failed; }

/* Reads the rung's summary back into the candidates. */
static void read_rung(tune *t, int rung, const char *sum_path) {
    sb_table tb;
    sb_err err;
    if (!sb_table_load(&tb, sum_path, &err)) return;
    for (int r = 0; r < tb.nrows; r++) {
        const char *id = sb_run_key_id(&tb, r);
        for (int i = 0; i < t->n; i++) {
            cand *c = &t->c[i];
            if (strcmp(c->run_id[rung], id)) continue;
            sb_status st = sb_status_of(sb_table_get(&tb, r, "status"));
            if (st == SB_STATUS_INTERRUPTED) continue;   /* not measured: a resumed search renders it again */
            c->rung = rung;
            c->skipped = st == SB_STATUS_SKIPPED;
            c->failed = st == SB_STATUS_FAILED;
            snprintf(c->reason, sizeof c->reason, "%s", sb_table_get(&tb, r, "reason"));
            double v;
            /* early rungs: the fastest frame, which a slow spell on a shared machine does not lower (all
               candidates render the same cameras); the last rung: the median, the figure tune reports */
            const char *time_col = rung < t->nrungs - 1 ? t->col.time_min : t->col.time_median;
            c->time_ms = sb_parse_double(sb_table_get(&tb, r, time_col), &v) ? v : NAN;
            c->time_ci = sb_parse_double(sb_table_get(&tb, r, t->col.time_ci), &v) ? v : NAN;
            c->err = sb_parse_double(sb_table_get(&tb, r, t->col.err_mean), &v) ? v : NAN;
            c->err_ci = sb_parse_double(sb_table_get(&tb, r, t->col.err_ci), &v) ? v : NAN;
            for (int k = 0; k < SB_TUNE_SIDES; k++)
                c->side[k] = sb_parse_double(sb_table_get(&tb, r, t->col.side_mean[k]), &v) ? v : NAN;
            long fr = 0, wu = 0, rep = 1;
            sb_parse_int(sb_table_get(&tb, r, "frames"), &fr);
            sb_parse_int(sb_table_get(&tb, r, "warmup"), &wu);
            if (!sb_parse_int(sb_table_get(&tb, r, "repeats"), &rep)) rep = 1;
            c->frames = (int)fr;
            if (!c->skipped) t->frames_rendered += rep * (fr + wu);
            if (!c->skipped && rung >= t->nrungs - 1) t->final_frames += rep * (fr + wu);
            if (measured_at(c, rung) && rung > t->last_rung) t->last_rung = rung;
            if (c->skipped || c->failed || isnan(c->time_ms) || isnan(c->err)) c->alive = false;
            if (!c->skipped && !c->failed && (isnan(c->time_ms) || isnan(c->err)))
                snprintf(c->reason, sizeof c->reason, "no gpu_ms or err_rate was measured (error evaluation off?)");
        }
    }
    sb_table_free(&tb);
}

/* ---- paired comparisons ---- */

/* A candidate's frames at a rung, as its per-frame file has them: the column's value and the pass of each. */
typedef struct frame_vals {
    double *v;
    int *pass, n, passes;
} frame_vals;

static frame_vals load_frames(const tune *t, int rung, const cand *c, const char *col) {
    frame_vals f = {0};
    char path[4400];
    snprintf(path, sizeof path, "%s/rung-%d/%s.csv", t->dir, rung, c->run_id[rung]);
    sb_table tb;
    sb_err err;
    if (!sb_table_load(&tb, path, &err)) return f;
    f.v = sb_xmalloc(sizeof *f.v * (size_t)(tb.nrows + 1));
    f.pass = sb_xmalloc(sizeof *f.pass * (size_t)(tb.nrows + 1));
    for (int r = 0; r < tb.nrows; r++) {
        long p = 0;
        if (!sb_parse_double(sb_table_get(&tb, r, col), &f.v[f.n])) f.v[f.n] = NAN;
        sb_parse_int(sb_table_get(&tb, r, "repeat"), &p);
        f.pass[f.n++] = (int)p;
        if (p + 1 > f.passes) f.passes = (int)p + 1;
    }
    sb_table_free(&tb);
    return f;
}

static void free_frames(frame_vals *f) {
    free(f->v);
    free(f->pass);
}

/* The median of the frames of one pass (NaN: none). */
static double pass_median(const frame_vals *f, int pass) {
    double *v = sb_xmalloc(sizeof *v * (size_t)(f->n + 1));
    int m = 0;
    for (int i = 0; i < f->n; i++)
        if (f->pass[i] == pass && !isnan(f->v[i])) v[m++] = f->v[i];
    double med = m ? sb_percentile_select(v, m, 0.5) : NAN;
    free(v);
    return med;
}

/* b's objective over a's at the rung (see pairing). The frame time is paired by pass where the rung has several
 * (a slow spell hits both of a pair alike: they ran side by side), else by frame; the error by frame of the
 * first pass (it does not change between passes: the same cameras, the same maps). */
static pairing compare(const tune *t, int rung, const cand *a, const cand *b) {
    const bool time = t->cmd->max_err > 0;
    frame_vals fa = load_frames(t, rung, a, time ? t->col.time : t->col.err);
    frame_vals fb = load_frames(t, rung, b, time ? t->col.time : t->col.err);
    pairing p = {.ratio = NAN, .lo = -INFINITY, .hi = INFINITY, .by_pass = time && fa.passes > 1 && fb.passes > 1};
    int cap = (fa.n < fb.n ? fa.n : fb.n) + 1, k = 0;
    double *x = sb_xmalloc(sizeof *x * (size_t)cap), *y = sb_xmalloc(sizeof *y * (size_t)cap);
    if (p.by_pass) {
        for (int q = 0; q < fa.passes && q < fb.passes; q++) x[k] = pass_median(&fa, q), y[k++] = pass_median(&fb, q);
    } else {
        for (int i = 0; i < fa.n && i < fb.n; i++)   /* the same frame of the same pass: the same camera */
            if (fa.pass[i] == 0 && fb.pass[i] == 0) x[k] = fa.v[i], y[k++] = fb.v[i];
    }
    sb_paired sp = sb_paired_compute(x, y, k);   /* NaN pairs skipped */
    p.n = sp.n, p.ratio = sp.ratio, p.lo = sp.lo, p.hi = sp.hi;
    free(x);
    free(y);
    free_frames(&fa);
    free_frames(&fb);
    return p;
}

/* The search stops where it is: its time limit is spent, or a SIGINT or
 * SIGTERM came (the run in flight ends `interrupted` at a frame boundary). */
static bool out_of_time(const tune *t) {
    return sb_interrupted() || (t->cmd->time_limit_s > 0 && (sb_now_ms() - t->t0) / 1e3 > t->cmd->time_limit_s);
}

/* Measures every live candidate at the rung (what a resumed folder has is
 * kept), in an order that follows from the seed. False: the time ran out, or
 * a signal stopped the search. */
static bool run_rung(tune *t, int rung) {
    sb_session *s = &t->s;
    s->opts.frames = t->rung_frames[rung];
    s->opts.warmup = rung_warmup(t, rung);
    char dir[4200], sum_path[4300];
    snprintf(dir, sizeof dir, "%s/rung-%d", t->dir, rung);
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    sb_err err;
    if (!sb_mkdir_p(dir, &err) || !sb_columns_write(dir, &err)) {
        sb_say_line(stderr, err.msg);
        return false;
    }
    const char **ids = sb_xcalloc((size_t)t->n, sizeof *ids);
    bool *done = sb_xcalloc((size_t)t->n, sizeof *done);
    int *order = sb_xmalloc(sizeof(int) * (size_t)t->n), todo = 0;
    for (int i = 0; i < t->n; i++) {
        if (!t->c[i].alive) continue;
        sb_session_run_id(s, &t->c[i].spec, t->c[i].run_id[rung]);
        ids[i] = t->c[i].run_id[rung];
    }
    sb_summary sum;
    sb_summary_open(&sum, sum_path);
    if (t->cmd->resume) sb_resultset_unseal(dir);   /* the rung changes now; sealed again when it ends */
    int kept = t->cmd->resume ? sb_summary_keep_complete(&sum, dir, ids, t->n, done) : 0;
    t->kept += kept;
    /* the rung's order over all its candidates, then those already done left out: a resumed search
       renders the rest in the order the whole search would have */
    int all = 0;
    for (int i = 0; i < t->n; i++)
        if (ids[i]) order[all++] = i;
    uint64_t rng = s->opts.seed ^ (0x5bd1e995u * (uint64_t)(rung + 1));
    for (int k = all - 1; k > 0; k--) {
        int j = (int)(sb_splitmix64(&rng) % (uint64_t)(k + 1));
        int tmp = order[k];
        order[k] = order[j], order[j] = tmp;
    }
    for (int k = 0; k < all; k++)
        if (!done[order[k]]) order[todo++] = order[k];
    sb_log("rung %d: %d candidate(s) on %d frame(s) of the path%s", rung, todo + kept, s->opts.frames,
           kept ? " (some kept from the resumed folder)" : "");
    bool in_time = true;
    const bool passes = rung >= t->nrungs - 1 && t->final_reps > 1;
    if (passes && todo) {   /* the finalists: their passes interleaved, so a slow spell hits each alike */
        if (out_of_time(t)) {
            in_time = false;
        } else {
            const sb_run_spec **specs = sb_xmalloc(sizeof *specs * (size_t)todo);
            for (int k = 0; k < todo; k++) specs[k] = &t->c[order[k]].spec;
            sb_run_opts keep = s->opts;
            s->opts.repeat = t->final_reps;
            s->opts.order = SB_ORDER_SHUFFLE;   /* each pass in an order of its own (from the seed): no one always first */
            sb_run_group(s, specs, order, todo, dir, &sum, 0, todo);
            s->opts = keep;
            free(specs);
            in_time = !sb_interrupted();
        }
    }
    for (int k = 0; !passes && k < todo; k++) {
        if (out_of_time(t)) {
            in_time = false;
            break;
        }
        cand *c = &t->c[order[k]];
        sb_run_one(s, &c->spec, dir, &sum, order[k], k, todo);
        if (!sb_summary_flush(&sum, &err)) sb_say_line(stderr, err.msg);
    }
    if (!sb_summary_flush(&sum, &err) || !sb_resultset_seal(dir, &err)) sb_say_line(stderr, err.msg);
    sb_summary_free(&sum);
    read_rung(t, rung, sum_path);
    free(ids);
    free(done);
    free(order);
    return in_time;
}

typedef struct rank {
    int group;                  /* 1..: the Pareto layer of one that may meet the bound; INT_MAX: does not */
    double v;                   /* may meet it: the objective; does not: the constraint */
    int i;
} rank;

/* The first run of a session is slower than the ones after it beyond its
 * own warm-up frame (llvmpipe, towers at 320x180: every frame of it 30-60 %
 * slower), which would price the first candidate of rung 0 out of the race:
 * one run of a candidate on the rung-0 frames with 8 warm-up frames comes
 * first, in warm-up/ (its frames counted, its figures not used). */
static void warm_session(tune *t) {
    sb_session *s = &t->s;
    int first = -1;
    for (int i = 0; i < t->n && first < 0; i++)
        if (t->c[i].alive && !sb_skip_reason(s, t->c[i].spec.tech, &t->c[i].spec)) first = i;
    if (first < 0) return;
    char dir[4200], sum_path[4300];
    snprintf(dir, sizeof dir, "%s/warm-up", t->dir);
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    sb_err err;
    if (!sb_mkdir_p(dir, &err)) {
        sb_say_line(stderr, err.msg);
        return;
    }
    sb_run_opts keep = s->opts;
    s->opts.frames = t->rung_frames[0];
    s->opts.warmup = 8;
    s->opts.error_every = 0;
    sb_summary sum;
    sb_summary_open(&sum, sum_path);
    sb_run_one(s, &t->c[first].spec, dir, &sum, first, 0, 1);
    if (!sb_summary_flush(&sum, &err)) sb_say_line(stderr, err.msg);
    sb_summary_free(&sum);
    s->opts = keep;
    t->warm_frames = t->rung_frames[0] + 8;
    t->frames_rendered += t->warm_frames;
}

static int cmp_rank(const void *a, const void *b) {
    const rank *x = a, *y = b;
    if (x->group != y->group) return x->group < y->group ? -1 : 1;
    if (x->v != y->v) return x->v < y->v ? -1 : 1;
    return x->i - y->i;
}

/* a beats b on both counts by more than an early rung can tell (eps: relative) */
static bool dominates(const cand *a, const cand *b, double eps) {
    return a->time_ms * (1 + eps) <= b->time_ms && a->err * (1 + eps) <= b->err;
}

/* The cut's noise: a hopeful candidate left out whose paired figures at the rung may be as good as those of the
 * last one kept (its ratio's 95 % CI reaches 1) goes on as well, at most `extra` of them, nearest first: a few
 * frames cannot tell them apart, and dropping either would be a coin's toss. */
static void within_noise(tune *t, int rung, const rank *rk, int m, int keep, int extra) {
    int cut = -1;
    for (int k = 0; k < keep && k < m; k++)
        if (rk[k].group != INT_MAX) cut = rk[k].i;
    for (int k = keep, added = 0; cut >= 0 && k < m && added < extra; k++) {
        cand *c = &t->c[rk[k].i];
        if (rk[k].group == INT_MAX || c->alive) continue;
        pairing p = compare(t, rung, &t->c[cut], c);
        if (!(p.lo <= 1)) continue;
        c->alive = true;
        added++;
        sb_log("tune: %s goes on within the noise of the cut (%.3g of %s's, 95%% CI %.3g-%.3g over %d frame(s))",
               c->label, p.ratio, t->c[cut].label, p.lo, p.hi, p.n);
    }
}

/* Who goes on from `rung`. Those that may meet the bound (within the margin,
 * which the few frames of an early rung need) go first, by Pareto layer of
 * (time, error) among them and then by objective: a candidate that another
 * beats on both counts waits for those that nothing beats, so a noisy time
 * alone cannot push a setting that is better on error out of the race (and
 * beating means by more than a quarter of the margin: three frames do not
 * tell errors 1 % apart); those whose estimate meets the bound before those
 * only within the margin. Then
 * the others, by how close they come. `keep` of them, and always the best
 * that clearly meets the bound, or if none does the one closest to meeting
 * it (it takes the last place). */
static void promote(tune *t, int rung, int keep, int extra, double margin) {
    const double b = bound_of(t);
    rank *rk = sb_xmalloc(sizeof *rk * (size_t)t->n);
    bool *within = sb_xcalloc((size_t)t->n, sizeof *within);
    int m = 0, best_clear = -1;
    for (int i = 0; i < t->n; i++) {
        cand *c = &t->c[i];
        if (!c->alive || !measured_at(c, rung)) {
            c->alive = false;
            continue;
        }
        bool maybe = constraint_of(t, c) <= b * (1 + margin) && sides_ok(t, c, margin);
        rk[m++] = (rank){maybe ? 0 : INT_MAX, maybe ? objective_of(t, c) : constraint_of(t, c), i};
        within[i] = constraint_of(t, c) <= b && sides_ok(t, c, 0);
        if (constraint_of(t, c) <= b * (1 - margin / 2) && sides_ok(t, c, -margin / 2) &&
            (best_clear < 0 || objective_of(t, c) < objective_of(t, &t->c[best_clear])))
            best_clear = i;
    }
    if (best_clear < 0)   /* nothing clearly meets it: the safe place goes to the one closest to meeting it */
        for (int k = 0; k < m; k++)
            if (best_clear < 0 || constraint_of(t, &t->c[rk[k].i]) < constraint_of(t, &t->c[best_clear]))
                best_clear = rk[k].i;
    /* non-dominated sorting of the hopeful: layer L holds those only layers < L beat */
    for (int layer = 1, left = 1; left; layer++) {
        left = 0;
        for (int k = 0; k < m; k++) {
            if (rk[k].group != 0) continue;
            bool beaten = false;
            for (int j = 0; j < m && !beaten; j++)
                beaten = j != k && (rk[j].group == 0 || rk[j].group == -layer) &&
                         dominates(&t->c[rk[j].i], &t->c[rk[k].i], margin / 4);
            if (!beaten) rk[k].group = -layer;   /* provisional: this layer */
            else left++;
        }
        for (int k = 0; k < m; k++)
            if (rk[k].group == -layer) rk[k].group = layer;
    }
    /* those whose estimate meets the bound before those only within the margin */
    for (int k = 0; k < m; k++)
        if (rk[k].group != INT_MAX && !within[rk[k].i]) rk[k].group += 1 << 20;
    free(within);
    qsort(rk, (size_t)m, sizeof *rk, cmp_rank);
    for (int k = 0; k < m; k++) t->c[rk[k].i].alive = k < keep;
    if (best_clear >= 0 && !t->c[best_clear].alive && keep > 0) {
        t->c[rk[keep - 1].i].alive = false;
        t->c[best_clear].alive = true;
    }
    within_noise(t, rung, rk, m, keep, extra);
    free(rk);
}

/* How many go on from rung 0 (k1) and to the last rung (k2). The last rung
 * renders each finalist FINAL_PASSES times, the passes interleaved in an
 * order of their own each, so that the leaders are compared pass by pass
 * (paired, as bisect times two commits): on this shared 2-core machine one
 * run's median moves by 10 % and more with the load of the moment, and two
 * settings 14 % apart came out in either order from single 33-frame runs
 * (towers at 320x180), while the load of a moment hits both runs of a pass
 * alike. The plan keeps the search within a quarter of the frames the grid
 * would render (warm-up frames and the warm-up run counted): as many
 * finalists as fit, at least the two leaders (so a small grid's search
 * renders more than a quarter: it says so) and at most 8; rung 1 runs only
 * with what is left, for at least twice as many as go on. Those within the
 * noise of a cut go on beyond the plan (within_noise), at most doubling it. */
static void plan_keep(tune *t, int runnable, int *k1, int *k2) {
    const int w = t->warmup, N = t->cmd->opts->frames;
    const long budget = (long)runnable * (N + w) / 4 - t->warm_frames;
    const long r0 = (long)runnable * (t->rung_frames[0] + rung_warmup(t, 0));
    const long left = budget - r0, pass = N + w;
    t->final_reps = FINAL_PASSES;
    long f = left / (t->final_reps * pass);
    if (f > 8) f = 8;
    if (f < 2) f = 2;
    if (f > runnable) f = runnable;
    *k2 = t->planned = (int)f;
    *k1 = 0;
    if (t->nrungs < 3) return;
    long rest = left - f * pass * t->final_reps, k = rest > 0 ? rest / (t->rung_frames[1] + w) : 0;
    if (k >= 2 * f && f < runnable) *k1 = (int)(k > runnable ? runnable : k);
}

/* ---- the answer ---- */

static int choose(tune *t, int rung) {
    int best = -1;
    const double b = bound_of(t);
    for (int i = 0; i < t->n; i++) {
        const cand *c = &t->c[i];
        if (!measured_at(c, rung) || isnan(c->err) || isnan(c->time_ms) || constraint_of(t, c) > b ||
            !sides_ok(t, c, 0))
            continue;
        if (best < 0 || objective_of(t, c) < objective_of(t, &t->c[best])) best = i;
    }
    return best;
}

/* The closest to the bound, when nothing meets it. */
static int closest(const tune *t, int rung) {
    int best = -1;
    for (int i = 0; i < t->n; i++) {
        const cand *c = &t->c[i];
        if (!measured_at(c, rung) || isnan(c->err) || isnan(c->time_ms)) continue;
        if (best < 0 || constraint_of(t, c) < constraint_of(t, &t->c[best])) best = i;
    }
    return best;
}

static bool usable(const cand *c) { return c->rung >= 0 && !c->skipped && !c->failed && !isnan(c->err) && !isnan(c->time_ms); }

/* The bound's name as the command line gives it: --max-err 0.015. */
static void bound_flag(const tune *t, char *out, size_t len) {
    snprintf(out, len, "%s %g", t->cmd->max_err > 0 ? "--max-err" : "--budget-ms", bound_of(t));
}

/* Of two tied settings, the one that holds less shadow storage, then the one with the better figure on the
 * other count (the error when the time is minimised, the time when the error is); says which decided. */
static int tiebreak(const tune *t, int a, int b, char *on, size_t len) {
    const cand *x = &t->c[a], *y = &t->c[b];
    double mx = sb_session_shadow_bytes(&t->s, &x->spec) / 1048576.0, my = sb_session_shadow_bytes(&t->s, &y->spec) / 1048576.0;
    if (mx != my) {
        snprintf(on, len, "%s %.4g MiB against %.4g", t->col.memory, fmin(mx, my), fmax(mx, my));
        return mx < my ? a : b;
    }
    double vx = constraint_of(t, x), vy = constraint_of(t, y);
    const char *col = t->cmd->max_err > 0 ? t->col.err : t->col.time;
    snprintf(on, len, "%s %.4g against %.4g (the same %s)", col, fmin(vx, vy), fmax(vx, vy), t->col.memory);
    return vx <= vy ? a : b;
}

/* The answer at the rung: the best that meets the bound, against the next best that meets it, paired (where
 * the pairs clearly say the other way round, the pairs win). Where their ratio's 95 % CI reaches 1 (for the
 * frame time: within TIE_SHARE of it) the two tie, and the tie is broken on memory, then on the other count;
 * nothing meeting the bound: the closest. */
static verdict decide(tune *t, int rung) {
    verdict v = {.chosen = choose(t, rung), .other = -1, .missed = -1};
    v.met = v.chosen >= 0;
    if (!v.met) {
        v.chosen = closest(t, rung);
        return v;
    }
    const double b = bound_of(t);
    for (int i = 0; i < t->n; i++) {   /* the runner-up: the next best that meets the bound */
        const cand *c = &t->c[i];
        if (i == v.chosen || !measured_at(c, rung) || isnan(c->err) || isnan(c->time_ms) || constraint_of(t, c) > b ||
            !sides_ok(t, c, 0))
            continue;
        if (v.other < 0 || objective_of(t, c) < objective_of(t, &t->c[v.other])) v.other = i;
    }
    if (v.other < 0) return v;
    /* the frame time is noisy, so a ratio within TIE_SHARE of 1 is no difference; the error of a frame is exact, and
       its CI only says how the cameras of the path differ */
    const double share = t->cmd->max_err > 0 ? TIE_SHARE : 0;
    v.p = compare(t, rung, &t->c[v.chosen], &t->c[v.other]);
    sb_paired pr = {.lo = v.p.lo, .hi = v.p.hi};
    if (sb_paired_verdict(&pr, share) == SB_PAIR_LOWER) {   /* the pairs say the other is clearly better: they outrank the pooled figure */
        int o = v.other;
        v.other = v.chosen, v.chosen = o;
        v.p = compare(t, rung, &t->c[v.chosen], &t->c[v.other]);
    }
    pr = (sb_paired){.lo = v.p.lo, .hi = v.p.hi};
    v.tie = sb_paired_verdict(&pr, share) != SB_PAIR_HIGHER;
    if (v.tie) {
        int pick = tiebreak(t, v.chosen, v.other, v.picked_on, sizeof v.picked_on);
        if (pick != v.chosen) {   /* the figures from the one picked */
            v.other = v.chosen, v.chosen = pick;
            v.p = compare(t, rung, &t->c[v.chosen], &t->c[v.other]);
        }
    }
    return v;
}

/* The runner-up for a verdict the last rung cannot give (only the chosen one there meets the bound): the best
 * of the others whose figures at an earlier rung meet it. -1: none. */
static int runner_up(const tune *t, int chosen) {
    int best = -1;
    for (int i = 0; i < t->n; i++) {
        const cand *c = &t->c[i];
        if (i == chosen || !usable(c) || c->rung >= t->nrungs - 1 || constraint_of(t, c) > bound_of(t) ||
            !sides_ok(t, c, 0))
            continue;
        if (best < 0 || objective_of(t, c) < objective_of(t, &t->c[best])) best = i;
    }
    return best;
}

/* The confirmation: where the last rung has only the chosen one within the bound, it and the runner-up render
 * side by side, FINAL_PASSES interleaved passes (rung-K, K the last rung + 1), and the verdict is theirs: how
 * much cheaper, or that the runner-up missed the bound measured in full. False: the time ran out or a signal came. */
static bool confirm(tune *t, verdict *v, int *rung) {
    int r = runner_up(t, v->chosen);
    if (r < 0) return true;
    for (int i = 0; i < t->n; i++) t->c[i].alive = i == v->chosen || i == r;
    const int k = t->nrungs;
    t->rung_frames[k] = t->cmd->opts->frames;
    t->final_reps = FINAL_PASSES;
    sb_log("tune: only %s meets the bound at the last rung: measuring it beside the runner-up, %s", t->c[v->chosen].label,
           t->c[r].label);
    bool in_time = run_rung(t, k);
    if (!measured_at(&t->c[v->chosen], k) || !measured_at(&t->c[r], k)) return in_time;
    *rung = k;
    *v = decide(t, k);
    if (v->met && v->other < 0 && v->chosen != r) v->missed = r;
    return in_time;
}

/* Each candidate measured at the rung: its objective over the chosen one's, paired (tune.csv). */
static void ratios_to(tune *t, int rung, int chosen) {
    for (int i = 0; i < t->n; i++) {
        cand *c = &t->c[i];
        c->ratio = c->ratio_lo = c->ratio_hi = NAN;
        if (chosen < 0 || !measured_at(c, rung)) continue;
        pairing p = i == chosen ? (pairing){.ratio = 1, .lo = 1, .hi = 1} : compare(t, rung, &t->c[chosen], c);
        c->ratio = p.ratio, c->ratio_lo = p.lo, c->ratio_hi = p.hi;
    }
}


/* Pareto front of (time, err) over every candidate's best-known figures. */
static void mark_front(tune *t) {
    for (int i = 0; i < t->n; i++) {
        cand *a = &t->c[i];
        a->front = usable(a);
        for (int j = 0; a->front && j < t->n; j++) {
            const cand *o = &t->c[j];
            if (j == i || !usable(o)) continue;
            if (o->time_ms <= a->time_ms && o->err <= a->err && (o->time_ms < a->time_ms || o->err < a->err))
                a->front = false;
        }
    }
}

static int cmp_time(const void *a, const void *b) {
    const cand *x = *(const cand *const *)a, *y = *(const cand *const *)b;
    return x->time_ms < y->time_ms ? -1 : x->time_ms > y->time_ms;
}

static bool write_csv(const tune *t, sb_err *err) {
    sb_csv csv = {0};
    const char *const head[] = {"candidate", "technique", "spec", "rung", "frames", "status", "reason",
                                t->col.time_median, t->col.time_ci, t->col.err_mean, t->col.err_ci,
                                t->col.side_mean[SB_TUNE_FLICKER], t->col.side_mean[SB_TUNE_FLIP], "front",
                                "recommended", "ratio_to_recommended",
                                "ratio_ci_low", "ratio_ci_high", "run_id"};
    for (size_t k = 0; k < SB_COUNT(head); k++) sb_csv_str(&csv, head[k]);
    sb_csv_end_row(&csv);
    for (int i = 0; i < t->n; i++) {
        const cand *c = &t->c[i];
        sb_csv_int(&csv, i);
        sb_csv_str(&csv, c->spec.tech->name);
        sb_csv_str(&csv, c->label);
        sb_csv_int(&csv, c->rung);
        sb_csv_int(&csv, c->rung >= 0 ? c->frames : 0);
        sb_csv_str(&csv, c->rung < 0 ? "not_run"
                         : sb_status_names[c->skipped  ? SB_STATUS_SKIPPED
                                          : c->failed ? SB_STATUS_FAILED
                                                      : SB_STATUS_OK]);
        sb_csv_str(&csv, c->reason);
        sb_csv_num(&csv, c->time_ms);
        sb_csv_num(&csv, c->time_ci);
        sb_csv_num(&csv, c->err);
        sb_csv_num(&csv, c->err_ci);
        sb_csv_num(&csv, c->side[SB_TUNE_FLICKER]);
        sb_csv_num(&csv, c->side[SB_TUNE_FLIP]);
        sb_csv_str(&csv, c->front ? "yes" : "no");
        sb_csv_str(&csv, c->chosen ? "yes" : "no");
        sb_csv_num(&csv, c->ratio);
        sb_csv_num(&csv, isfinite(c->ratio_lo) ? c->ratio_lo : NAN);
        sb_csv_num(&csv, isfinite(c->ratio_hi) ? c->ratio_hi : NAN);
        sb_csv_str(&csv, c->rung >= 0 ? c->run_id[c->rung] : "");
        sb_csv_end_row(&csv);
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/tune.csv", t->dir);
    bool ok = sb_write_file_atomic(path, csv.buf, csv.len, err);
    sb_csv_free(&csv);
    return ok;
}

/* front.html (the report's chart): every candidate measured, the front joined, the choice ringed, the bound
 * dashed. A build without the charting library says so and writes the rest. */
static bool write_front(const tune *t, int chosen, bool met, sb_err *err) {
    if (!sb_site_available()) {
        sb_log("no front.html: this shadowbench was built without the charting library (libjs-dygraphs)");
        return true;
    }
    sb_site_point *p = sb_xcalloc((size_t)t->n, sizeof *p);
    int n = 0;
    for (int i = 0; i < t->n; i++) {
        const cand *c = &t->c[i];
        if (!usable(c)) continue;
        p[n++] = (sb_site_point){.technique = c->spec.tech->name, .label = c->label, .x = c->time_ms, .y = c->err,
                                 .frames = c->frames, .front = c->front, .chosen = i == chosen};
    }
    char title[2048], about[1024], bounds[512];
    bounds_text(t, bounds, sizeof bounds);
    snprintf(title, sizeof title, "tune %s along %s, %dx%d: %s", t->s.scene_name, t->s.path_name,
             t->cmd->opts->width, t->cmd->opts->height, bounds);
    snprintf(about, sizeof about, "Each point a candidate at the last rung it reached: the median frame time at the "
             "last rung (the fastest frame at earlier ones) against the mean error rate against the exact reference.");
    sb_site_front f = {.out = t->dir, .title = title, .about = about, .xlabel = t->col.time, .ylabel = t->col.err,
                       .bound = bound_of(t), .bound_on_x = t->cmd->max_err <= 0,
                       .chosen_is = met ? "the recommended setting" : "the closest (nothing met the bound)",
                       .points = p, .n = n};
    bool ok = sb_site_write_front(&f, err);
    free(p);
    return ok;
}

/* A file or a bundled name as a batch file can name it. */
static void batch_name(const char *what, char *out, size_t len) {
    char real[4096];
    if (access(what, R_OK) == 0 && realpath(what, real)) snprintf(out, len, "%s", real);
    else snprintf(out, len, "%s", what);
}

static void verdict_text(const tune *t, const verdict *v, char *out, size_t len);

static bool write_bench(const tune *t, const verdict *v, sb_err *err) {
    const int chosen = v->met ? v->chosen : -1;
    const sb_tune_cmd *cmd = t->cmd;
    const sb_run_opts *o = cmd->opts;
    char scene[4096], path[4096];
    batch_name(cmd->scene, scene, sizeof scene);
    batch_name(cmd->path ? cmd->path : "auto", path, sizeof path);
    sb_csv b = {0};
    line(&b, "# shadowbench tune %s %s: %s %g", cmd->scene, cmd->path ? cmd->path : "auto",
               cmd->max_err > 0 ? "--max-err" : "--budget-ms", bound_of(t));
    line(&b, "path tuned %s", path);
    line(&b, "scene %s %s tuned", t->s.scene_name, scene);
    line(&b, "defaults --frames %d --size %dx%d --error-every %d", o->frames, o->width, o->height,
               o->error_every > 0 ? o->error_every : 10);
    char say[1600];
    verdict_text(t, v, say, sizeof say);
    if (chosen >= 0) line(&b, "# %s: %s", t->c[chosen].label, say);
    const char *lights = o->lights ? " --lights " : "";   /* the lamps it was tuned for (a series of its own) */
    if (chosen >= 0) line(&b, "@%s %s%s%s", t->s.scene_name, t->c[chosen].label, lights, o->lights ? o->lights : "");
    else line(&b, "# nothing met the bound");
    char file[4200];
    snprintf(file, sizeof file, "%s/tune.bench", t->dir);
    bool ok = sb_write_file_atomic(file, b.buf, b.len, err);
    sb_csv_free(&b);
    return ok;
}

/* The verdict in one line: how much better the choice is than the next best within the bound, with its
 * confidence, or that the two tie and what decided. */
static void verdict_text(const tune *t, const verdict *v, char *out, size_t len) {
    char flag[64];
    bound_flag(t, flag, sizeof flag);
    const bool time = t->cmd->max_err > 0;
    if (v->chosen < 0 || !v->met) {
        snprintf(out, len, "nothing met %s", flag);
        return;
    }
    if (v->other < 0 && v->missed >= 0) {
        const cand *m = &t->c[v->missed];
        snprintf(out, len, "the only setting within %s: the next one, %s, missed it measured in full (%s %.4g)", flag,
                 m->label, time ? t->col.err : t->col.time, constraint_of(t, m));
        return;
    }
    if (v->other < 0) {
        snprintf(out, len, "the only setting measured within %s", flag);
        return;
    }
    char how[96];
    snprintf(how, sizeof how, "95 %% CI %.3g-%.3g, %d paired %s", v->p.lo, v->p.hi, v->p.n,
             v->p.by_pass ? "passes" : "frames");
    const char *other = t->c[v->other].label;
    if (!v->tie)
        snprintf(out, len, "%.3gx %s than %s (%s), both within %s", v->p.ratio, time ? "cheaper" : "less error",
                 other, how, flag);
    else
        snprintf(out, len, "ties with %s within the noise (its %s %.3gx of this one's, %s), both within %s; "
                 "picked on %s", other, time ? t->col.time : t->col.err, v->p.ratio, how, flag, v->picked_on);
}

static void print_report(const tune *t, const verdict *v) {
    const sb_tune_cmd *cmd = t->cmd;
    const int chosen = v->chosen;
    const bool met = v->met;
    const cand **vv = sb_xmalloc(sizeof *vv * (size_t)t->n);
    int nv = 0, skipped = 0, failed = 0;
    for (int i = 0; i < t->n; i++) {
        skipped += t->c[i].skipped, failed += t->c[i].failed;
        if (t->c[i].front) vv[nv++] = &t->c[i];
    }
    qsort(vv, (size_t)nv, sizeof *vv, cmp_time);
    char bounds[512];
    bounds_text(t, bounds, sizeof bounds);
    printf("%s along %s, %dx%d, %s\n", t->s.scene_name, t->s.path_name, cmd->opts->width, cmd->opts->height, bounds);
    if (chosen >= 0) {
        const cand *c = &t->c[chosen];
        char say[1600];
        verdict_text(t, v, say, sizeof say);
        printf("%s: %s\n  %s\n  %s median %.3g (95%% CI of the mean +-%.2g), %s %.4g (+-%.2g), %d frames x %d pass(es)\n",
               met ? "recommended" : "nothing met the bound; closest", c->label, say, t->col.time, c->time_ms,
               c->time_ci, t->col.err, c->err, c->err_ci, c->frames, c->rung >= t->nrungs - 1 ? t->final_reps : 1);
        for (int k = 0; k < SB_TUNE_SIDES; k++)
            if (cmd->max_side[k] > 0) printf("  %s %.4g\n", t->col.side[k], c->side[k]);
    } else {
        printf("no candidate could be measured\n");
    }
    if (t->kept) printf("  (%d run(s) kept from the resumed folder, not measured again)\n", t->kept);
    if (t->out_of_time)
        printf("  (%s ended the search after rung %d: figures from fewer frames)\n",
               sb_interrupted() ? sb_interrupt_name() : "the time limit", t->last_rung);
    printf("\nPareto front (time against error; frames: how many frames the figures are from):\n");
    printf("  %-52s %10s %9s %10s %9s %6s\n", "setting", t->col.time, "+-ci95", t->col.err, "+-ci95", "frames");
    for (int k = 0; k < nv; k++)
        printf("%c %-52s %10.3g %9.2g %10.4g %9.2g %6d\n", vv[k]->chosen ? '*' : ' ',
               vv[k]->label, vv[k]->time_ms, vv[k]->time_ci, vv[k]->err, vv[k]->err_ci, vv[k]->frames);
    long grid = 0;
    for (int i = 0; i < t->n; i++)
        if (!t->c[i].skipped && t->c[i].rung >= 0) grid += cmd->opts->frames + t->warmup;
    int finalists = 0;
    for (int i = 0; i < t->n; i++) finalists += t->c[i].rung >= t->nrungs - 1 && !t->c[i].skipped;
    const long search = t->frames_rendered - t->final_frames;
    printf("\n%d candidate(s) (%d skipped here, %d failed); frames rendered %ld of the full grid's %ld (%.0f%%): "
           "the search %ld (%.0f%%), the finalists' passes %ld (%d finalist(s) x %d interleaved pass(es))\n",
           t->n, skipped, failed, t->frames_rendered, grid, grid ? 100.0 * t->frames_rendered / grid : 0, search,
           grid ? 100.0 * search / grid : 0, t->final_frames, finalists, t->final_reps);
    if (grid && t->frames_rendered * 4 > grid && finalists <= 2 && !t->out_of_time)
        printf("  (over a quarter of the grid: a grid this small leaves no room for the two leaders' %d passes)\n",
               t->final_reps);
    for (int i = 0, shown = 0; i < t->n && shown < 5; i++)
        if (t->c[i].skipped) printf("  skipped %s: %s\n", t->c[i].label, t->c[i].reason), shown++;
    const char *lights = t->cmd->opts->lights;
    if (chosen >= 0 && met)
        printf("\nbatch line (pin it in a nightly):\n  @%s %s%s%s\n", t->s.scene_name, t->c[chosen].label,
               lights ? " --lights " : "", lights ? lights : "");
    printf("\nfront.html (open it in a browser), tune.csv and tune.bench in\n%s\n", t->dir);
    free(vv);
}

/* The search's folder: --resume's (its meta the same search's) or a new stamped one, and its meta; 0: ready, else
 * the exit status (said). */
static int open_folder(tune *t) {
    const sb_tune_cmd *cmd = t->cmd;
    sb_err err;
    if (cmd->resume) {
        snprintf(t->dir, sizeof t->dir, "%s", cmd->resume);
        if (cmd->identity && !sb_resume_check(t->dir, cmd->identity, NULL, -1, &err)) {   /* nothing written */
            sb_say_line(stderr, err.msg);
            return SB_EXIT_BAD_INPUT;
        }
    } else {
        char base[4200];
        snprintf(base, sizeof base, "%s/tune-%s", cmd->out, t->s.scene_name);
        if (!sb_make_stamped_dir(base, t->dir, sizeof t->dir, &err)) {
            sb_say_line(stderr, err.msg);
            return SB_EXIT_WRITE;   /* the results folder could not be made */
        }
    }
    if (cmd->identity) {   /* what the search is, for a resume to match (its rungs are results sets of their own) */
        char path[4400], text[8400];
        snprintf(path, sizeof path, "%s/meta", t->dir);
        int n = snprintf(text, sizeof text, "command: tune %s\n%s", cmd->scene, cmd->identity);
        if (!sb_write_file_atomic(path, text, (size_t)(n < (int)sizeof text ? n : (int)sizeof text - 1), &err))
            sb_say_line(stderr, err.msg);
    }
    return 0;
}

/* The rungs, successive halving: each rung's best go on to the next; the last rung run (-1: none) */
static int climb(tune *t) {
    int final_rung = -1, k1 = 0, k2 = 0;
    bool in_time = true;
    for (int r = 0; r < t->nrungs && in_time; r++) {
        in_time = run_rung(t, r);
        if (!in_time) break;
        final_rung = r;
        if (r == t->nrungs - 1) break;
        if (r == 0) {
            int runnable = 0;
            for (int i = 0; i < t->n; i++) runnable += measured_at(&t->c[i], 0);
            plan_keep(t, runnable, &k1, &k2);
            sb_log("tune: %d of %d can run here; %d go on to rung 1, %d to the last rung (%d pass(es) each)",
                   runnable, t->n, k1, k2, t->final_reps);
            if (k1 > 0) {
                promote(t, 0, k1, k1 / 2, 0.5);
            } else {   /* straight to the last rung */
                promote(t, 0, k2, k2, 0.5);
                r = t->nrungs - 2;
            }
        } else {
            promote(t, r, k2, k2, 0.2);
        }
    }
    t->out_of_time = !in_time;
    return final_rung;
}

int sb_tune_main(const sb_tune_cmd *cmd) {
    if ((cmd->max_err > 0) == (cmd->budget_ms > 0)) {
        fprintf(stderr, "shadowbench: tune needs one of --max-err E or --budget-ms B\n");
        return SB_EXIT_BAD_INPUT;
    }
    tune t;
    memset(&t, 0, sizeof t);
    t.cmd = cmd;
    tune_cols_init(&t.col);
    t.t0 = sb_now_ms();
    t.last_rung = -1;
    sb_err err;
    if (!make_candidates(&t, &err)) {
        sb_say_line(stderr, err.msg);
        return SB_EXIT_BAD_INPUT;
    }
    if (cmd->opts->error_every <= 0) {
        fprintf(stderr, "shadowbench: tune needs the error: --error-every must be at least 1\n");
        free(t.c);
        return SB_EXIT_BAD_INPUT;
    }
    plan_frames(&t);
    t.warmup = cmd->opts->warmup < 0 ? 1 : cmd->opts->warmup;
    t.final_reps = t.nrungs == 1 ? FINAL_PASSES : 1;   /* one rung: it is the last */
    int rc = 0;
    if (!sb_session_open(&t.s, cmd->opts, cmd->scene, cmd->path ? cmd->path : "auto", &err)) {
        sb_say_line(stderr, err.msg);
        rc = t.s.files_refused ? SB_EXIT_BAD_INPUT : SB_EXIT_FAILED;
    }
    if (rc || (rc = open_folder(&t)) != 0) {
        sb_session_close(&t.s);
        free(t.c);
        return rc;
    }
    sb_session_keep_reference(&t.s, t.dir);   /* OUT/tune-SCENE/.reference: reruns and --resume cast no ray twice */
    memory_bound(&t);
    sb_log("tune: %d candidate(s), rungs of %d/%d/%d frames, seed %llu, results in %s", t.n, t.rung_frames[0],
           t.nrungs > 1 ? t.rung_frames[1] : t.rung_frames[0], t.rung_frames[t.nrungs - 1],
           (unsigned long long)cmd->opts->seed, t.dir);
    warm_session(&t);
    int final_rung = climb(&t);
    int rung = t.out_of_time ? t.last_rung : final_rung;
    verdict v = rung >= 0 ? decide(&t, rung) : (verdict){.chosen = -1, .other = -1, .missed = -1};
    if (!t.out_of_time && v.met && v.other < 0 && !confirm(&t, &v, &rung)) t.out_of_time = true;
    int chosen = v.chosen;
    bool met = v.met;
    if (chosen >= 0) t.c[chosen].chosen = true;
    ratios_to(&t, rung, chosen);
    mark_front(&t);
    bool ok = write_csv(&t, &err) && write_front(&t, chosen, met, &err) && write_bench(&t, &v, &err);
    if (!ok) sb_say_line(stderr, err.msg);
    print_report(&t, &v);
    sb_session_close(&t.s);
    free(t.c);
    if (sb_interrupted()) {   /* said even with --quiet: the folder is half a search */
        fprintf(stderr, "shadowbench: interrupted: the runs measured so far are in %s; the rest: the same command "
                        "with --resume %s\n", t.dir, t.dir);
        return SB_EXIT_SIGNAL + sb_interrupted();
    }
    return ok && met ? SB_EXIT_OK : SB_EXIT_FAILED;
}
