/* Summary statistics against values computed by hand. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "stats.h"

static void test_known_values(void **st) {
    (void)st;
    double v[] = {5, 1, 4, 2, 3, NAN};
    sb_stats s = sb_stats_compute(v, 6);
    assert_int_equal(s.n, 5);
    assert_true(fabs(s.mean - 3) < 1e-12);
    assert_true(fabs(s.median - 3) < 1e-12);
    assert_true(fabs(s.std - sqrt(2.5)) < 1e-12);
    assert_true(fabs(s.p95 - 4.8) < 1e-12);           /* 1 + 0.95*4 -> between 4 and 5 */
    assert_true(fabs(s.ci95 - 2.776 * sqrt(2.5) / sqrt(5)) < 1e-9);
    sb_stats e = sb_stats_compute(v, 0);
    assert_true(isnan(e.mean) && isnan(e.ci95));
}

static void test_t_quantiles(void **st) {
    (void)st;
    assert_true(fabs(sb_t975(1) - 12.706) < 1e-3);
    assert_true(fabs(sb_t975(30) - 2.042) < 1e-3);
    assert_true(fabs(sb_t975(60) - 2.000) < 2e-3);
    assert_true(fabs(sb_t975(120) - 1.980) < 2e-3);
    assert_true(sb_t975(1000) > 1.959 && sb_t975(1000) < 1.963);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_known_values), cmocka_unit_test(test_t_quantiles)};
    return cmocka_run_group_tests_name("stats", tests, NULL, NULL);
}
