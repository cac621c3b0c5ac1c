/* resolve.c - TAA's per-pixel resolve (resolve.h). */
#include "resolve.h"

#include <math.h>
#include <string.h>

#include "error.h"

void sb_taa_jitter(int k, double *jx, double *jy) {
    double r[2] = {0, 0};
    const int base[2] = {2, 3};
    for (int d = 0; d < 2; d++) {
        double f = 1;
        for (int i = k + 1; i > 0; i /= base[d]) {
            f /= base[d];
            r[d] += f * (i % base[d]);
        }
    }
    *jx = r[0] - 0.5, *jy = r[1] - 0.5;
}

/* Origin-relative point p through a view-projection to pixel coordinates (x right, y up from the bottom row, pixel
 * centres at integers); false behind the camera. */
static bool to_pixel(const sb_m4 *vp, const float *p, int w, int h, double *sx, double *sy) {
    const double *m = vp->m;
    double x = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12], y = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13],
           cw = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    if (cw <= 1e-9) return false;
    *sx = (x / cw * 0.5 + 0.5) * w - 0.5;
    *sy = (y / cw * 0.5 + 0.5) * h - 0.5;
    return true;
}

/* Pixel (x, y): the history at its reprojected point, bilinear, clamped to the current 3x3 neighbourhood and
 * blended into out (which holds the current frame). */
static void resolve_pixel(const sb_taa_frame *f, int x, int y, double sx, double sy, const float *hist_rgb,
                          const float *hist_vis, float *o, float *ov) {
    const int w = f->w, h = f->h;
    const size_t i = (size_t)y * w + x;
    int x0 = (int)sx, y0 = (int)sy, x1 = x0 + 1 < w ? x0 + 1 : x0, y1 = y0 + 1 < h ? y0 + 1 : y0;
    double fx = sx - x0, fy = sy - y0, wt[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    size_t at[4] = {(size_t)y0 * w + x0, (size_t)y0 * w + x1, (size_t)y1 * w + x0, (size_t)y1 * w + x1};
    double H[4] = {0, 0, 0, 0};
    for (int s = 0; s < 4; s++) {
        for (int c = 0; c < 3; c++) H[c] += wt[s] * hist_rgb[3 * at[s] + c];
        H[3] += wt[s] * hist_vis[at[s]];
    }
    double lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            size_t j = (size_t)ny * w + nx;
            for (int c = 0; c < 4; c++) {
                double v = c < 3 ? f->rgb[3 * j + c] : f->vis[j];
                lo[c] = fmin(lo[c], v), hi[c] = fmax(hi[c], v);
            }
        }
    for (int c = 0; c < 4; c++) {
        double hc = fmin(fmax(H[c], lo[c]), hi[c]), now = c < 3 ? f->rgb[3 * i + c] : f->vis[i];
        double v = hc + SB_TAA_ALPHA * (now - hc);
        if (c < 3) o[c] = (float)v;
        else *ov = (float)v;
    }
}

void sb_taa_resolve(const sb_taa_frame *f, bool have_history, float *hist_rgb, float *hist_vis, float *out_rgb,
                    float *out_vis) {
    const int w = f->w, h = f->h;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const size_t i = (size_t)y * w + x;
            memcpy(out_rgb + 3 * i, f->rgb + 3 * i, sizeof(float) * 3);
            out_vis[i] = f->vis[i];
            double sx, sy;
            if (!have_history || !sb_eval_has_geometry(f->aux, i) || !to_pixel(f->prev_vp, f->pos + 4 * i, w, h, &sx, &sy) ||
                sx < 0 || sy < 0 || sx > w - 1 || sy > h - 1)
                continue;
            resolve_pixel(f, x, y, sx, sy, hist_rgb, hist_vis, out_rgb + 3 * i, &out_vis[i]);
        }
    memcpy(hist_rgb, out_rgb, sizeof(float) * 3 * (size_t)w * h);
    memcpy(hist_vis, out_vis, sizeof(float) * (size_t)w * h);
}
