/* The change-point detector alone (harness/base/changepoint.h), on synthetic
 * series: steps of 5 % in 2 % Gaussian noise must be found within two nights
 * of where they are, pure noise must give at most one false change in 1,000
 * series-nights, and the series' own features (weights, constant series, one
 * odd night) must behave as documented. Seeds are fixed: the rates printed are
 * the measured ones. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "changepoint.h"

static uint64_t rng = 0x5eed;
static double u01(void) {
    uint64_t z = (rng += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return ((double)(z >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(void) { return sqrt(-2 * log(u01())) * cos(6.283185307179586 * u01()); }

static const sb_cp_opts rel = {.relative = true};

static void test_false_alarms(void **state) {
    (void)state;
    sb_cp_change ch[64];
    long changes = 0, nights = 0;
    for (int s = 0; s < 2000; s++) {
        double x[30];
        for (int i = 0; i < 30; i++) x[i] = 100 * (1 + 0.02 * gauss());
        changes += sb_changepoints(x, NULL, 30, &rel, ch, 64, NULL);
        nights += 30;
    }
    double rate = 1000.0 * (double)changes / (double)nights;
    printf("pure noise (2%%, 2000 series of 30 nights): %ld false changes, %.2f per 1000 series-nights\n", changes,
           rate);
    assert_true(rate <= 1.0);
}

static void test_steps_found(void **state) {
    (void)state;
    sb_cp_change ch[64];
    int trials = 2000, within2 = 0, exact = 0, next_morning = 0;
    for (int s = 0; s < trials; s++) {
        double x[30], step = s % 2 ? 1.05 : 0.95;
        int at = 8 + (int)(u01() * 15);
        for (int i = 0; i < 30; i++) x[i] = 100 * (i >= at ? step : 1) * (1 + 0.02 * gauss());
        int n = sb_changepoints(x, NULL, 30, &rel, ch, 64, NULL);
        bool hit = false;
        for (int j = 0; j < n && j < 64; j++) {
            if (abs(ch[j].at - at) <= 2 && (ch[j].rel > 0) == (step > 1)) hit = true;
            if (ch[j].at == at) exact++;
        }
        within2 += hit;
        /* the same step seen with only two nights after it (the morning after the second night) */
        int n2 = sb_changepoints(x, NULL, at + 2, &rel, ch, 64, NULL);
        for (int j = 0; j < n2 && j < 64; j++)
            if (ch[j].at == at) next_morning++;
    }
    printf("5%% steps in 2%% noise (%d series of 30 nights): found within two nights %.1f%%, at the night %.1f%%; "
           "with only two nights after the step: %.1f%%\n", trials, 100.0 * within2 / trials,
           100.0 * exact / trials, 100.0 * next_morning / trials);
    assert_true(within2 >= trials * 90 / 100);
}

static void test_big_step_two_nights(void **state) {
    (void)state;
    /* a large step is found the morning after its second night, with its size and direction */
    double x[10] = {10.1, 9.9, 10.0, 10.2, 9.8, 10.0, 10.1, 9.9, 15.0, 15.2};
    sb_cp_change ch[4];
    int n = sb_changepoints(x, NULL, 10, &rel, ch, 4, NULL);
    assert_int_equal(n, 1);
    assert_int_equal(ch[0].at, 8);
    assert_true(fabs(ch[0].before - 10.0) < 0.11 && fabs(ch[0].after - 15.1) < 0.11);
    assert_true(ch[0].rel > 0.45 && ch[0].z > 5 && ch[0].p < 1e-3);
    /* one night is never a change */
    assert_int_equal(sb_changepoints(x, NULL, 9, &rel, ch, 4, NULL), 0);
}

static void test_weak_nights(void **state) {
    (void)state;
    /* two odd nights at the end: a change at full weight, none when both are marked unstable */
    double x[12] = {10, 10.1, 9.9, 10, 10.05, 9.95, 10, 10.1, 9.9, 10, 10.4, 10.45};
    double w[12] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    sb_cp_opts o = {.relative = true, .noise_floor = 0.005};
    sb_cp_change ch[4];
    assert_int_equal(sb_changepoints(x, w, 12, &o, ch, 4, NULL), 1);
    w[10] = w[11] = 0.05;
    assert_int_equal(sb_changepoints(x, w, 12, &o, ch, 4, NULL), 0);
}

static void test_constant_and_exact(void **state) {
    (void)state;
    sb_cp_change ch[4];
    double c[8] = {0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01};
    assert_int_equal(sb_changepoints(c, NULL, 8, &rel, ch, 4, NULL), 0);
    /* the same figure night after night is no change, at any level (rounding in the sums is not a shift) */
    double d[30];
    for (int i = 0; i < 30; i++) d[i] = 618.3;
    assert_int_equal(sb_changepoints(d, NULL, 30, &rel, ch, 4, NULL), 0);
    for (int i = 0; i < 30; i++) d[i] = 1.811e-05;
    assert_int_equal(sb_changepoints(d, NULL, 30, &rel, ch, 4, NULL), 0);
    /* a deterministic metric (an error rate) that moves once moves for a reason: it is a change */
    double e[8] = {0.0100, 0.0100, 0.0100, 0.0100, 0.0100, 0.0101, 0.0101, 0.0101};
    assert_int_equal(sb_changepoints(e, NULL, 8, &rel, ch, 4, NULL), 1);
    assert_int_equal(ch[0].at, 5);
    /* NaN nights are skipped, zeros read on a linear scale */
    double z[8] = {0, 0, NAN, 0, 0, 2, 2, 2};
    assert_int_equal(sb_changepoints(z, NULL, 8, &rel, ch, 4, NULL), 1);
    assert_int_equal(ch[0].at, 5);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_false_alarms),     cmocka_unit_test(test_steps_found),
        cmocka_unit_test(test_big_step_two_nights), cmocka_unit_test(test_weak_nights),
        cmocka_unit_test(test_constant_and_exact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
