/* changepoint.c - optimal partitioning of a weighted mean-shift cost (changepoint.h). */
#include "changepoint.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median_of(double *v, int n) {
    if (n <= 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* sum w, sum w x, sum w x^2 over [s, t) from prefix sums */
typedef struct { double *w, *wx, *wxx; } prefix;

static double seg_cost(const prefix *p, int s, int t) {
    double W = p->w[t] - p->w[s], S = p->wx[t] - p->wx[s], Q = p->wxx[t] - p->wxx[s];
    if (W <= 0) return 0;
    double c = Q - S * S / W;
    return c > 0 ? c : 0;
}

/* The least-cost cut of v[0..k) into segments of >= m (cost / sigma^2 + beta a change); the cuts (starts of
   segments after the first) written last first. */
static int search(const prefix *p, int k, int m, double beta, double sigma, int *cuts) {
    double s2 = sigma * sigma;
    double *F = sb_xmalloc(sizeof *F * (size_t)(k + 1));
    int *last = sb_xmalloc(sizeof *last * (size_t)(k + 1));
    for (int t = 0; t <= k; t++) F[t] = INFINITY, last[t] = 0;
    F[0] = -beta;
    for (int t = m; t <= k; t++)
        for (int s = 0; s + m <= t; s++) {
            if ((s > 0 && s < m) || !isfinite(F[s])) continue;
            double c = F[s] + seg_cost(p, s, t) / s2 + beta;
            if (c < F[t]) F[t] = c, last[t] = s;
        }
    int nc = 0;
    for (int t = k; t > 0; t = last[t])
        if (last[t] > 0) cuts[nc++] = last[t];
    free(F);
    free(last);
    return nc;
}

/* The noise of v[0..k) (k >= 2): the median absolute difference of neighbours as a sigma, at least the floor (a
 * share of the mean magnitude, or of the log), and v centred. */
static double noise_and_centre(double *v, int k, bool logs, double noise_floor) {
    double *diff = sb_xmalloc(sizeof *diff * (size_t)k);
    for (int i = 0; i + 1 < k; i++) diff[i] = fabs(v[i + 1] - v[i]);
    double sigma = 1.4826 * median_of(diff, k - 1) / sqrt(2.0);
    free(diff);
    double mag = 0;
    for (int i = 0; i < k; i++) mag += fabs(v[i]);
    mag /= k;
    double floor_ = noise_floor > 0 ? (logs ? noise_floor : noise_floor * mag) : 0;
    if (sigma < floor_) sigma = floor_;
    /* a deterministic series (counts, error rates): any shift of the figures as written (6 digits) is a change, and
       rounding in the sums is not */
    double tiny = logs ? 1e-7 : 1e-7 * (1 + mag);
    if (sigma < tiny) sigma = tiny;
    /* centred, so that the sums of squares below carry no rounding of the level itself */
    double mean = 0;
    for (int i = 0; i < k; i++) mean += v[i];
    mean /= k;
    for (int i = 0; i < k; i++) v[i] -= mean;
    return sigma;
}

/* One odd night is clipped to within 3 sigma of the median of itself and its neighbours (at the ends, of the first
 * or last three): it can neither make a change nor, by inflating the noise, hide one; a level held for two nights
 * is its own median and stays. */
static void clip_odd_nights(double *v, int k, double sigma) {
    double *c3 = sb_xmalloc(sizeof *c3 * (size_t)k);
    for (int i = 0; i < k; i++) {
        int a = i == 0 ? 0 : i == k - 1 ? k - 3 : i - 1;
        if (a < 0) a = 0;
        double t[3];
        int nt = 0;
        for (int j = a; j < a + 3 && j < k; j++) t[nt++] = v[j];
        double med = median_of(t, nt);
        c3[i] = v[i] > med + 3 * sigma ? med + 3 * sigma : v[i] < med - 3 * sigma ? med - 3 * sigma : v[i];
    }
    memcpy(v, c3, sizeof *v * (size_t)k);
    free(c3);
}

/* The cut (search), then with the residual noise of that cut when it is larger than the estimate from the
 * differences (which a short noisy series can underestimate): the larger of the two is kept in *sigma. */
static int cut_with_noise(const prefix *p, int k, int m, double beta, double *sigma, int *cuts) {
    int nc = search(p, k, m, beta, *sigma, cuts);
    for (int it = 0; it < 3; it++) {
        double rss = 0;
        for (int c = 0, a = 0; c <= nc; c++) {
            int b = c < nc ? cuts[nc - 1 - c] : k;
            rss += seg_cost(p, a, b);
            a = b;
        }
        int dof = k - nc - 1;
        if (dof < 1) break;
        double sr = sqrt(rss / p->w[k] * k / dof);
        if (!(sr > *sigma * 1.0001)) break;
        *sigma = sr;
        nc = search(p, k, m, beta, *sigma, cuts);
    }
    return nc;
}

/* The change at cut `at` between the segments [a, at) and [at, b): medians of the figures as given, its z and a
 * p-value corrected for the places a change could have been. */
static void describe(const double *x, const int *idx, const prefix *p, int k, int m, int a, int at, int b,
                     double sigma, sb_cp_change *ch) {
    double *tmp = sb_xmalloc(sizeof *tmp * (size_t)k);
    int nt = 0;
    for (int i = a; i < at; i++) tmp[nt++] = x[idx[i]];
    ch->before = median_of(tmp, nt);
    nt = 0;
    for (int i = at; i < b; i++) tmp[nt++] = x[idx[i]];
    ch->after = median_of(tmp, nt);
    free(tmp);
    ch->at = idx[at];
    ch->rel = ch->before != 0 ? ch->after / ch->before - 1 : NAN;
    double Wa = p->w[at] - p->w[a], Wb = p->w[b] - p->w[at];
    double ma = (p->wx[at] - p->wx[a]) / Wa, mb = (p->wx[b] - p->wx[at]) / Wb;
    ch->z = (mb - ma) / (sigma * sqrt(1 / Wa + 1 / Wb));
    int places = k - 2 * m + 1;
    double pv = erfc(fabs(ch->z) / sqrt(2.0)) * (places > 1 ? places : 1);
    ch->p = pv < 1 ? pv : 1;
}

int sb_changepoints(const double *x, const double *w, int n, const sb_cp_opts *o, sb_cp_change *out, int max,
                    double *sigma_out) {
    sb_cp_opts d = o ? *o : (sb_cp_opts){0};
    double beta = d.penalty > 0 ? d.penalty : SB_CP_PENALTY;
    int m = d.min_seg > 0 ? d.min_seg : SB_CP_MIN_SEG;
    /* the nights with a value, on the scale read */
    double *v = sb_xmalloc(sizeof *v * (size_t)(n + 1)), *wt = sb_xmalloc(sizeof *wt * (size_t)(n + 1));
    int *idx = sb_xmalloc(sizeof *idx * (size_t)(n + 1));
    int k = 0;
    bool logs = d.relative;
    for (int i = 0; i < n; i++)
        if (isfinite(x[i]) && x[i] <= 0) logs = false;
    for (int i = 0; i < n; i++) {
        if (!isfinite(x[i])) continue;
        double wi = w ? w[i] : 1.0;
        if (!(wi > 0)) continue;
        v[k] = logs ? log(x[i]) : x[i];
        wt[k] = wi > 1 ? 1 : wi;
        idx[k++] = i;
    }
    int found = 0;
    double sigma = k >= 2 ? noise_and_centre(v, k, logs, d.noise_floor) : 0;
    if (k >= 2 * m) {
        clip_odd_nights(v, k, sigma);
        prefix p = {sb_xcalloc((size_t)k + 1, sizeof(double)), sb_xcalloc((size_t)k + 1, sizeof(double)),
                    sb_xcalloc((size_t)k + 1, sizeof(double))};
        for (int i = 0; i < k; i++) {
            p.w[i + 1] = p.w[i] + wt[i];
            p.wx[i + 1] = p.wx[i] + wt[i] * v[i];
            p.wxx[i + 1] = p.wxx[i] + wt[i] * v[i] * v[i];
        }
        int *cuts = sb_xmalloc(sizeof *cuts * (size_t)k), nc = cut_with_noise(&p, k, m, beta, &sigma, cuts);
        for (int c = nc - 1; c >= 0; c--, found++)
            if (found < max)
                describe(x, idx, &p, k, m, c + 1 < nc ? cuts[c + 1] : 0, cuts[c], c > 0 ? cuts[c - 1] : k, sigma,
                         &out[found]);
        free(cuts);
        free(p.w);
        free(p.wx);
        free(p.wxx);
    }
    if (sigma_out) *sigma_out = sigma;
    free(v);
    free(wt);
    free(idx);
    return found;
}
