/* --submit direct|indirect on a tiled scene (towers 3 x 3 by node instancing,
 * 585 draws): the same frames rendered both ways give the same error figures,
 * triangles and draws frame by frame; direct issues one GL call a draw, and
 * indirect at most one a pass and layer (the z-pass, each shadow map or the
 * layered pass, the camera pass). */
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

static char g_out[65536];

SB_TEST_SCRATCH("sbsubmit")

static const char *const g_specs = "none sm:res=512 pssm:res=512 pssm:res=512:layered=gs pssm:res=512:layered=vs "
                                   "sdsm:res=512";
/* per frame, equal in both modes (as written: the same figures print the same) */
static const char *const g_same[] = {"triangles", "shadow_triangles", "draw_calls", "shadow_draw_calls",
                                     "cascades_rendered", "err_rate", "err_false_shadow", "err_false_lit",
                                     "vis_mae", "res_err_mean", "flicker_rate", "geom_mismatch"};

/* Renders the specs on the tiled scene with --submit mode; the results folder into dir. */
static void render(const char *scene, const char *mode, char *dir, size_t len) {
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run %s towers %s --frames 4 --size 160x90 --error-every 2 "
                                "--warmup 0 --quiet --submit %s --out %s/%s", test_binary(), scene, g_specs, mode,
                                g_tmp, mode), 0);
    snprintf(dir, len, "%s", last_line_of(g_out));
}


static void test_direct_and_indirect(void **st) {
    (void)st;
    char src[128], scene[128], cmd[8192], a_dir[4096], b_dir[4096];
    snprintf(src, sizeof src, "%s/towers.glb", g_tmp);
    snprintf(scene, sizeof scene, "%s/towers3.glb", g_tmp);
    copy_bundled("towers.glb", src);
    snprintf(cmd, sizeof cmd, "%s/scripts/tile-gltf %s %s 3 3 > /dev/null", getenv("SB_SOURCE_ROOT"), src, scene);
    assert_int_equal(system(cmd), 0);
    render(scene, "direct", a_dir, sizeof a_dir);
    render(scene, "indirect", b_dir, sizeof b_dir);
    sb_table A, B;
    summary_table(a_dir, &A);
    summary_table(b_dir, &B);
    assert_int_equal(A.nrows, 6);
    assert_int_equal(B.nrows, A.nrows);
    for (int r = 0; r < A.nrows; r++) {
        assert_string_equal(sb_table_get(&A, r, "status"), "ok");
        assert_string_equal(sb_table_get(&B, r, "status"), "ok");
        assert_string_equal(sb_table_get(&A, r, "submit"), "direct");
        assert_string_equal(sb_table_get(&B, r, "submit"), "indirect");
        assert_string_equal(sb_table_get(&A, r, "params"), sb_table_get(&B, r, "params"));
        assert_string_not_equal(sb_table_get(&A, r, "run_id"), sb_table_get(&B, r, "run_id"));
        const char *params = sb_table_get(&A, r, "params");
        bool per_cascade = strstr(params, "layered=off") != NULL;
        sb_table fa, fb;
        frames_table(a_dir, &A, r, &fa);
        frames_table(b_dir, &B, r, &fb);
        assert_int_equal(fa.nrows, 4);
        assert_int_equal(fb.nrows, fa.nrows);
        long draws = 0, calls = 0;
        for (int f = 0; f < fa.nrows; f++) {
            for (size_t k = 0; k < sizeof g_same / sizeof *g_same; k++)
                if (strcmp(sb_table_get(&fa, f, g_same[k]), sb_table_get(&fb, f, g_same[k]))) {
                    print_message("%s frame %d: %s %s direct, %s indirect\n", sb_table_get(&A, r, "technique"), f,
                                  g_same[k], sb_table_get(&fa, f, g_same[k]), sb_table_get(&fb, f, g_same[k]));
                    fail();
                }
            /* direct: a call a draw; indirect: a pass or layer a call (no alpha-tested or double-sided draws
               here, so one program and one culling state a pass) */
            assert_int_equal(table_int(&fa, f, "api_calls"), table_int(&fa, f, "draw_calls"));
            assert_int_equal(table_int(&fa, f, "shadow_api_calls"), table_int(&fa, f, "shadow_draw_calls"));
            bool maps = *sb_table_get(&fa, f, "cascades_rendered");
            long layers = !maps ? 0 : per_cascade ? table_int(&fb, f, "cascades_rendered") : 1;
            long zpass = *sb_table_get(&fb, f, "zpass_ms") ? 1 : 0;
            assert_true(table_int(&fb, f, "shadow_api_calls") <= layers);
            assert_true(table_int(&fb, f, "api_calls") <= zpass + layers + 1);
            draws += table_int(&fb, f, "draw_calls");
            calls += table_int(&fb, f, "api_calls");
        }
        print_message("%-10s %-40.40s: %ld draws in 4 frames, %ld GL calls indirect\n",
                      sb_table_get(&A, r, "technique"), params, draws, calls);
        assert_true(draws >= 10 * calls);   /* the tiled scene's hundreds of draws, a few calls */
        sb_table_free(&fa);
        sb_table_free(&fb);
    }
    sb_table_free(&A);
    sb_table_free(&B);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_direct_and_indirect),
    };
    return cmocka_run_group_tests_name("submit", tests, setup, teardown);
}
