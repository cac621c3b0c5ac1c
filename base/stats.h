/* stats.h - summary statistics of per-frame samples.
 * ci95 is the half-width of the 95% confidence interval of the mean from the
 * t-distribution (t-interval, n-1 degrees of freedom). */
#pragma once

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
