/* LDR-FLIP against what the paper's equations give on inputs whose answer is known.
 *
 * - An image against itself: 0 at every pixel.
 * - The colour pipeline on uniform images (the filters, normalised, leave them as they are; no edges): green
 *   against blue is the metric's maximum, exactly 1; black against white follows from textbook CIELab values
 *   (L* 0 and 100: HyAB 100, to the power 0.7, mapped against green-blue's distance from their CIELab values).
 * - The feature pipeline on a step from black to white against a uniform image: at the two pixels beside the step
 *   the edge detector (a derivative kernel whose positive and negative weights each sum to 1) answers the step's
 *   height in the achromatic channel, 1, so the feature difference is (1 / sqrt 2)^0.5; beyond the kernels' reach
 *   it is 0 (to float rounding), and a step against itself is exactly 0.
 * - A shadow (a dark rectangle on a lit, textured floor) shifted by 1, 2 and 4 pixels: the mean grows with the
 *   shift, and the error sits where the shadow's edges moved.
 * - The viewing condition: 0.7 m from a 0.7 m wide 3840-pixel display is 67.02 pixels per degree. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "flip.h"

static float *uniform(int w, int h, float r, float g, float b) {
    float *img = malloc(sizeof(float) * 3 * (size_t)w * h);
    for (int i = 0; i < w * h; i++) img[3 * i] = r, img[3 * i + 1] = g, img[3 * i + 2] = b;
    return img;
}

/* A lit floor with a texture (sRGB) and, if sw > 0, a shadow rectangle [sx, sx + sw) x [sy, sy + sh). */
static float *floor_with_shadow(int w, int h, int sx, int sy, int sw, int sh) {
    float *img = malloc(sizeof(float) * 3 * (size_t)w * h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float tex = 0.75f + 0.1f * (float)(((x / 4) + (y / 4)) % 2);   /* a checker of 4-pixel tiles */
            bool shadow = sw > 0 && x >= sx && x < sx + sw && y >= sy && y < sy + sh;
            float lin = sb_srgb_decode(tex) * (shadow ? 0.3f : 1.0f);
            float *p = img + 3 * ((size_t)y * w + x);
            p[0] = sb_srgb_encode(lin), p[1] = sb_srgb_encode(lin * 0.95f), p[2] = sb_srgb_encode(lin * 0.85f);
        }
    return img;
}

static void test_identical_is_zero(void **st) {
    (void)st;
    int w = 96, h = 64;
    float *a = floor_with_shadow(w, h, 30, 20, 25, 18), *map = malloc(sizeof(float) * w * h);
    sb_flip_stats s = sb_flip(a, a, w, h, 0, map);
    for (int i = 0; i < w * h; i++) assert_true(map[i] == 0);
    assert_true(s.mean == 0 && s.p95 == 0 && s.max == 0);
    free(a);
    free(map);
}

/* The colour metric's remapping of a HyAB distance d against the green-blue distance gb (both before ^0.7). */
static double remap(double d, double gb) {
    double c = pow(d, 0.7), cmax = pow(gb, 0.7), knee = 0.4 * cmax;
    return c < knee ? c * 0.95 / knee : 0.95 + (c - knee) / (cmax - knee) * 0.05;
}

static void test_color_pipeline(void **st) {
    (void)st;
    int w = 40, h = 30;
    float *green = uniform(w, h, 0, 1, 0), *blue = uniform(w, h, 0, 0, 1), *map = malloc(sizeof(float) * w * h);
    sb_flip_stats s = sb_flip(green, blue, w, h, 0, map);
    print_message("green against blue: mean %.7f, max %.7f\n", s.mean, s.max);
    for (int i = 0; i < w * h; i++) assert_true(fabs(map[i] - 1) < 1e-5);
    /* textbook CIELab (D65) of sRGB green and blue, Hunt-adjusted (chroma x L / 100) */
    const double g[3] = {87.7347, -86.1827, 83.1793}, b[3] = {32.3026, 79.1967, -107.8637};
    double ga = g[1] * g[0] / 100, gb_ = g[2] * g[0] / 100, ba = b[1] * b[0] / 100, bb = b[2] * b[0] / 100;
    double gb = fabs(g[0] - b[0]) + sqrt((ga - ba) * (ga - ba) + (gb_ - bb) * (gb_ - bb));
    float *black = uniform(w, h, 0, 0, 0), *white = uniform(w, h, 1, 1, 1);
    s = sb_flip(black, white, w, h, 0, map);
    double want = remap(100, gb);
    print_message("black against white: %.6f, from the paper's equations %.6f\n", s.mean, want);
    assert_true(fabs(s.mean - want) < 1e-3);
    assert_true(fabs(s.max - s.mean) < 1e-6);   /* uniform */
    /* a mid grey against a slightly lighter one: below the knee, linear in the distance^0.7 */
    float *g1 = uniform(w, h, 0.5f, 0.5f, 0.5f), *g2 = uniform(w, h, 0.52f, 0.52f, 0.52f);
    double L1 = 116 * cbrt(sb_srgb_decode(0.5f)) - 16, L2 = 116 * cbrt(sb_srgb_decode(0.52f)) - 16;
    s = sb_flip(g1, g2, w, h, 0, NULL);
    print_message("grey 0.50 against 0.52: %.6f, from the equations %.6f\n", s.mean, remap(fabs(L2 - L1), gb));
    assert_true(fabs(s.mean - remap(fabs(L2 - L1), gb)) < 1e-4);
    free(green), free(blue), free(black), free(white), free(g1), free(g2), free(map);
}

static void test_feature_pipeline(void **st) {
    (void)st;
    int w = 80, h = 20, edge = 40;
    float *step = malloc(sizeof(float) * 3 * (size_t)w * h), *flat = uniform(w, h, 0.5f, 0.5f, 0.5f);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++) step[3 * (y * w + x) + c] = x < edge ? 0.0f : 1.0f;
    float *f = malloc(sizeof(float) * w * h);
    sb_flip_features(step, flat, w, h, 0, f);
    double want = pow(1 / sqrt(2.0), 0.5);
    print_message("beside the step: %.6f and %.6f (the equations: %.6f); far from it %.6f\n", f[10 * w + edge - 1],
                  f[10 * w + edge], want, f[10 * w + 5]);
    for (int y = 0; y < h; y++) {
        assert_true(fabs(f[y * w + edge - 1] - want) < 1e-4);
        assert_true(fabs(f[y * w + edge] - want) < 1e-4);
        /* sigma = 0.5 * 0.082 * 67.02 = 2.75 pixels, radius 9: nothing 10 or more pixels away */
        for (int x = 0; x < w; x++)   /* the kernels' weights cancel to float rounding there */
            if (abs(x - edge) > 10) assert_true(f[y * w + x] < 1e-3);
    }
    /* the same step against itself: no feature difference anywhere */
    sb_flip_features(step, step, w, h, 0, f);
    for (int i = 0; i < w * h; i++) assert_true(f[i] == 0);
    free(step), free(flat), free(f);
}

static void test_grows_with_shadow_shift(void **st) {
    (void)st;
    int w = 128, h = 96;
    float *ref = floor_with_shadow(w, h, 40, 30, 40, 30), *map = malloc(sizeof(float) * w * h);
    double last = 0;
    const int shifts[] = {1, 2, 4};
    for (int k = 0; k < 3; k++) {
        float *test = floor_with_shadow(w, h, 40 + shifts[k], 30, 40, 30);
        sb_flip_stats s = sb_flip(ref, test, w, h, 0, map);
        print_message("shadow shifted %d px: mean %.5f, p95 %.5f\n", shifts[k], s.mean, s.p95);
        assert_true(s.mean > last);
        last = s.mean;
        /* the error is where the edges moved: at the left edge's new columns, not in the shadow's middle */
        assert_true(map[45 * w + 40] > 0.1);
        assert_true(map[45 * w + 60] < 0.05);
        free(test);
    }
    free(ref);
    free(map);
}

static void test_viewing_condition(void **st) {
    (void)st;
    assert_true(fabs(sb_flip_ppd(0.7, 3840, 0.7) - 67.0206) < 1e-3);
    assert_true(fabs(sb_flip_ppd(0.7, 3840, 0.7) - SB_FLIP_PPD_DEFAULT) < 1e-3);
    /* more pixels per degree: the eye's contrast filter spans more pixels, so the colour difference of a 2-pixel
       shift is blurred further (the feature detectors widen too, and their share can go either way) */
    int w = 128, h = 96;
    float *ref = floor_with_shadow(w, h, 40, 30, 40, 30), *test = floor_with_shadow(w, h, 42, 30, 40, 30);
    float *c30 = malloc(sizeof(float) * w * h), *c120 = malloc(sizeof(float) * w * h);
    sb_flip_color(ref, test, w, h, 30, c30);
    sb_flip_color(ref, test, w, h, 120, c120);
    double m30 = 0, m120 = 0, top30 = 0, top120 = 0;
    for (int i = 0; i < w * h; i++) m30 += c30[i], m120 += c120[i], top30 = fmax(top30, c30[i]), top120 = fmax(top120, c120[i]);
    print_message("colour difference of a 2-px shift: at 30 ppd mean %.5f max %.5f, at 120 ppd mean %.5f max %.5f\n",
                  m30 / (w * h), top30, m120 / (w * h), top120);
    assert_true(top30 > top120);
    /* ppd 0 is the default viewing condition */
    assert_true(sb_flip(ref, test, w, h, 0, NULL).mean == sb_flip(ref, test, w, h, SB_FLIP_PPD_DEFAULT, NULL).mean);
    free(c30), free(c120), free(ref), free(test);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_identical_is_zero), cmocka_unit_test(test_color_pipeline),
                                       cmocka_unit_test(test_feature_pipeline),
                                       cmocka_unit_test(test_grows_with_shadow_shift),
                                       cmocka_unit_test(test_viewing_condition)};
    return cmocka_run_group_tests_name("flip", tests, NULL, NULL);
}
