/* Paths checked before they render (harness/pathcheck.c): a camera that
 * passes through plane-box's box is flagged at exactly the frames inside it,
 * in `path`'s verdict column, in a run's warnings, and refused by
 * --strict-path; a camera under desert's terrain (a single-sided sheet) is
 * below a surface facing up; every bundled scene's own path is clean. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "table.h"

static char g_out[262144];

SB_TEST_SCRATCH("sbpath")

/* `path PATH SCENE --frames n`: each frame's verdict column, in order, into v (n entries). */
static void verdicts(const char *path, const char *scene, int n, char v[][16]) {
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s path %s %s --frames %d 2>/dev/null", test_binary(), path,
                                scene, n), 0);
    int k = 0;
    for (char *line = strtok(g_out, "\n"); line; line = strtok(NULL, "\n")) {
        if (strncmp(line, "frame,", 6) == 0 || !strchr(line, ',') || line[0] == '$' || line[0] == '-') continue;
        char *c = line;   /* the 14th field */
        for (int f = 0; f < 13 && c; f++) c = strchr(c, ',') ? strchr(c, ',') + 1 : NULL;
        assert_non_null(c);
        snprintf(v[k], 16, "%.*s", (int)strcspn(c, ","), c);
        k++;
    }
    assert_int_equal(k, n);
}

static void test_through_the_box(void **st) {
    (void)st;
    char v[20][16];
    verdicts(test_data("planebox-through.path"), "plane-box", 20, v);
    for (int i = 0; i < 20; i++) {
        printf("frame %d: %s\n", i, v[i]);
        assert_string_equal(v[i], i >= 8 && i <= 11 ? "inside" : "clear");   /* x = -0.79 ... 0.79 inside [-1, 1] */
    }
    /* --strict-path refuses it, naming the frames; a run says it in every run's warnings */
    const char *bin = test_binary();
    expect_cli_fail("frames 8-11: the camera is inside closed geometry", "%s path %s plane-box --frames 20 --strict-path",
                    bin, test_data("planebox-through.path"));
    expect_cli_fail("frames 8-11: the camera is inside closed geometry (node 1) (--strict-path)",
                    "%s run plane-box %s none --frames 20 --error-every 5 --size 64x36 --strict-path --out %s/strict",
                    bin, test_data("planebox-through.path"), g_tmp);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run plane-box %s none sm:res=256 --frames 20 --error-every 5 "
                                "--warmup 0 --size 64x36 --quiet --out %s/warned", bin,
                                test_data("planebox-through.path"), g_tmp), 0);
    sb_table t;
    summary_table(last_line_of(g_out), &t);
    for (int r = 0; r < t.nrows; r++)
        assert_non_null(strstr(sb_table_get(&t, r, "warnings"),
                               "the path's cameras: frames 8-11: the camera is inside closed geometry"));
    sb_table_free(&t);
}

static void test_under_the_ground(void **st) {
    (void)st;
    char v[5][16];
    verdicts(test_data("desert-under.path"), "desert", 5, v);
    for (int i = 0; i < 5; i++) assert_string_equal(v[i], "below");
}

/* Every bundled scene along its own path, at the nightly's 24 frames, the default 60 and a dense 300. */
static void test_bundled_paths_clean(void **st) {
    (void)st;
    const char *scenes[] = {"plane-box", "plane-box-lamp", "desert", "towers", "towers-night", "overhangs",
                            "towers-draco"};
    const int counts[] = {24, 60, 300};
    for (size_t s = 0; s < SB_COUNT(scenes); s++)
        for (size_t c = 0; c < SB_COUNT(counts); c++) {
            char v[300][16];
            verdicts(scenes[s], scenes[s], counts[c], v);
            for (int i = 0; i < counts[c]; i++) {
                if (strcmp(v[i], "clear")) print_error("%s along its path, %d frames: frame %d %s\n", scenes[s], counts[c], i, v[i]);
                assert_string_equal(v[i], "clear");
            }
        }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_through_the_box),
        cmocka_unit_test(test_under_the_ground),
        cmocka_unit_test(test_bundled_paths_clean),
    };
    return cmocka_run_group_tests_name("pathcheck", tests, setup, teardown);
}
