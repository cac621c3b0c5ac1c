/* Cached cascades (cache=on): a cascade whose light view-projection (its
 * snapped window, the light) is the one its layer was rendered with is not
 * rendered again. With a still camera the first frame renders every active
 * cascade and the later ones none (cascades_cached = what frame 0 rendered,
 * no shadow draw), and the shadows are uncached PSSM's, frame by frame, per
 * cascade and layered, with depth and with moments; along a moving path the
 * figures are uncached PSSM's too. cache=on without stable=on, and SDSM's GPU
 * fits, are refused before anything renders; the parameter left at its
 * default leaves the canonical parameters (and so the run ids and series) as
 * they were. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "table.h"


SB_TEST_SCRATCH("sbcache")

static const char *const g_errors[] = {"err_rate", "err_false_shadow", "err_false_lit", "vis_mae"};

static void render(const char *scene, const char *path, const char *specs, int frames, const char *tag, sb_table *sum,
                   char *dir, size_t len) {
    char out[4200];
    snprintf(out, sizeof out, "%s/%s", g_tmp, tag);
    run_evaluated(scene, path, specs, frames, "160x90", out, sum, dir, len);
}


/* Runs 2k (cached) and 2k+1 (the same uncached): equal error figures frame by frame. */
static void same_shadows(const char *dir, const sb_table *sum, int pairs, bool still) {
    for (int k = 0; k < pairs; k++) {
        sb_table a, b;
        frames_table(dir, sum, 2 * k, &a);
        frames_table(dir, sum, 2 * k + 1, &b);
        const char *pa = sb_table_get(sum, 2 * k, "params"), *pb = sb_table_get(sum, 2 * k + 1, "params");
        assert_non_null(strstr(pa, "cache=on"));
        assert_null(strstr(pb, "cache="));   /* at its default: not in the canonical text */
        long cached = 0;
        for (int f = 0; f < a.nrows; f++) {
            for (size_t e = 0; e < sizeof g_errors / sizeof *g_errors; e++)
                if (strcmp(sb_table_get(&a, f, g_errors[e]), sb_table_get(&b, f, g_errors[e]))) {
                    print_message("%s frame %d: %s %s cached, %s not\n", pa, f, g_errors[e],
                                  sb_table_get(&a, f, g_errors[e]), sb_table_get(&b, f, g_errors[e]));
                    fail();
                }
            assert_int_equal(table_int(&b, f, "cascades_cached"), 0);
            cached += table_int(&a, f, "cascades_cached");
            /* every active cascade is rendered or kept */
            assert_int_equal(table_int(&a, f, "cascades_rendered") + table_int(&a, f, "cascades_cached"),
                             table_int(&b, f, "cascades_rendered"));
            if (!still) continue;
            if (f == 0) {
                assert_true(table_int(&a, 0, "cascades_rendered") > 0);
                assert_int_equal(table_int(&a, 0, "cascades_cached"), 0);
            } else {
                assert_int_equal(table_int(&a, f, "cascades_rendered"), 0);
                assert_int_equal(table_int(&a, f, "cascades_cached"), table_int(&a, 0, "cascades_rendered"));
                assert_int_equal(table_int(&a, f, "shadow_draw_calls"), 0);
            }
        }
        print_message("%-70.70s: %ld cascades kept over %d frames\n", pa, cached, a.nrows);
        sb_table_free(&a);
        sb_table_free(&b);
    }
}

static void test_still_camera(void **st) {
    (void)st;
    sb_table sum;
    char dir[4096];
    render("plane-box", test_data("planebox-fixed.path"),
           "pssm:stable=on:cache=on pssm:stable=on pssm:stable=on:cache=on:layered=gs pssm:stable=on:layered=gs "
           "pssm:stable=on:cache=on:format=vsm pssm:stable=on:format=vsm",
           4, "still", &sum, dir, sizeof dir);
    assert_int_equal(sum.nrows, 6);
    same_shadows(dir, &sum, 3, true);
    sb_table_free(&sum);
}

static void test_moving_camera(void **st) {
    (void)st;
    sb_table sum;
    char dir[4096];
    render("towers", "towers", "pssm:stable=on:cache=on:res=512 pssm:stable=on:res=512", 8, "moving", &sum, dir,
           sizeof dir);
    same_shadows(dir, &sum, 1, false);
    sb_table_free(&sum);
}

static void test_refused(void **st) {
    (void)st;
    expect_cli_exit(2, "cache=on needs stable=on", "%s run towers towers pssm:cache=on --frames 2 --out %s/r",
                    test_binary(), g_tmp);
    expect_cli_exit(2, "cache=on needs splits=cpu", "%s run towers towers sdsm:stable=on:cache=on:splits=gpu --frames 2 "
                    "--out %s/r", test_binary(), g_tmp);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_still_camera),
        cmocka_unit_test(test_moving_camera),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests_name("cache", tests, setup, teardown);
}
