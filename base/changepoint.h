/* changepoint.h - where a series of nightly figures changes level.
 *
 * Optimal partitioning (PELT's exact search; the series are short enough that
 * nothing needs pruning) of a weighted Gaussian mean-shift cost: segment cost
 * sum w_i (x_i - mean_w)^2 / sigma^2, plus a penalty for each change.
 *
 * - sigma, the night-to-night noise, is estimated robustly from the series
 *   itself: 1.4826 * median |x_{i+1} - x_i| / sqrt(2) (a level shift moves one
 *   difference, not the median), floored at noise_floor; or, when larger,
 *   from the residuals of the cut found (and the cut made again).
 * - One odd night is clipped to within 3 sigma of the median of itself and
 *   its neighbours before the search: it neither makes a change nor, by
 *   inflating sigma, hides one.
 * - With `relative`, positive series are read on a log scale, so a change is a
 *   ratio (5 % is 5 % at 1 ms or at 100 ms) and noise_floor is relative.
 * - A night's weight (0..1] says how much it counts: the caller lowers it for
 *   a night whose timings were marked unstable, or whose own confidence
 *   interval is wide. A weak night moves the cost less; it is not a change.
 * - Every segment has at least min_seg nights, so one odd night is never a
 *   change and a change is reported once two nights show it.
 * - The penalty: with sigma known, adding one change at the best of the n-2m+1
 *   places lowers the cost by the largest of their z^2, each chi-square with
 *   one degree of freedom under no change. A penalty at its 1 - 1/10000
 *   quantile (15.14) bounds the false changes of a series of n nights by
 *   n/10000 (Bonferroni): a tenth of the budget of one in 1,000
 *   series-nights, the rest paying for sigma being estimated and for cuts
 *   into several segments. tests/unit/test_changepoint.c measures the rates (and
 *   docs/history.md gives them). */
#pragma once
#include <stdbool.h>

#define SB_CP_PENALTY 15.14
#define SB_CP_MIN_SEG 2

typedef struct sb_cp_opts {
    double penalty;         /* 0: SB_CP_PENALTY */
    int min_seg;            /* 0: SB_CP_MIN_SEG */
    double noise_floor;     /* the least sigma (relative with `relative`); 0: none */
    bool relative;          /* log scale when every value is > 0 */
} sb_cp_opts;

typedef struct sb_cp_change {
    int at;                 /* index of the first night after the change */
    double before, after;   /* medians of the segments on either side */
    double rel;             /* after / before - 1 (NaN when before is 0) */
    double z;               /* the shift over its standard error (signed: after - before) */
    double p;               /* two-sided normal p of z, times the places tried (Bonferroni), <= 1 */
} sb_cp_change;

/* Finds the changes of x[0..n) (w: weights, NULL for all 1; NaN values are
 * skipped). Writes at most max changes in order and returns how many there
 * are; *sigma (may be NULL) gets the noise estimate used, on the scale read. */
int sb_changepoints(const double *x, const double *w, int n, const sb_cp_opts *o, sb_cp_change *out, int max,
                    double *sigma);
