/* The numerical-stability battery in reduced form (one frame a case, small
 * frames): it must pass, and its table must hold every case and technique. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

static char g_out[262144];

static void test_battery_passes(void **st) {
    (void)st;
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s stress --frames 1 --size 160x90", test_binary());
    int rc = run_capture(cmd, g_out, sizeof g_out);
    print_message("%s\n", g_out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(g_out, "0 failure(s)"));
    const char *cases[] = {"translate-1e6", "near-far-1e8", "scene-1e-3", "scene-1e5", "sun-vertical",
                           "sun-along-view", "sun-against-view", "sun-grazing", "camera-inside-caster", "all-sky",
                           "single-triangle", "degenerate-huge-triangles", "path-one-key", "path-repeated-keys",
                           "path-180-flips"};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char row[128];
        snprintf(row, sizeof row, "%-26s %-28s ok", cases[i], "sdsm");
        assert_non_null(strstr(g_out, row));
    }
    assert_null(strstr(g_out, "FAIL"));
}

static void test_battery_can_fail(void **st) {
    (void)st;
    /* the battery run on a shadow map without bias (acne) and one whose bias
       detaches every shadow must fail them, and pass the default beside them */
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s stress base sm:bias=0:slope=0:normal=0 sm:bias=100:normal=100 sm --frames 1 --size 160x90",
             test_binary());
    int rc = run_capture(cmd, g_out, sizeof g_out);
    print_message("%s\n", g_out);
    assert_int_equal(rc, 1);
    char row[128];
    snprintf(row, sizeof row, "%-26s %-28s FAIL", "base", "sm:bias=0:slope=0:normal=0");
    assert_non_null(strstr(g_out, row));
    snprintf(row, sizeof row, "%-26s %-28s FAIL", "base", "sm:bias=100:normal=100");
    assert_non_null(strstr(g_out, row));
    snprintf(row, sizeof row, "%-26s %-28s ok", "base", "sm");
    assert_non_null(strstr(g_out, row));
    assert_non_null(strstr(g_out, "above the bound"));
    assert_non_null(strstr(g_out, "2 failure(s)"));
}

/* The cases' scenes go to $TMPDIR where it is set (a cluster node's scratch): one that cannot be written is
 * named in one line, exit 2, before anything is rendered. */
static void test_tmpdir(void **st) {
    (void)st;
    expect_cli_exit(2, "for the stress scenes in /nonexistent-sb-tmp", "TMPDIR=/nonexistent-sb-tmp %s stress base sm",
                    test_binary());
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_battery_passes), cmocka_unit_test(test_battery_can_fail),
                                       cmocka_unit_test(test_tmpdir)};
    return cmocka_run_group_tests_name("stress", tests, NULL, NULL);
}
