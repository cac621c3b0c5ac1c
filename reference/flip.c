/* flip.c - LDR-FLIP (see flip.h). */
#include "flip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stats.h"
#include "util.h"

#define PI 3.14159265358979323846

/* The paper's constants: the colour metric's exponent qc, the knee pc and the share pt of [0, 1] below it; the
 * feature detectors' width w (degrees) and exponent qf. */
static const double QC = 0.7, PC = 0.4, PT = 0.95, W_FEATURE = 0.082, QF = 0.5;
/* The contrast sensitivity of the achromatic, red-green and blue-yellow channels as sums of Gaussians:
 * a1 sqrt(pi/b1) exp(-pi^2 x^2/b1) + a2 sqrt(pi/b2) exp(-pi^2 x^2/b2), x in degrees. */
static const double CSF_A1[3] = {1, 1, 34.1}, CSF_B1[3] = {0.0047, 0.0053, 0.04};
static const double CSF_A2[3] = {0, 0, 13.5}, CSF_B2[3] = {1e-5, 1e-5, 0.025};

double sb_flip_ppd(double distance_m, double pixels, double width_m) { return distance_m * (pixels / width_m) * PI / 180; }

float sb_srgb_decode(float c) { return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f); }
float sb_srgb_encode(float c) { return c <= 0.0031308f ? c * 12.92f : 1.055f * powf(c, 1 / 2.4f) - 0.055f; }

/* ---- colour spaces: linear sRGB, XYZ (D65), YCxCz, CIELab ---- */

typedef struct spaces {
    double rgb2xyz[3][3], xyz2rgb[3][3];
    double white[3];   /* D65's XYZ, Y = 1: what linear RGB (1, 1, 1) is */
} spaces;

static void invert3(const double m[3][3], double out[3][3]) {
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
            out[r][c] = (m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]) / det;
        }
}

/* The sRGB primaries and D65 white point (IEC 61966-2-1) to the RGB -> XYZ matrix: each primary's XYZ at unit
 * luminance, scaled so that RGB (1, 1, 1) is the white. */
static void spaces_init(spaces *s) {
    const double xy[4][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}, {0.3127, 0.3290}};
    double p[3][3], pi[3][3];
    for (int k = 0; k < 3; k++) {
        p[0][k] = xy[k][0] / xy[k][1];
        p[1][k] = 1;
        p[2][k] = (1 - xy[k][0] - xy[k][1]) / xy[k][1];
    }
    s->white[0] = xy[3][0] / xy[3][1], s->white[1] = 1, s->white[2] = (1 - xy[3][0] - xy[3][1]) / xy[3][1];
    invert3(p, pi);
    for (int k = 0; k < 3; k++) {
        double scale = pi[k][0] * s->white[0] + pi[k][1] * s->white[1] + pi[k][2] * s->white[2];
        for (int r = 0; r < 3; r++) s->rgb2xyz[r][k] = p[r][k] * scale;
    }
    invert3(s->rgb2xyz, s->xyz2rgb);
}

static void mul3(const double m[3][3], const double v[3], double out[3]) {
    for (int r = 0; r < 3; r++) out[r] = m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2];
}

/* sRGB-encoded to YCxCz: the white-relative XYZ, linear in light (Y: 116 y - 16, as L* without the cube root). */
static void srgb_to_ycxcz(const spaces *s, const float *in, float *out) {
    double lin[3] = {sb_srgb_decode(in[0]), sb_srgb_decode(in[1]), sb_srgb_decode(in[2])}, xyz[3];
    mul3(s->rgb2xyz, lin, xyz);
    double x = xyz[0] / s->white[0], y = xyz[1] / s->white[1], z = xyz[2] / s->white[2];
    out[0] = (float)(116 * y - 16), out[1] = (float)(500 * (x - y)), out[2] = (float)(200 * (y - z));
}

static double lab_f(double t) {
    const double d = 6.0 / 29;
    return t > d * d * d ? cbrt(t) : t / (3 * d * d) + 4.0 / 29;
}

/* Linear RGB to CIELab with the Hunt adjustment (chroma scaled by L/100: dark colours differ less). */
static void rgb_to_hunt_lab(const spaces *s, const double rgb[3], double out[3]) {
    double xyz[3];
    mul3(s->rgb2xyz, rgb, xyz);
    double fx = lab_f(xyz[0] / s->white[0]), fy = lab_f(xyz[1] / s->white[1]), fz = lab_f(xyz[2] / s->white[2]);
    double L = 116 * fy - 16;
    out[0] = L, out[1] = 0.01 * L * 500 * (fx - fy), out[2] = 0.01 * L * 200 * (fy - fz);
}

/* YCxCz (filtered) back to linear RGB clamped to [0, 1], then Hunt-adjusted Lab. */
static void ycxcz_to_hunt_lab(const spaces *s, const double ycc[3], double out[3]) {
    double y = (ycc[0] + 16) / 116, xyz[3] = {(y + ycc[1] / 500) * s->white[0], y * s->white[1],
                                              (y - ycc[2] / 200) * s->white[2]}, rgb[3];
    mul3(s->xyz2rgb, xyz, rgb);
    for (int k = 0; k < 3; k++) rgb[k] = rgb[k] < 0 ? 0 : rgb[k] > 1 ? 1 : rgb[k];
    rgb_to_hunt_lab(s, rgb, out);
}

/* HyAB: city-block in lightness, Euclidean in the chroma plane. */
static double hyab(const double a[3], const double b[3]) {
    return fabs(a[0] - b[0]) + sqrt((a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* ---- separable filters (correlation, borders clamped) ---- */

typedef struct kernel {
    int radius;
    double *w;   /* 2 * radius + 1 */
} kernel;

static kernel kernel_new(int radius) {
    return (kernel){radius, sb_xcalloc((size_t)(2 * radius + 1), sizeof(double))};
}

/* The colour filters at ppd: the achromatic and red-green channels one Gaussian each (1D sums of 1), the
 * blue-yellow channel two, each split into equal 1D factors (sqrt of its 2D weight), scaled together so that
 * their 2D kernel sums to 1. */
static void color_kernels(double ppd, kernel k[4]) {
    double bmax = 0;
    for (int c = 0; c < 3; c++) bmax = fmax(bmax, fmax(CSF_B1[c], CSF_B2[c]));
    int r = (int)ceil(3 * sqrt(bmax / (2 * PI * PI)) * ppd);
    for (int i = 0; i < 4; i++) k[i] = kernel_new(r);
    double sum[4] = {0};
    for (int i = -r; i <= r; i++) {
        double x2 = (i / ppd) * (i / ppd);
        for (int c = 0; c < 2; c++) {
            k[c].w[i + r] = CSF_A1[c] * sqrt(PI / CSF_B1[c]) * exp(-PI * PI * x2 / CSF_B1[c]);
            sum[c] += k[c].w[i + r];
        }
        k[2].w[i + r] = sqrt(CSF_A1[2] * sqrt(PI / CSF_B1[2])) * exp(-PI * PI * x2 / CSF_B1[2]);
        k[3].w[i + r] = sqrt(CSF_A2[2] * sqrt(PI / CSF_B2[2])) * exp(-PI * PI * x2 / CSF_B2[2]);
        sum[2] += k[2].w[i + r], sum[3] += k[3].w[i + r];
    }
    double by = sqrt(sum[2] * sum[2] + sum[3] * sum[3]);
    for (int i = 0; i <= 2 * r; i++) k[0].w[i] /= sum[0], k[1].w[i] /= sum[1], k[2].w[i] /= by, k[3].w[i] /= by;
}

/* The feature detectors at ppd: a Gaussian of sigma 0.5 w ppd pixels (sums to 1), its first and second
 * derivatives (positive weights sum to 1, negative ones to -1). */
static void feature_kernels(double ppd, kernel k[3]) {
    double sigma = 0.5 * W_FEATURE * ppd;
    int r = (int)ceil(3 * sigma);
    for (int i = 0; i < 3; i++) k[i] = kernel_new(r);
    double g = 0, pos[2] = {0}, neg[2] = {0};
    for (int i = -r; i <= r; i++) {
        double e = exp(-(double)i * i / (2 * sigma * sigma)), d1 = -i * e, d2 = ((double)i * i / (sigma * sigma) - 1) * e;
        k[0].w[i + r] = e, k[1].w[i + r] = d1, k[2].w[i + r] = d2;
        g += e;
        if (d1 > 0) pos[0] += d1;
        else neg[0] -= d1;
        if (d2 > 0) pos[1] += d2;
        else neg[1] -= d2;
    }
    for (int i = 0; i <= 2 * r; i++) {
        k[0].w[i] /= g;
        for (int d = 0; d < 2; d++) {
            double *v = &k[1 + d].w[i];
            *v /= *v > 0 ? pos[d] : neg[d];
        }
    }
}

static void kernels_free(kernel *k, int n) {
    for (int i = 0; i < n; i++) free(k[i].w);
}

static inline int clampi(int v, int lo, int hi) { return v < lo ? lo : v > hi ? hi : v; }

/* One image's colour: its YCxCz (3 a pixel) filtered by the colour kernels, to Hunt-adjusted Lab (3 a pixel). */
static void filtered_lab(const spaces *s, const float *ycc, int w, int h, const kernel k[4], double *lab) {
    const int r = k[0].radius;
    float *mid = sb_xmalloc(sizeof(float) * 4 * (size_t)w * h);   /* along x: Y, Cx, and Cz by both Gaussians */
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double a[4] = {0};
            for (int i = -r; i <= r; i++) {
                const float *p = ycc + 3 * ((size_t)y * w + clampi(x + i, 0, w - 1));
                a[0] += k[0].w[i + r] * p[0], a[1] += k[1].w[i + r] * p[1];
                a[2] += k[2].w[i + r] * p[2], a[3] += k[3].w[i + r] * p[2];
            }
            float *o = mid + 4 * ((size_t)y * w + x);
            for (int c = 0; c < 4; c++) o[c] = (float)a[c];
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double a[4] = {0};
            for (int i = -r; i <= r; i++) {
                const float *p = mid + 4 * ((size_t)clampi(y + i, 0, h - 1) * w + x);
                for (int c = 0; c < 4; c++) a[c] += k[c].w[i + r] * p[c];
            }
            double ycc_f[3] = {a[0], a[1], a[2] + a[3]};
            ycxcz_to_hunt_lab(s, ycc_f, lab + 3 * ((size_t)y * w + x));
        }
    free(mid);
}

/* One image's edge and point strength (2 a pixel) on its achromatic channel, y = (Y + 16) / 116 in [0, 1]. */
static void features(const float *ycc, int w, int h, const kernel k[3], float *ep) {
    const int r = k[0].radius;
    float *mid = sb_xmalloc(sizeof(float) * 3 * (size_t)w * h);   /* along x: d/dx, d2/dx2, Gaussian */
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double a[3] = {0};
            for (int i = -r; i <= r; i++) {
                double v = (ycc[3 * ((size_t)y * w + clampi(x + i, 0, w - 1))] + 16) / 116;
                a[0] += k[1].w[i + r] * v, a[1] += k[2].w[i + r] * v, a[2] += k[0].w[i + r] * v;
            }
            float *o = mid + 3 * ((size_t)y * w + x);
            o[0] = (float)a[0], o[1] = (float)a[1], o[2] = (float)a[2];
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double dx = 0, ddx = 0, dy = 0, ddy = 0;
            for (int i = -r; i <= r; i++) {
                const float *p = mid + 3 * ((size_t)clampi(y + i, 0, h - 1) * w + x);
                dx += k[0].w[i + r] * p[0], ddx += k[0].w[i + r] * p[1];
                dy += k[1].w[i + r] * p[2], ddy += k[2].w[i + r] * p[2];
            }
            float *o = ep + 2 * ((size_t)y * w + x);
            o[0] = (float)sqrt(dx * dx + dy * dy), o[1] = (float)sqrt(ddx * ddx + ddy * ddy);
        }
    free(mid);
}

static float *to_ycxcz(const spaces *s, const float *img, int w, int h) {
    float *out = sb_xmalloc(sizeof(float) * 3 * (size_t)w * h);
    for (size_t i = 0; i < (size_t)w * h; i++) srgb_to_ycxcz(s, img + 3 * i, out + 3 * i);
    return out;
}

/* The colour difference of two images already in YCxCz. */
static void color_diff(const spaces *s, const float *ya, const float *yb, int w, int h, double ppd, float *out) {
    kernel k[4];
    color_kernels(ppd, k);
    size_t n = (size_t)w * h;
    double *la = sb_xmalloc(sizeof(double) * 3 * n), *lb = sb_xmalloc(sizeof(double) * 3 * n);
    filtered_lab(s, ya, w, h, k, la);
    filtered_lab(s, yb, w, h, k, lb);
    /* the largest difference there is: green against blue */
    double g[3], b[3];
    rgb_to_hunt_lab(s, (double[3]){0, 1, 0}, g);
    rgb_to_hunt_lab(s, (double[3]){0, 0, 1}, b);
    const double cmax = pow(hyab(g, b), QC), knee = PC * cmax;
    for (size_t i = 0; i < n; i++) {
        double d = pow(hyab(la + 3 * i, lb + 3 * i), QC);
        out[i] = (float)(d < knee ? d * PT / knee : PT + (d - knee) / (cmax - knee) * (1 - PT));
    }
    free(la);
    free(lb);
    kernels_free(k, 4);
}

/* The feature difference of two images already in YCxCz. */
static void feature_diff(const float *ya, const float *yb, int w, int h, double ppd, float *out) {
    kernel k[3];
    feature_kernels(ppd, k);
    size_t n = (size_t)w * h;
    float *ea = sb_xmalloc(sizeof(float) * 2 * n), *eb = sb_xmalloc(sizeof(float) * 2 * n);
    features(ya, w, h, k, ea);
    features(yb, w, h, k, eb);
    for (size_t i = 0; i < n; i++) {
        double d = fmax(fabs(ea[2 * i] - eb[2 * i]), fabs(ea[2 * i + 1] - eb[2 * i + 1]));
        out[i] = (float)pow(d / sqrt(2.0), QF);
    }
    free(ea);
    free(eb);
    kernels_free(k, 3);
}

/* Both images to YCxCz once, then the pipelines asked for (the public ones, and sb_flip both at once). */
typedef enum { PIPE_COLOR = 1, PIPE_FEATURES = 2 } pipes;

static void run_pipes(const float *ref, const float *test, int w, int h, double ppd, unsigned which, float *color,
                      float *feat) {
    if (ppd <= 0) ppd = SB_FLIP_PPD_DEFAULT;
    spaces s;
    spaces_init(&s);
    float *ya = to_ycxcz(&s, ref, w, h), *yb = to_ycxcz(&s, test, w, h);
    if (which & PIPE_COLOR) color_diff(&s, ya, yb, w, h, ppd, color);
    if (which & PIPE_FEATURES) feature_diff(ya, yb, w, h, ppd, feat);
    free(ya);
    free(yb);
}

void sb_flip_color(const float *ref, const float *test, int w, int h, double ppd, float *out) {
    run_pipes(ref, test, w, h, ppd, PIPE_COLOR, out, NULL);
}

void sb_flip_features(const float *ref, const float *test, int w, int h, double ppd, float *out) {
    run_pipes(ref, test, w, h, ppd, PIPE_FEATURES, NULL, out);
}

sb_flip_stats sb_flip(const float *ref, const float *test, int w, int h, double ppd, float *map) {
    size_t n = (size_t)w * h;
    float *c = sb_xmalloc(sizeof(float) * (n ? n : 1)), *f = sb_xmalloc(sizeof(float) * (n ? n : 1));
    run_pipes(ref, test, w, h, ppd, PIPE_COLOR | PIPE_FEATURES, c, f);
    double *e = sb_xmalloc(sizeof(double) * (n ? n : 1)), sum = 0, max = 0;
    for (size_t i = 0; i < n; i++) {
        e[i] = pow(c[i], 1 - f[i]);
        sum += e[i];
        max = fmax(max, e[i]);
        if (map) map[i] = (float)e[i];
    }
    sb_flip_stats st = {n ? sum / n : NAN, n ? sb_percentile_select(e, n, 0.95) : NAN, n ? max : NAN};
    free(e);
    free(c);
    free(f);
    return st;
}
