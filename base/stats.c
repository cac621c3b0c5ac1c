/* stats.c - mean, median, percentiles, standard deviation, t-interval. */
#include "stats.h"

#include <math.h>
#include <stdlib.h>

#include "util.h"

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y ? 1 : 0;
}

double sb_percentile(const double *s, int n, double p) {
    if (n <= 0) return NAN;
    double pos = p * (n - 1);
    int i = (int)floor(pos);
    if (i >= n - 1) return s[n - 1];
    double f = pos - i;
    return s[i] + (s[i + 1] - s[i]) * f;
}

/* Rearranges a[lo..hi] so that a[k] holds the value it would hold sorted,
 * smaller values before it and larger after (Hoare's selection). */
static void select_kth(double *a, int lo, int hi, int k) {
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        double x = a[mid] < a[lo] ? (a[hi] < a[mid] ? a[mid] : a[hi] < a[lo] ? a[hi] : a[lo])
                                  : (a[hi] < a[lo] ? a[lo] : a[hi] < a[mid] ? a[hi] : a[mid]); /* median of 3 */
        int i = lo, j = hi;
        while (i <= j) {
            while (a[i] < x) i++;
            while (x < a[j]) j--;
            if (i <= j) {
                double t = a[i];
                a[i++] = a[j];
                a[j--] = t;
            }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else return;
    }
}

double sb_percentile_select(double *a, int n, double p) {
    if (n <= 0) return NAN;
    double pos = p * (n - 1);
    int i = (int)floor(pos);
    if (i >= n - 1) i = n - 1;
    select_kth(a, 0, n - 1, i);
    if (i == n - 1) return a[i];
    double next = a[i + 1];
    for (int k = i + 2; k < n; k++) next = a[k] < next ? a[k] : next;
    return a[i] + (next - a[i]) * (pos - i);
}

double sb_t975(int dof) {
    static const double table[] = {NAN,    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262,
                                   2.228,  2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093,
                                   2.086,  2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045,
                                   2.042};
    if (dof <= 0) return NAN;
    if (dof <= 30) return table[dof];
    /* Cornish-Fisher expansion around z = 1.959964 */
    double z = 1.959964, d = dof;
    return z + (z * z * z + z) / (4 * d) + (5 * pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * d * d);
}

sb_stats sb_stats_compute(const double *v, int n) {
    sb_stats s = {0, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
    double *c = sb_xmalloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    int m = 0;
    for (int i = 0; i < n; i++)
        if (!isnan(v[i])) c[m++] = v[i];
    s.n = m;
    if (m == 0) {
        free(c);
        return s;
    }
    qsort(c, (size_t)m, sizeof(double), cmp);
    double sum = 0;
    for (int i = 0; i < m; i++) sum += c[i];
    s.mean = sum / m;
    s.min = c[0];
    s.max = c[m - 1];
    s.median = sb_percentile(c, m, 0.5);
    s.p95 = sb_percentile(c, m, 0.95);
    s.p99 = sb_percentile(c, m, 0.99);
    if (m > 1) {
        double ss = 0;
        for (int i = 0; i < m; i++) ss += (c[i] - s.mean) * (c[i] - s.mean);
        s.std = sqrt(ss / (m - 1));
        s.ci95 = sb_t975(m - 1) * s.std / sqrt((double)m);
    }
    free(c);
    return s;
}

sb_paired sb_paired_compute(const double *a, const double *b, int n) {
    sb_paired p = {.ratio = NAN, .lo = -INFINITY, .hi = INFINITY, .ci = INFINITY};
    double *x = sb_xmalloc(sizeof *x * (size_t)(n > 0 ? n : 1)), *d = sb_xmalloc(sizeof *d * (size_t)(n > 0 ? n : 1));
    double sb = 0;
    for (int i = 0; i < n; i++)
        if (!isnan(a[i]) && !isnan(b[i])) x[p.n] = a[i], d[p.n++] = b[i] - a[i], sb += b[i];
    if (p.n >= 1) {
        sb_stats sx = sb_stats_compute(x, p.n), sd = sb_stats_compute(d, p.n);
        p.a = sx.mean, p.b = sb / p.n, p.diff = sd.mean;
        if (p.n >= 2) p.ci = sd.ci95;
        if (sx.mean > 0) {
            p.ratio = 1 + sd.mean / sx.mean;
            if (p.n >= 2) p.lo = fmax(0, 1 + (sd.mean - sd.ci95) / sx.mean), p.hi = 1 + (sd.mean + sd.ci95) / sx.mean;
        }
    } else {
        p.a = p.b = p.diff = NAN;
    }
    free(x);
    free(d);
    return p;
}

sb_pair_verdict sb_paired_verdict(const sb_paired *p, double share) {
    if (p->lo > 1 + share) return SB_PAIR_HIGHER;
    if (p->hi < 1 - share) return SB_PAIR_LOWER;
    return SB_PAIR_TIE;
}

bool sb_paired_differs(const sb_paired *p, double threshold_pct) {
    return fabs(p->diff) > p->ci && p->a != 0 && 100 * fabs(p->diff) / fabs(p->a) >= threshold_pct;
}
