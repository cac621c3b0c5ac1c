/* stats.h - summary statistics of per-frame samples.
 * ci95 is the half-width of the 95% confidence interval of the mean from the
 * t-distribution (t-interval, n-1 degrees of freedom). */
#pragma once
#include <stdbool.h>

typedef struct sb_stats {
    int n;
    double mean, median, p95, p99, std, ci95, min, max;
} sb_stats;

/* NaN samples are ignored; with no samples every field is NaN. */
sb_stats sb_stats_compute(const double *v, int n);
double sb_percentile(const double *sorted, int n, double p);
/* The same percentile of unsorted a (n values), found by selection in linear
 * expected time; reorders a. */
double sb_percentile_select(double *a, int n, double p);   /* linear interpolation */
double sb_t975(int dof);                                        /* two-sided 95% t quantile */

/* Two things measured side by side, pass by pass (pairs a_i, b_i: the same load of the moment on both): the mean
 * difference b - a and its 95% CI, and b over a as a ratio of means, 1 + diff / mean(a), with its CI (lo >= 0).
 * Below two pairs the CI is unbounded. Pairs with a NaN are skipped. tune's finalists and bisect's commits are
 * judged by it. */
typedef struct sb_paired {
    int n;                      /* pairs used */
    double a, b;                /* the means */
    double diff, ci;            /* mean of b - a, its 95% CI half-width (INFINITY below 2 pairs) */
    double ratio, lo, hi;       /* b / a (NaN when mean(a) <= 0), its CI (-inf, inf below 2 pairs) */
} sb_paired;
sb_paired sb_paired_compute(const double *a, const double *b, int n);

/* b against a at a share (0.05: within 5 % is no difference): higher when its ratio's CI lies above 1 + share,
 * lower when below 1 - share, else a tie. */
typedef enum sb_pair_verdict { SB_PAIR_TIE, SB_PAIR_LOWER, SB_PAIR_HIGHER } sb_pair_verdict;
sb_pair_verdict sb_paired_verdict(const sb_paired *p, double share);
/* Whether b differs from a beyond the noise (|diff| above its CI) and by at least threshold_pct of mean(a). */
bool sb_paired_differs(const sb_paired *p, double threshold_pct);
