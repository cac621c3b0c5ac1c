/* `shadowbench flip A B` on a real render: the colour frame of a plane-box run (--images) against itself and
 * against itself moved sideways by 1, 2 and 4 pixels.
 *
 * - A frame against itself: mean, p95 and max 0.
 * - Moved by 1, 2 and 4 pixels: the mean grows with the move, and each printed figure is the one sb_flip gives
 *   on the same two files read in this process (the command reads, checks and scores, nothing else).
 * - --map writes the per-pixel error at the frame's size, its brightest pixel the largest error.
 * - Two sizes, a file that is not there, a value outside [0, 1] (an EXR), a missing argument: one line, exit 2.
 *
 * --flip on plane-box (the box under a sun 50 degrees up):
 * - the reference's shaded frame is base colour x (0.3 + 0.7 N.L x visibility): on the floor (N up, the same base
 *   colour everywhere) a lit pixel over a shadowed one is (0.3 + 0.7 sin 50 deg) / 0.3 in linear light, per channel;
 * - raycast's shaded frame is the reference's, pixel for pixel, and its flip_mean exactly 0; a 128-texel map's is
 *   above a 2048-texel one's, which is above 0;
 * - without --flip the runs keep their ids and every figure, and the FLIP columns are empty;
 * - tune --max-flip: the cheapest map whose flip_mean stays within the bound (a 128-texel map's is above it, a
 *   1024-texel one's below), and nothing for a bound none can meet. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flip.h"
#include "image.h"
#include "support.h"
#include "table.h"

SB_TEST_SCRATCH("sbflip")

static char g_color[512];

/* Writes top-down RGB floats in [0, 1] as an 8-bit PNG (sb_image_write_u8 takes rows bottom-up). */
static void write_png(const char *path, const float *rgb, int w, int h) {
    unsigned char *px = malloc(3 * (size_t)w * h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < 3 * w; x++) px[(size_t)(h - 1 - y) * 3 * w + x] = (unsigned char)lroundf(255 * rgb[(size_t)y * 3 * w + x]);
    sb_err err;
    assert_true(sb_image_write_u8(path, w, h, 3, px, &err));
    free(px);
}

static double printed(const char *out, const char *what) {
    const char *p = strstr(out, what);
    assert_non_null(p);
    return atof(p + strlen(what));
}

static int render_frame(void **st) {
    (void)st;
    if (setup(st)) return -1;
    if (!sb_images_available()) return 0;   /* each test says why it skips */
    char out[8192];
    int rc = run_logged(out, sizeof out,
                        "%s run plane-box plane-box sm:res=512 --frames 1 --warmup 0 --size 160x90 --error-every 1 "
                        "--images 1 --quiet --out %s/r && ls %s/r/*/images/*_color.png",
                        test_binary(), g_tmp, g_tmp);
    if (rc != 0) return -1;
    snprintf(g_color, sizeof g_color, "%s", last_line_of(out));
    return 0;
}

static void test_against_itself_and_moved(void **st) {
    (void)st;
    if (!sb_images_available()) {
        print_message("skipped: %s\n", sb_images_unavailable_reason());
        skip();
    }
    sb_err err;
    int w, h;
    float *rgb;
    assert_true(sb_image_read_rgb(g_color, &w, &h, &rgb, &err));
    assert_int_equal(w, 160);
    assert_int_equal(h, 90);
    char out[4096], map[600];
    snprintf(map, sizeof map, "%s/self_map.png", g_tmp);
    assert_int_equal(run_logged(out, sizeof out, "%s flip %s %s --map %s", test_binary(), g_color, g_color, map), 0);
    assert_true(printed(out, "mean ") == 0 && printed(out, "p95 ") == 0 && printed(out, "max ") == 0);
    double last = 0;
    const int moves[] = {1, 2, 4};
    for (int k = 0; k < 3; k++) {
        float *moved = malloc(sizeof(float) * 3 * (size_t)w * h);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                for (int c = 0; c < 3; c++) {
                    int from = x - moves[k] < 0 ? 0 : x - moves[k];
                    moved[3 * ((size_t)y * w + x) + c] = rgb[3 * ((size_t)y * w + from) + c];
                }
        char path[600];
        snprintf(path, sizeof path, "%s/moved%d.png", g_tmp, moves[k]);
        write_png(path, moved, w, h);
        snprintf(map, sizeof map, "%s/map%d.png", g_tmp, moves[k]);
        assert_int_equal(run_logged(out, sizeof out, "%s flip %s %s --map %s", test_binary(), g_color, path, map), 0);
        double mean = printed(out, "mean "), p95 = printed(out, "p95 "), max = printed(out, "max ");
        /* the same two files, read and scored here */
        int w2, h2;
        float *a, *b, *mine = malloc(sizeof(float) * (size_t)w * h);
        assert_true(sb_image_read_rgb(g_color, &w2, &h2, &a, &err));
        assert_true(sb_image_read_rgb(path, &w2, &h2, &b, &err));
        sb_flip_stats s = sb_flip(a, b, w, h, 0, mine);
        print_message("moved %d px: mean %.6f p95 %.6f max %.6f (here: %.6f %.6f %.6f)\n", moves[k], mean, p95, max,
                      s.mean, s.p95, s.max);
        assert_true(fabs(mean - s.mean) < 1e-6 && fabs(p95 - s.p95) < 1e-6 && fabs(max - s.max) < 1e-6);
        assert_true(mean > last);
        last = mean;
        /* the map: the frame's size, its brightest pixel the largest error */
        float *m;
        int mw, mh;
        assert_true(sb_image_read_rgb(map, &mw, &mh, &m, &err));
        assert_int_equal(mw, w);
        assert_int_equal(mh, h);
        float top = 0;
        for (int i = 0; i < mw * mh; i++) top = fmaxf(top, m[3 * i]);
        assert_true(fabs(top - lroundf(255 * (float)s.max) / 255.0) < 1e-6);
        /* and where it is: the map's pixels are the error's, row for row */
        int at = 0;
        for (int i = 0; i < w * h; i++)
            if (mine[i] > mine[at]) at = i;
        assert_true(fabs(m[3 * at] - top) < 1e-6);
        free(m), free(a), free(b), free(mine), free(moved);
    }
    assert_true(last > 0.001);
    free(rgb);
}

static void test_bad_input(void **st) {
    (void)st;
    if (!sb_images_available()) {
        print_message("skipped: %s\n", sb_images_unavailable_reason());
        skip();
    }
    char small[600], exr[600];
    snprintf(small, sizeof small, "%s/small.png", g_tmp);
    float *px = calloc(3 * 80 * 45, sizeof(float));
    write_png(small, px, 80, 45);
    expect_cli_fail("FLIP compares images of one size", "%s flip %s %s", test_binary(), g_color, small);
    expect_cli_fail("nothing-here.png", "%s flip %s %s/nothing-here.png", test_binary(), g_color, g_tmp);
    /* an EXR holding 1.5: not a displayed image */
    snprintf(exr, sizeof exr, "%s/bright.exr", g_tmp);
    float *f = calloc(3 * 160 * 90, sizeof(float));
    f[3 * 100 + 1] = 1.5f;
    sb_err err;
    assert_true(sb_image_write_f32(exr, 160, 90, 3, f, &err));
    expect_cli_fail("holds 1.5: LDR-FLIP compares displayed images", "%s flip %s %s", test_binary(), g_color, exr);
    expect_cli_fail("usage: shadowbench flip", "%s flip %s", test_binary(), g_color);
    free(px);
    free(f);
}

static double cell(const sb_table *t, int r, const char *col) {
    const char *v = sb_table_get(t, r, col);
    return v && *v ? atof(v) : NAN;
}

static void image_of(const char *dir, const char *run_id, const char *kind, float **rgb) {
    char path[1024];
    int w, h;
    sb_err err;
    snprintf(path, sizeof path, "%s/images/%s_f0000_%s.png", dir, run_id, kind);
    assert_true(sb_image_read_rgb(path, &w, &h, rgb, &err));
    assert_int_equal(w, 160);
    assert_int_equal(h, 90);
}

static void test_shaded_frames(void **st) {
    (void)st;
    if (!sb_images_available()) {
        print_message("skipped: %s\n", sb_images_unavailable_reason());
        skip();
    }
    char out[8192], dir[512];
    const char *specs = "raycast sm:res=128 sm:res=2048";
    const char *opts = "--frames 1 --warmup 0 --size 160x90 --error-every 1 --quiet";
    int rc = run_logged(out, sizeof out, "%s run plane-box plane-box %s %s --flip --images 1 --out %s/flip",
                        test_binary(), specs, opts, g_tmp);
    assert_int_equal(rc, 0);
    snprintf(dir, sizeof dir, "%s", last_line_of(out));
    rc = run_logged(out, sizeof out, "%s run plane-box plane-box %s %s --out %s/plain", test_binary(), specs, opts, g_tmp);
    assert_int_equal(rc, 0);
    sb_table with, without;
    summary_table(dir, &with);
    summary_table(last_line_of(out), &without);
    assert_int_equal(with.nrows, 3);
    for (int r = 0; r < 3; r++) {
        assert_string_equal(sb_table_get(&with, r, "run_id"), sb_table_get(&without, r, "run_id"));
        assert_string_equal(sb_table_get(&with, r, "err_rate_mean"), sb_table_get(&without, r, "err_rate_mean"));
        assert_true(isnan(cell(&without, r, "flip_mean_mean")));
    }
    double ray = cell(&with, 0, "flip_mean_mean"), coarse = cell(&with, 1, "flip_mean_mean"),
           fine = cell(&with, 2, "flip_mean_mean");
    print_message("flip_mean: raycast %g, sm 128 %g, sm 2048 %g (err_rate %g, %g, %g)\n", ray, coarse, fine,
                  cell(&with, 0, "err_rate_mean"), cell(&with, 1, "err_rate_mean"), cell(&with, 2, "err_rate_mean"));
    assert_true(ray == 0);
    assert_true(coarse > fine && fine > 0);
    /* the reference's shaded frame by hand: the floor lit and in the box's shadow */
    const char *id = sb_table_get(&with, 0, "run_id");
    float *ref, *shaded_ref, *shaded;
    image_of(dir, id, "ref", &ref);
    image_of(dir, id, "shaded_ref", &shaded_ref);
    image_of(dir, id, "shaded", &shaded);
    for (int i = 0; i < 3 * 160 * 90; i++) assert_true(shaded[i] == shaded_ref[i]);   /* raycast: exact */
    int lit = 89 * 160 + 2, dark = -1;   /* the bottom row is floor near the camera, in the sun */
    for (int i = 0; i < 160 * 90 && dark < 0; i++)
        if (ref[3 * i] == 0) dark = i;   /* black in ref.png: shadowed, and only the floor is */
    assert_true(ref[3 * lit] == 1 && dark >= 0);
    double want = (0.3 + 0.7 * sin(50 * 3.14159265358979 / 180)) / 0.3;
    for (int c = 0; c < 3; c++) {
        double l = sb_srgb_decode(shaded_ref[3 * lit + c]), d = sb_srgb_decode(shaded_ref[3 * dark + c]);
        print_message("channel %d: lit %.4f, shadowed %.4f, ratio %.4f (by hand %.4f)\n", c, l, d, l / d, want);
        assert_true(fabs(l / d - want) < 0.03 * want);
    }
    free(ref), free(shaded_ref), free(shaded);
    /* the map is there too */
    float *map;
    image_of(dir, sb_table_get(&with, 1, "run_id"), "flip", &map);
    free(map);
    sb_table_free(&with);
    sb_table_free(&without);
}

static void test_tune_max_flip(void **st) {
    (void)st;
    if (!sb_images_available()) skip();   /* not needed for FLIP itself, but the runs above set the scene */
    char out[16384];
    int rc = run_logged(out, sizeof out, "%s tune plane-box plane-box 'sm:res=128,1024' --max-err 0.05 --max-flip 0.0004 "
                        "--frames 3 --size 160x90 --quiet --out %s/tune", test_binary(), g_tmp);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "flip_mean at most 0.0004"));
    const char *rec = strstr(out, "recommended: ");
    assert_non_null(rec);
    char line[256];
    snprintf(line, sizeof line, "%.*s", (int)strcspn(rec, "\n"), rec);
    print_message("%s\n", line);
    assert_non_null(strstr(line, "res=1024"));
    rc = run_logged(out, sizeof out, "%s tune plane-box plane-box 'sm:res=128' --max-err 0.05 --max-flip 0.000000001 "
                    "--frames 3 --size 160x90 --quiet --out %s/tune", test_binary(), g_tmp);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(out, "nothing met the bound"));
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_against_itself_and_moved), cmocka_unit_test(test_bad_input),
                                       cmocka_unit_test(test_shaded_frames), cmocka_unit_test(test_tune_max_flip)};
    return cmocka_run_group_tests_name("perceptual", tests, render_frame, teardown);
}
