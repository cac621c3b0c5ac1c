/* Virtual shadow maps (techniques/virtual.c) rendered for real on llvmpipe:
 *  - on towers and plane-box along their paths, `virtual` with a 64 MiB pool is less wrong than pssm with four
 *    2048² cascades, which hold 64 MiB;
 *  - a still camera draws its pages once: every later frame needs the same pages, keeps them all
 *    (pages_rendered 0, pages_cached = pages_needed, no shadow draw) and its visibility is the first frame's
 *    bit for bit, and cache=off's;
 *  - a moving camera draws fewer pages than it needs (the pages it still needs are kept);
 *  - a sun moved between frames draws every needed page again, and then none;
 *  - a pool of 1 MiB: the pool_overflow warning with its shortfall, a finite error, no GL error;
 *  - bad parameters are refused before anything renders, with the valid values. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eval.h"
#include "support.h"
#include "table.h"


SB_TEST_SCRATCH("sbvirtual")

static void render(const char *scene, const char *path, const char *specs, int frames, const char *size,
                   const char *tag, sb_table *sum, char *dir, size_t len) {
    char out[4200];
    snprintf(out, sizeof out, "%s/%s", g_tmp, tag);
    run_evaluated(scene, path, specs, frames, size, out, sum, dir, len);
}

static double num(const sb_table *t, int r, const char *col) { return atof(sb_table_get(t, r, col)); }

/* The mean err_rate of two runs on a scene's path: virtual's (pool=64) below pssm 4x2048's, at no more shadow_mb. */
static void test_less_wrong_than_pssm(void **st) {
    (void)st;
    const char *scenes[] = {"towers", "plane-box"};
    for (int i = 0; i < 2; i++) {
        sb_table sum;
        char dir[4096];
        render(scenes[i], scenes[i], "virtual:pool=64 pssm:cascades=4:res=2048", 6, "640x360", scenes[i], &sum, dir,
               sizeof dir);
        assert_int_equal(sum.nrows, 2);
        double ev = num(&sum, 0, "err_rate_mean"), ep = num(&sum, 1, "err_rate_mean");
        double mv = num(&sum, 0, "shadow_mb"), mp = num(&sum, 1, "shadow_mb");
        print_message("%s: err_rate virtual %.3g (%.2f MiB), pssm 4x2048 %.3g (%.2f MiB)\n", scenes[i], ev, mv, ep, mp);
        assert_string_equal(sb_table_get(&sum, 0, "status"), "ok");
        assert_string_equal(sb_table_get(&sum, 0, "warnings"), "");
        assert_true(ev < ep);
        assert_true(mv <= mp);
        sb_table_free(&sum);
    }
}

/* A still camera, cached and not: the cached run draws its pages at frame 0 only. */
static void test_still_camera_keeps_its_pages(void **st) {
    (void)st;
    sb_table sum, a, b;
    char dir[4096];
    render("plane-box", test_data("planebox-fixed.path"), "virtual virtual:cache=off", 4, "320x180", "still", &sum,
           dir, sizeof dir);
    frames_table(dir, &sum, 0, &a);
    frames_table(dir, &sum, 1, &b);
    long need0 = table_int(&a, 0, "pages_needed");
    assert_true(need0 > 0);
    assert_int_equal(table_int(&a, 0, "pages_rendered"), need0);
    for (int f = 1; f < a.nrows; f++) {
        assert_int_equal(table_int(&a, f, "pages_needed"), need0);
        assert_int_equal(table_int(&a, f, "pages_rendered"), 0);
        assert_int_equal(table_int(&a, f, "pages_cached"), need0);
        assert_int_equal(table_int(&a, f, "shadow_draw_calls"), 0);
        assert_int_equal(table_int(&b, f, "pages_rendered"), need0);   /* cache=off draws them all again */
        assert_string_equal(sb_table_get(&a, f, "err_rate"), sb_table_get(&b, f, "err_rate"));
        assert_string_equal(sb_table_get(&a, f, "err_rate"), sb_table_get(&a, 0, "err_rate"));
    }
    print_message("still camera: %ld pages at frame 0, none after\n", need0);
    sb_table_free(&a);
    sb_table_free(&b);
    sb_table_free(&sum);
}

/* Along towers' path the camera moves: pages it still needs are kept, so it draws fewer than it needs. */
static void test_moving_camera_draws_fewer_than_it_needs(void **st) {
    (void)st;
    sb_table sum, a;
    char dir[4096];
    render("towers", test_data("towers-pan.path"), "virtual", 8, "320x180", "moving", &sum, dir, sizeof dir);
    frames_table(dir, &sum, 0, &a);
    long need = 0, drawn = 0, kept = 0;
    for (int f = 1; f < a.nrows; f++) {
        need += table_int(&a, f, "pages_needed");
        drawn += table_int(&a, f, "pages_rendered");
        kept += table_int(&a, f, "pages_cached");
        assert_int_equal(table_int(&a, f, "pages_rendered") + table_int(&a, f, "pages_cached"), table_int(&a, f, "pages_needed"));
    }
    print_message("moving camera: frames 1..%d needed %ld pages, drew %ld, kept %ld\n", a.nrows - 1, need, drawn, kept);
    assert_true(drawn < need);
    assert_true(kept > 0);
    sb_table_free(&a);
    sb_table_free(&sum);
}

/* Through the API: the same frame twice (still), under a new sun (every page again), and again (none). */

/* A frame's own counter of its technique by name (virtual declares its page counters in its own file); fails the
 * test where the frame's technique does not declare it. */
static long own(const sb_counters *c, const char *name) {
    for (int k = 0; k < c->own_count; k++)
        if (!strcmp(c->own_defs[k].name, name)) return lround(c->own[k]);
    fail_msg("the frame holds no counter %s", name);
    return 0;
}
static void test_moved_sun_draws_every_page(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    memset(&s, 0, sizeof s);
    assert_true(test_open(&s, "plane-box", test_data("planebox-fixed.path"), 320, 180, &err));
    sb_run_spec *runs = NULL;
    int n = 0;
    assert_true(sb_spec_expand("virtual", NULL, &runs, &n, &err));
    sb_instance in;
    assert_true(sb_instance_create(&in, &s, &runs[0], 8, &err));
    const int npx = 320 * 180;
    unsigned char *v0 = malloc(npx), *v1 = malloc(npx), *v2 = malloc(npx);
    sb_counters c[4];
    unsigned char *out[4] = {v0, v1, v2, NULL};
    sb_v3 sun0 = s.gpu.sun;
    for (int k = 0; k < 4; k++) {
        if (k == 2) s.gpu.sun = sb_v3_norm(sb_v3_make(sun0.x + 0.3, sun0.y, sun0.z - 0.2));
        sb_timer t;
        sb_timer_init(&t, SB_TIMING_SYNC, 1, 1);
        sb_timer_frame_begin(&t, 0);
        sb_frame f;
        memset(&f, 0, sizeof f);
        render_frame_eval(&s, &in, &f, 0, 1, k, &t);
        if (out[k]) sb_gpu_readback(&s.gpu, NULL, out[k], NULL);
        sb_timer_free(&t);
        c[k] = f.counters;
        print_message("frame %d: needed %ld, rendered %ld, cached %ld\n", k, own(&c[k], "pages_needed"),
                      own(&c[k], "pages_rendered"), own(&c[k], "pages_cached"));
        assert_int_equal(own(&c[k], "pool_overflow"), 0);
    }
    assert_true(own(&c[0], "pages_needed") > 0);
    assert_int_equal(own(&c[0], "pages_rendered"), own(&c[0], "pages_needed"));
    assert_int_equal(own(&c[1], "pages_rendered"), 0);
    assert_int_equal(own(&c[1], "pages_cached"), own(&c[1], "pages_needed"));
    assert_memory_equal(v0, v1, npx);                                   /* kept pages: the same shadows, bit for bit */
    assert_int_equal(own(&c[2], "pages_rendered"), own(&c[2], "pages_needed"));   /* a new sun: everything again */
    assert_int_equal(own(&c[2], "pages_cached"), 0);
    assert_int_equal(own(&c[3], "pages_rendered"), 0);
    long moved = 0;
    for (int i = 0; i < npx; i++) moved += abs((int)v0[i] - (int)v2[i]) > 64;
    print_message("%ld of %d pixels changed their shadow with the sun\n", moved, npx);
    assert_true(moved > npx / 1000);                                    /* and the shadows did move */
    sb_instance_destroy(&in);
    free(runs);
    free(v0);
    free(v1);
    free(v2);
    sb_session_close(&s);
}

/* A pool of 1 MiB holds a few pages: the warning names the shortfall; the error stays finite; no GL error
 * (a GL error would fail the run). */
static void test_small_pool_warns(void **st) {
    (void)st;
    sb_table sum, a;
    char dir[4096];
    render("towers", "towers", "virtual:pool=1", 3, "320x180", "pool", &sum, dir, sizeof dir);
    assert_string_equal(sb_table_get(&sum, 0, "status"), "ok");
    const char *w = sb_table_get(&sum, 0, "warnings");
    print_message("pool=1: %s\n", w);
    assert_non_null(strstr(w, "pool_overflow: the page pool was short of"));
    assert_non_null(strstr(w, "used the page one level coarser"));   /* what happened, as docs/techniques.md says */
    frames_table(dir, &sum, 0, &a);
    for (int f = 0; f < a.nrows; f++) {
        double e = num(&a, f, "err_rate");
        assert_true(isfinite(e) && e >= 0 && e < 0.5);
        assert_true(table_int(&a, f, "pool_overflow") > 0);
        /* the counters partition the pages needed: each drawn or kept for itself, or given up; the stand-ins
           drawn or kept in their place are apart */
        long needed = table_int(&a, f, "pages_needed"), rendered = table_int(&a, f, "pages_rendered"),
             cached = table_int(&a, f, "pages_cached"), stand = table_int(&a, f, "pages_stand_in"),
             over = table_int(&a, f, "pool_overflow");
        print_message("frame %d: needed %ld = rendered %ld + cached %ld - stand-ins %ld + overflow %ld\n", f, needed,
                      rendered, cached, stand, over);
        assert_true(stand > 0);
        assert_int_equal(rendered + cached - stand + over, needed);
    }
    sb_table_free(&a);
    sb_table_free(&sum);
}

static void test_bad_parameters_refused(void **st) {
    (void)st;
    const struct {
        const char *spec, *says;
    } bad[] = {
        {"virtual:page=100", "page=100 is not a power of two (valid: 16, 32"},
        {"virtual:res=1000", "res=1000 is not a multiple of page=128"},
        {"virtual:pool=0", "pool"},
        {"virtual:res=131072", "res"},
        {"virtual:page=1024:pool=2", "holds no page of 1024 texels"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        const char *out = expect_cli_exit(2, bad[i].says, "%s run towers towers %s --frames 2 --out %s/bad", test_binary(),
                                          bad[i].spec, g_tmp);
        print_message("%s: %s", bad[i].spec, out);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_less_wrong_than_pssm),
        cmocka_unit_test(test_still_camera_keeps_its_pages),
        cmocka_unit_test(test_moving_camera_draws_fewer_than_it_needs),
        cmocka_unit_test(test_moved_sun_draws_every_page),
        cmocka_unit_test(test_small_pool_warns),
        cmocka_unit_test(test_bad_parameters_refused),
    };
    return cmocka_run_group_tests_name("virtual", tests, setup, teardown);
}
