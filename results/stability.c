/* stability.c - the stability verdict of a run (see stability.h). */
#include "stability.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stats.h"
#include "util.h"

static void add(char *why, size_t len, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void add(char *why, size_t len, const char *fmt, ...) {
    size_t n = strlen(why);
    if (n && n + 2 < len) {
        memcpy(why + n, "; ", 3);
        n += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why + n, len - n, fmt, ap);
    va_end(ap);
}

/* Paired drift between the first and the last repetition; returns the relative change (NaN: no test). */
static double drift(const sb_stability_in *in, double tol, bool *beyond) {
    int m = in->per_repeat, reps = m > 0 ? in->n / m : 0;
    *beyond = false;
    if (reps < 2 || m < 2) return NAN;
    const double *first = in->frame_ms, *last = in->frame_ms + (size_t)(reps - 1) * m;
    double *d = sb_xmalloc(sizeof(double) * (size_t)m);
    double base = 0;
    for (int i = 0; i < m; i++) {
        d[i] = last[i] - first[i];
        base += first[i] / m;
    }
    sb_stats st = sb_stats_compute(d, m);
    free(d);
    if (!(base > 0) || isnan(st.mean)) return NAN;
    double rel = st.mean / base;
    *beyond = fabs(rel) > tol && fabs(st.mean) > st.ci95;
    return rel;
}

bool sb_stability(const sb_stability_in *in, char *why, size_t len) {
    double ptol = in->probe_tol > 0 ? in->probe_tol : SB_PROBE_TOL;
    double btol = in->batch_tol > 0 ? in->batch_tol : SB_BATCH_TOL;
    double dtol = in->drift_tol > 0 ? in->drift_tol : SB_DRIFT_TOL;
    why[0] = 0;
    double a = in->calib_before, b = in->calib_after;
    if (a > 0 && b > 0 && fabs(b / a - 1) > ptol)
        add(why, len, "the calibration probe changed %+.0f%% during the run (%.3g ms before, %.3g ms after)",
            100 * (b / a - 1), a, b);
    if (a > 0 && in->nbatch >= 3) {
        double *v = sb_xmalloc(sizeof(double) * (size_t)in->nbatch);
        memcpy(v, in->batch_calib, sizeof(double) * (size_t)in->nbatch);
        sb_stats st = sb_stats_compute(v, in->nbatch);
        free(v);
        if (st.median > 0 && fabs(a / st.median - 1) > btol)
            add(why, len, "the calibration probe was %+.0f%% off the batch median (%.3g ms against %.3g ms)",
                100 * (a / st.median - 1), a, st.median);
    }
    bool beyond;
    double rel = drift(in, dtol, &beyond);
    if (beyond)
        add(why, len, "frame times drifted %+.0f%% from the first repetition of the path to the last (beyond their 95%% CI)",
            100 * rel);
    return why[0] == 0;
}

/* One line's fields (at most 4 + SB_REPLAY_REPS), split at blanks; the count, or -1 past the most. */
static int split_fields(const char *line, size_t n, char f[][64]) {
    int k = 0;
    for (size_t i = 0; i < n;) {
        while (i < n && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) i++;
        if (i == n || line[i] == '#') break;
        size_t b = i;
        while (i < n && line[i] != ' ' && line[i] != '\t' && line[i] != '\r' && line[i] != '#') i++;
        if (k == 4 + SB_REPLAY_REPS || i - b >= 64) return -1;
        memcpy(f[k], line + b, i - b);
        f[k++][i - b] = 0;
    }
    return k;
}

int sb_stability_replay_find(const char *text, const char *technique, int attempt, sb_stability_replay *out,
                             char *why, size_t len) {
    int lineno = 0, found = 0;
    for (const char *p = text; *p;) {
        const char *nl = strchr(p, '\n');
        size_t n = nl ? (size_t)(nl - p) : strlen(p);
        lineno++;
        char f[4 + SB_REPLAY_REPS][64];
        int k = split_fields(p, n, f);
        p += n + (nl != NULL);
        if (k == 0) continue;
        if (k < 5) {   /* -1: too many fields or one too long */
            snprintf(why, len, "line %d: expected technique attempt calib_before calib_after ms_1 [... ms_%d]", lineno,
                     SB_REPLAY_REPS);
            return -1;
        }
        long a = 0;
        sb_stability_replay r = {.nreps = k - 4};
        bool ok = (!strcmp(f[1], "*") || (sb_parse_int(f[1], &a) && a >= 1)) && sb_parse_double(f[2], &r.calib_before) &&
                  sb_parse_double(f[3], &r.calib_after) && r.calib_before > 0 && r.calib_after > 0 &&
                  isfinite(r.calib_before) && isfinite(r.calib_after);
        for (int i = 0; ok && i < r.nreps; i++)
            ok = sb_parse_double(f[4 + i], &r.rep_ms[i]) && r.rep_ms[i] > 0 && isfinite(r.rep_ms[i]);
        if (!ok) {
            snprintf(why, len, "line %d: the attempt must be * or 1 and on, the probe and frame times positive numbers",
                     lineno);
            return -1;
        }
        if (!found && (!strcmp(f[0], "*") || !strcmp(f[0], technique)) && (!strcmp(f[1], "*") || a == attempt)) {
            *out = r;
            found = 1;   /* the rest read on: a typo anywhere in the file fails every run, not only some */
        }
    }
    return found;
}

typedef struct by_cost {
    double s;
    int i;
} by_cost;

static int cheaper(const void *a, const void *b) {
    const by_cost *x = a, *y = b;
    return x->s < y->s ? -1 : x->s > y->s ? 1 : x->i - y->i;
}

void sb_rerun_plan_make(const sb_rerun_run *runs, int n, const double *probe, int np, double night_s, double spent_s,
                        double tol, bool *rerun, sb_rerun_plan *out) {
    memset(out, 0, sizeof *out);
    out->runs = n;
    /* the calm: the 10th percentile of the night's finite probes (a night busy for three quarters of its runs still
       has its calm ones below it) */
    double *p = sb_xmalloc(sizeof(double) * (size_t)(np > 0 ? np : 1));
    int nf = 0;
    for (int i = 0; i < np; i++)
        if (isfinite(probe[i]) && probe[i] > 0) p[nf++] = probe[i];
    out->calm_ms = nf ? sb_percentile_select(p, nf, 0.10) : NAN;
    free(p);
    for (int i = 0, streak = 0; i < np; i++) {
        bool busy = isfinite(out->calm_ms) && isfinite(probe[i]) && probe[i] > out->calm_ms * (1 + tol);
        streak = busy ? streak + 1 : 0;
        if (streak > out->busy_streak) out->busy_streak = streak;
    }
    double known = 0;
    int nknown = 0;
    for (int i = 0; i < n; i++) {
        out->unstable += runs[i].unstable;
        if (isfinite(runs[i].wall_s)) known += runs[i].wall_s, nknown++;
    }
    int stretch = np / 5 > 3 ? np / 5 : 3;
    out->disturbed = out->unstable > SB_RERUN_DISTURBED * n && out->busy_streak >= stretch;
    double budget = SB_RERUN_SHARE * night_s;
    out->budget_s = (budget > SB_RERUN_FLOOR_S ? budget : SB_RERUN_FLOOR_S) - spent_s;
    /* cheapest first, while they fit */
    by_cost *c = sb_xmalloc(sizeof *c * (size_t)(n > 0 ? n : 1));
    int nc = 0;
    for (int i = 0; i < n; i++) {
        rerun[i] = false;
        if (runs[i].unstable) c[nc++] = (by_cost){isfinite(runs[i].wall_s) ? runs[i].wall_s : nknown ? known / nknown : 0, i};
    }
    qsort(c, (size_t)nc, sizeof *c, cheaper);
    for (int k = 0; k < nc && out->planned_s + c[k].s <= out->budget_s; k++) {
        rerun[c[k].i] = true;
        out->planned_s += c[k].s;
        out->chosen++;
    }
    free(c);
}
