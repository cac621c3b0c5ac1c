/* The metric table walked row by row on a real results set: every metric (a
 * series or a scalar with a unit, results/columns.c) is in the summary's
 * header, in `shadowbench columns`, accepted by `compare --metric` and
 * `history regressions --metric`, and in docs/csv.md; the commands' default
 * metrics are the table's SB_USE_ rows. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "table.h"

static char g_tmp[64], g_out[65536], g_dir[8192];

static int setup(void **st) {
    (void)st;
    if (tmp_folder(g_tmp, sizeof g_tmp, "sbmetric")) return -1;
    /* a small set: a technique without maps and one with, every frame evaluated (and scored with FLIP) */
    if (run_logged(g_out, sizeof g_out, "%s run plane-box plane-box none sm:res=256 sdsm:res=256 volumes raycast virtual:pool=8 --frames 3 --size 96x54 "
                   "--error-every 1 --flip --taa on --warmup 0 --out %s/r --quiet", test_binary(), g_tmp) != 0)
        return -1;
    char *nl = strrchr(g_out, '\n');
    if (nl && nl > g_out) *nl = 0;
    nl = strrchr(g_out, '\n');
    snprintf(g_dir, sizeof g_dir, "%.4000s", nl ? nl + 1 : g_out);
    return run_logged(g_out, sizeof g_out, "%s history add %s --history %s/h.sqlite --quiet", test_binary(), g_dir,
                      g_tmp);
}

static int teardown(void **st) {
    (void)st;
    return tmp_remove(g_tmp);
}

static void test_every_metric_everywhere(void **st) {
    (void)st;
    const char *metrics[128];
    int n = sb_columns_metrics(metrics, 128);
    assert_true(n > 20);
    char path[8400];
    snprintf(path, sizeof path, "%s/summary.csv", g_dir);
    sb_err err;
    char *summary = sb_read_file(path, NULL, &err);
    assert_non_null(summary);
    *strchr(summary, '\n') = 0;   /* the header */
    snprintf(path, sizeof path, "%s/docs/csv.md", getenv("SB_SOURCE_ROOT"));
    char *doc = sb_read_file(path, NULL, &err);
    assert_non_null(doc);
    sb_csv cols = {0};
    sb_columns_csv(&cols);
    int measured = 0, motion = 0, many = 0;
    for (int i = 0; i < n; i++) {
        const char *m = metrics[i];
        sb_metric_cols mc;
        assert_true(sb_columns_metric(m, &mc));
        char want[160];
        snprintf(want, sizeof want, ",%s,", mc.center);   /* the column compare reads is in the header */
        char header[8192];
        snprintf(header, sizeof header, ",%s,", summary);
        if (!strstr(header, want)) print_error("summary.csv has no %s (metric %s)\n", mc.center, m);
        assert_non_null(strstr(header, want));
        snprintf(want, sizeof want, "run,%s,", m);
        assert_non_null(strstr(cols.buf, want));
        snprintf(want, sizeof want, "| `%s` |", m);
        if (!strstr(doc, want)) print_error("docs/csv.md has no row for %s\n", m);
        assert_non_null(strstr(doc, want));
        int rc = run_logged(g_out, sizeof g_out, "%s compare %s %s --metric %s --format csv", test_binary(), g_dir,
                            g_dir, m);
        assert_true(rc == 0 || rc == 3);   /* the same set: no regression (3: a timing of an unstable run) */
        assert_null(strstr(g_out, "unknown metric"));
        snprintf(want, sizeof want, ",%s,", m);   /* a row for it, unless no run of the set measures it */
        if (!strstr(g_out, want)) {
            print_message("no run of the set measures %s\n", m);
            /* the figures of a moving scene are empty on plane-box, where nothing moves (test_motion has them) */
            const char *still[] = {"anim_ms", "casters_moved", "cascades_invalidated", "pages_invalidated",
                                   "pages_dynamic", "ref_refit_ms", "stale_px", "pose_ms"};
            for (size_t k = 0; k < sizeof still / sizeof *still; k++) motion += !strcmp(m, still[k]);
            /* the figures of several lamps and of the atlas: none on plane-box's one sun (test_lights has them) */
            const char *lamps[] = {"lights_px", "lights_shadowed", "lights_dropped", "lights_downscaled",
                                   "atlas_occupancy", "grid_items", "clusters_ms"};
            for (size_t k = 0; k < sizeof lamps / sizeof *lamps; k++) many += !strcmp(m, lamps[k]);
        }
        measured += strstr(g_out, want) != NULL;
        rc = run_logged(g_out, sizeof g_out, "%s history regressions --history %s/h.sqlite --metric %s --quiet",
                        test_binary(), g_tmp, m);
        assert_int_equal(rc, 0);
    }
    assert_int_equal(motion, 8);
    assert_int_equal(many, 7);
    assert_true(measured >= n - 4 - motion - many);   /* llvmpipe has no clock; warp_fallbacks... are 0, which is a row */
    /* a name that is a column but not a number is no metric */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s compare %s %s --metric renderer", test_binary(), g_dir, g_dir),
                     2);
    assert_non_null(strstr(g_out, "unknown metric 'renderer'"));
    sb_csv_free(&cols);
    free(summary);
    free(doc);
}

/* compare with no --metric compares the SB_USE_COMPARE rows, in table order. */
static void test_default_metrics_are_the_table_rows(void **st) {
    (void)st;
    const char *def[32];
    int n = sb_columns_default_metrics(SB_USE_COMPARE, def, 32);
    assert_true(n >= 3);
    assert_int_not_equal(run_logged(g_out, sizeof g_out, "%s compare %s %s --format csv", test_binary(), g_dir, g_dir), 2);
    /* sm's rows: every default metric once, nothing else */
    int rows = 0;
    for (char *line = strtok(g_out, "\n"); line; line = strtok(NULL, "\n")) {
        if (!strstr(line, ",sm,")) continue;
        bool known = false;
        for (int k = 0; k < n; k++) {
            char want[96];
            snprintf(want, sizeof want, ",%s,", def[k]);
            known |= strstr(line, want) != NULL;
        }
        if (!known) print_error("compare's default row is no SB_USE_COMPARE metric: %s\n", line);
        assert_true(known);
        rows++;
    }
    /* ... each one sm's run measured (penumbra_err: a light with a size; stale_px: a cache in a moving scene;
       lights_dropped: an atlas; not here) */
    sb_table t;
    summary_table(g_dir, &t);
    int measured = 0, sm = -1;
    for (int r = 0; r < t.nrows && sm < 0; r++)
        if (!strcmp(sb_table_get(&t, r, "technique"), "sm")) sm = r;
    for (int k = 0; k < n; k++) {
        sb_metric_cols mc;
        assert_true(sb_columns_metric(def[k], &mc));
        measured += *sb_table_get(&t, sm, mc.center) != 0;
    }
    sb_table_free(&t);
    assert_true(measured >= n - 3);
    assert_int_equal(rows, measured);
    const char *hist[32];
    int nh = sb_columns_default_metrics(SB_USE_HISTORY, hist, 32);
    const char *rep[32];
    int nr = sb_columns_default_metrics(SB_USE_REPORT, rep, 32);
    assert_true(nh >= 1 && nr >= 1);
    const char *pair[32];
    int np = sb_columns_default_metrics(SB_USE_PAIR, pair, 32);
    assert_int_equal(np, 4);   /* time, error, flicker and the splits' jitter */
    const char *want[] = {"gpu_ms", "err_rate", "flicker_rate", "split_jitter"};
    for (int k = 0; k < 4; k++) assert_string_equal(pair[k], want[k]);
}

/* The summary's shadow_mb of runs not rendered: the rendering-free estimate (sb_params_shadow_bytes). */
static void shadow_mb_of(const char *scene, const char *specs, const char *extra, sb_table *t) {
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run %s auto %s --frames 1 --size 64x36 --error-every 0 "
                                "--warmup 0 --quiet %s --out %s/mb", test_binary(), scene, specs, extra, g_tmp), 0);
    char *nl = strrchr(g_out, '\n');
    if (nl && nl > g_out) *nl = 0;
    nl = strrchr(g_out, '\n');
    summary_table(nl ? nl + 1 : g_out, t);
}

/* shadow_mb is the maps a technique holds, from its parameters: res^2 a map in its depth format (32f: 4 bytes),
 * with a moment format its moments and their blur copy (vsm: 2 floats twice), six cube faces, two paraboloids;
 * 0 without maps. The GPU-memory check reads the same figure: a run over --gpu-memory is skipped naming it.
 * tune --max-mb renders no setting over it. */
static void test_shadow_mb_is_the_maps(void **st) {
    (void)st;
    sb_table t;
    /* virtual: whole slots of (128 + 2 x 2)^2 32-bit texels and the table (16 levels of 128^2 16-bit entries and a
       request bit each: 557,056 bytes) within pool MiB: 64 holds 31 x 30 slots, 16 holds 16 x 14 */
    shadow_mb_of("towers", "none sm:res=1024 pssm:res=2048:cascades=4 pssm:res=1024:cascades=2:format=vsm "
                 "sm:res=512:depth=16 virtual:pool=64 virtual:pool=16", "", &t);
    const double want[] = {0, 4, 64, 40, 0.5, (930 * 132 * 132 * 4.0 + 557056) / 1048576,
                           (224 * 132 * 132 * 4.0 + 557056) / 1048576};
    assert_int_equal(t.nrows, 7);
    for (int r = 0; r < t.nrows; r++) {
        print_message("%s %s: shadow_mb %s\n", sb_table_get(&t, r, "technique"), sb_table_get(&t, r, "params"),
                      sb_table_get(&t, r, "shadow_mb"));
        assert_string_equal(sb_table_get(&t, r, "status"), "ok");
        assert_float_equal(atof(sb_table_get(&t, r, "shadow_mb")), want[r], 1e-4);   /* the CSV holds 6 digits */
    }
    sb_table_free(&t);
    shadow_mb_of("towers-night", "cube:res=512 dpsm:res=512", "", &t);
    assert_float_equal(atof(sb_table_get(&t, 0, "shadow_mb")), 6, 1e-9);
    assert_float_equal(atof(sb_table_get(&t, 1, "shadow_mb")), 2, 1e-9);
    sb_table_free(&t);
    /* 64 MiB of maps beside 64x36 targets do not fit in 48 MiB: skipped, the figure in its row and its reason */
    shadow_mb_of("towers", "pssm:res=2048:cascades=4 sm:res=1024 virtual:pool=64 virtual:pool=16", "--gpu-memory 48M", &t);
    assert_string_equal(sb_table_get(&t, 0, "status"), "skipped");
    assert_non_null(strstr(sb_table_get(&t, 0, "reason"), "needs 64 MiB of shadow maps"));
    assert_float_equal(atof(sb_table_get(&t, 0, "shadow_mb")), 64, 1e-9);
    assert_string_equal(sb_table_get(&t, 1, "status"), "ok");
    print_message("virtual: %s\n", sb_table_get(&t, 2, "reason"));
    assert_string_equal(sb_table_get(&t, 2, "status"), "skipped");   /* the same estimate as its shadow_mb */
    assert_non_null(strstr(sb_table_get(&t, 2, "reason"), "needs 62 MiB of page pool"));
    assert_float_equal(atof(sb_table_get(&t, 2, "shadow_mb")), want[5], 1e-4);
    assert_string_equal(sb_table_get(&t, 3, "status"), "ok");
    sb_table_free(&t);
    /* tune --max-mb 5: res=2048 (16 MiB) is never rendered; the choice holds at most 5 */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s tune towers auto 'sm:res=512,1024,2048' --max-err 1 --max-mb 5 "
                                "--frames 9 --size 96x54 --quiet --out %s/tune", test_binary(), g_tmp), 0);
    assert_non_null(strstr(g_out, "shadow_mb at most 5"));
    assert_non_null(strstr(g_out, "holds 16 MiB of shadow storage, over --max-mb 5"));
    assert_null(strstr(g_out, "recommended: sm:res=2048"));
    char *dir = strrchr(g_out, '\n');
    if (dir && dir[1] == 0) *dir = 0, dir = strrchr(g_out, '\n');   /* the last line: the tune folder */
    assert_non_null(dir);
    char path[8400];
    snprintf(path, sizeof path, "%s/rung-0/summary.csv", dir + 1);
    sb_table r0;
    sb_err err;
    assert_true(sb_table_load(&r0, path, &err));
    for (int r = 0; r < r0.nrows; r++) assert_true(atof(sb_table_get(&r0, r, "shadow_mb")) <= 5);
    assert_int_equal(r0.nrows, 2);
    sb_table_free(&r0);
}

/* One estimate, two users, for every technique: each run's shadow_mb is the figure its GPU-memory check names when
 * the maps do not fit (every technique that keeps maps, at its defaults and at a second setting), and a technique
 * keeping none is never skipped for memory. */
static void test_memory_check_is_shadow_mb(void **st) {
    (void)st;
    const struct {
        const char *scene, *specs;
    } sets[] = {
        {"towers", "none raycast volumes sm sm:res=4096:format=msm pssm pssm:cascades=2:res=1024:depth=16 sdsm lispsm tsm "
                   "psm psm:cube=on virtual virtual:pool=300"},
        {"towers-night", "cube cube:res=2048 dpsm dpsm:res=4096"},
    };
    int checked = 0;
    for (size_t k = 0; k < sizeof sets / sizeof *sets; k++) {
        sb_table t;
        shadow_mb_of(sets[k].scene, sets[k].specs, "--gpu-memory 1M", &t);
        for (int r = 0; r < t.nrows; r++) {
            double mb = atof(sb_table_get(&t, r, "shadow_mb"));
            const char *status = sb_table_get(&t, r, "status"), *reason = sb_table_get(&t, r, "reason");
            print_message("%-8s shadow_mb %8.3f  %s %s\n", sb_table_get(&t, r, "technique"), mb, status, reason);
            if (mb == 0) {
                assert_null(strstr(reason, "needs"));
                continue;
            }
            char want[64];
            snprintf(want, sizeof want, "needs %.0f MiB of ", mb);
            assert_string_equal(status, "skipped");
            assert_non_null(strstr(reason, want));
            checked++;
        }
        sb_table_free(&t);
    }
    assert_int_equal(checked, 15);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_metric_everywhere),
        cmocka_unit_test(test_default_metrics_are_the_table_rows),
        cmocka_unit_test(test_shadow_mb_is_the_maps),
        cmocka_unit_test(test_memory_check_is_shadow_mb),
    };
    return cmocka_run_group_tests_name("metrics", tests, setup, teardown);
}
