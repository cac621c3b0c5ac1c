/* Spec parsing: glmark2-style grids, validation against the parameter table. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "spec.h"

static void test_grid(void **st) {
    (void)st;
    sb_run_spec *runs = NULL;
    int n = 0;
    sb_err err;
    assert_true(sb_spec_expand("sm:res=512,1024,2048:filter=none,pcf3", NULL, &runs, &n, &err));
    assert_int_equal(n, 6);
    char c[512];
    sb_params_canonical(&runs[0].params, c, sizeof c);
    assert_string_equal(c, "res=512:depth=32f:bias=1:slope=0.5:normal=0.25:filter=none:sun_size=0.53:stable=off:format=depth:blur=2:bleed=0.2:exponent=80");
    sb_params_canonical(&runs[5].params, c, sizeof c);
    assert_string_equal(c, "res=2048:depth=32f:bias=1:slope=0.5:normal=0.25:filter=pcf3:sun_size=0.53:stable=off:format=depth:blur=2:bleed=0.2:exponent=80");
    double filter, res;
    assert_true(sb_params_find(&runs[5].params, "filter", &filter) && filter == 2);
    assert_true(sb_params_find(&runs[1].params, "res", &res) && res == 512);
    assert_true(sb_spec_expand("none", NULL, &runs, &n, &err));
    assert_int_equal(n, 7);
    assert_ptr_equal(runs[6].tech, sb_technique_find("none"));
    /* "auto" where the table allows it: a grid value like any other, kept as text, bound as the default */
    assert_true(sb_spec_expand("pssm:bias=auto,0.5:normal=auto", NULL, &runs, &n, &err));
    assert_int_equal(n, 9);
    sb_params_canonical(&runs[7].params, c, sizeof c);
    assert_non_null(strstr(c, ":bias=auto:slope=0.5:normal=auto:"));
    double bias;
    assert_true(sb_params_find(&runs[7].params, "bias", &bias) && bias == 1);
    assert_true(runs[7].params.v[2].automatic && !runs[8].params.v[2].automatic && runs[8].params.v[4].automatic);
    assert_true(sb_spec_expand("cube:bias=auto", NULL, &runs, &n, &err));
    free(runs);
}

static void expect_error(const char *spec, const char *needle) {
    sb_run_spec *runs = NULL;
    int n = 0;
    sb_err err = {{0}};
    assert_false(sb_spec_expand(spec, "b.bench:3", &runs, &n, &err));
    print_message("%s -> %s\n", spec, err.msg);
    assert_non_null(strstr(err.msg, needle));
    assert_non_null(strstr(err.msg, "b.bench:3"));
    free(runs);
}

static void test_errors(void **st) {
    (void)st;
    expect_error("nosuch:res=1", "unknown technique 'nosuch'");
    expect_error("sm:rez=1024", "unknown parameter 'rez' (valid: res, depth, bias, slope, normal, filter, sun_size, stable, format, blur, bleed, exponent, distance)");
    expect_error("sm:res=100000", "out of range");
    expect_error("sm:res=10.5", "expected an integer");
    expect_error("sm:filter=gauss", "expected one of none|hw|pcf3|pcf5|poisson16|pcss");
    expect_error("sm:res", "not NAME=VALUE");
    expect_error("sm:res=512:res=1024", "given twice");
    expect_error("sm:bias=nan", "expected a number in [0, 100] or auto");
    expect_error("pssm:lambda=auto", "expected a number in [0, 1]");
    expect_error("sm:res=auto", "expected a number in [64, 16384]");
    expect_error("sm:filter=auto", "expected one of");
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_grid), cmocka_unit_test(test_errors)};
    return cmocka_run_group_tests_name("spec", tests, NULL, NULL);
}
