/* error.c - per-frame shadow error against the Embree reference. */
#include "error.h"

#include <stdlib.h>
#include <string.h>

#include "stats.h"

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y ? 1 : 0;
}

void sb_evaluate_frame(const sb_reference *r, const double light[4], sb_v3 eye, int w, int h, const float *pos,
                       const float *aux, const unsigned char *vis, unsigned char *ref_out, sb_error_metrics *out,
                       int threads) {
    memset(out, 0, sizeof *out);
    int n = w * h;
    sb_ref_point *pts = sb_xmalloc(sizeof *pts * (size_t)(n > 0 ? n : 1));
    int *pix = sb_xmalloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
    int m = 0;
    for (int i = 0; i < n; i++) {
        const float *a = aux + 4 * (size_t)i, *p = pos + 4 * (size_t)i;
        if (ref_out) ref_out[i] = 128;
        double nl = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        if (nl < 0.5) continue;                                   /* sky */
        double L[3] = {light[0], light[1], light[2]};
        if (light[3] > 0.5)
            for (int k = 0; k < 3; k++) L[k] -= p[k];
        if (a[0] * L[0] + a[1] * L[1] + a[2] * L[2] <= 0) continue;   /* facing away from the light */
        sb_ref_point *q = &pts[m];
        memcpy(q->p, p, sizeof q->p);
        memcpy(q->n, a, sizeof q->n);
        q->eps = sb_ref_position_eps(r, q->p, (float)sb_v3_len(sb_v3_sub(sb_v3_make(p[0], p[1], p[2]), eye)));
        pix[m++] = i;
    }
    unsigned char *ref = sb_xmalloc((size_t)(m > 0 ? m : 1));
    double t0 = sb_now_ms();
    out->rays = sb_reference_visibility_light(r, light, pts, m, ref, threads);
    out->ray_ms = sb_now_ms() - t0;
    double *res_err = sb_xmalloc(sizeof(double) * (size_t)(m > 0 ? m : 1));
    double *texel = sb_xmalloc(sizeof(double) * (size_t)(m > 0 ? m : 1));
    int nres = 0;
    long wrong = 0, fshadow = 0, flit = 0;
    double mae = 0;
    for (int k = 0; k < m; k++) {
        int i = pix[k];
        double v = vis[i] / 255.0;
        bool tech_shadow = vis[i] < 128, ref_shadow = ref[k] == 0;
        if (ref_out) ref_out[i] = ref_shadow ? 0 : 255;
        wrong += tech_shadow != ref_shadow;
        fshadow += tech_shadow && !ref_shadow;
        flit += !tech_shadow && ref_shadow;
        mae += fabs(v - (ref_shadow ? 0.0 : 1.0));
        float d = pos[4 * (size_t)i + 3];
        if (d > 0) {
            texel[nres] = d;
            res_err[nres++] = fmax(-log2(d), 0.0);
        }
    }
    out->pixels = m;
    if (m > 0) {
        out->err_rate = (double)wrong / m;
        out->false_shadow = (double)fshadow / m;
        out->false_lit = (double)flit / m;
        out->vis_mae = mae / m;
    }
    out->res_err_mean = out->res_err_p95 = out->texel_px_p95 = NAN;
    if (nres > 0) {
        double sum = 0;
        for (int k = 0; k < nres; k++) sum += res_err[k];
        out->res_err_mean = sum / nres;
        qsort(res_err, (size_t)nres, sizeof(double), cmp_double);
        qsort(texel, (size_t)nres, sizeof(double), cmp_double);
        out->res_err_p95 = sb_percentile(res_err, nres, 0.95);
        out->texel_px_p95 = sb_percentile(texel, nres, 0.95);
    }
    free(res_err);
    free(texel);
    free(ref);
    free(pts);
    free(pix);
}
