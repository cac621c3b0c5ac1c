/* Bad input through the command line: one line naming the file and place,
 * a non-zero exit, nothing written. Also run in the ASan/UBSan build (suite
 * `loader`): a broken file is refused before any GL context exists. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "support.h"

static char g_tmp[64];

static int setup(void **st) {
    (void)st;
    return tmp_folder(g_tmp, sizeof g_tmp, "sbbad");
}

static int teardown(void **st) {
    (void)st;
    return tmp_remove(g_tmp);
}

static void test_truncated_glb(void **st) {
    (void)st;
    char f[256];
    snprintf(f, sizeof f, "%s/trunc.glb", g_tmp);
    copy_bundled("towers.glb", f);
    assert_int_equal(truncate(f, 5000), 0);
    expect_cli_fail("trunc.glb", "%s run %s plane-box sm --frames 1 --out %s/x", test_binary(), f, g_tmp);
    assert_int_equal(truncate(f, 10), 0);
    expect_cli_fail("trunc.glb", "%s run %s plane-box sm --frames 1 --out %s/x", test_binary(), f, g_tmp);
}

static void test_nan_vertex(void **st) {
    (void)st;
    char f[256];
    snprintf(f, sizeof f, "%s/nan.glb", g_tmp);
    copy_bundled("plane-box.glb", f);
    /* the first float of the BIN chunk is mesh 0's first POSITION x */
    FILE *fp = fopen(f, "r+b");
    assert_non_null(fp);
    uint32_t hdr[5];
    assert_int_equal(fread(hdr, 4, 5, fp), 5);
    long bin = 20 + (long)hdr[3] + 8;
    float nan = NAN;
    fseek(fp, bin, SEEK_SET);
    fwrite(&nan, 4, 1, fp);
    fclose(fp);
    expect_cli_fail("nan.glb: /meshes/0/primitives/0/attributes/POSITION: element 0 is NaN", "%s run %s plane-box sm --frames 1 --out %s/x",
                test_binary(), f, g_tmp);
}

static void test_bad_index(void **st) {
    (void)st;
    char f[256];
    snprintf(f, sizeof f, "%s/idx.glb", g_tmp);
    copy_bundled("plane-box.glb", f);
    /* mesh 0 indices follow its 24 positions and 24 normals */
    FILE *fp = fopen(f, "r+b");
    uint32_t hdr[5];
    assert_int_equal(fread(hdr, 4, 5, fp), 5);
    long bin = 20 + (long)hdr[3] + 8;
    uint32_t bad = 9999;
    fseek(fp, bin + 24 * 24 + 4 * 5, SEEK_SET);
    fwrite(&bad, 4, 1, fp);
    fclose(fp);
    expect_cli_fail("idx.glb: /meshes/0/primitives/0/indices: index 9999 at 5 is out of range (24 vertices)",
                "%s run %s plane-box sm --frames 1 --out %s/x", test_binary(), f, g_tmp);
}

static void test_unknown_parameter(void **st) {
    (void)st;
    expect_cli_fail("sm: unknown parameter 'rez' (valid: res, depth, bias, slope, normal, filter, sun_size, stable, format, blur, bleed, exponent)",
                "%s run plane-box plane-box sm:rez=2 --out %s/x", test_binary(), g_tmp);
    expect_cli_fail("unknown technique 'smm'", "%s run plane-box plane-box smm --out %s/x", test_binary(), g_tmp);
    /* rejected before anything is written */
    char dir[300];
    snprintf(dir, sizeof dir, "%s/x", g_tmp);
    assert_int_not_equal(access(dir, F_OK), 0);
}

static void test_malformed_path(void **st) {
    (void)st;
    char f[256];
    snprintf(f, sizeof f, "%s/bad.path", g_tmp);
    FILE *fp = fopen(f, "w");
    fprintf(fp, "fov 60\nlook 0  0 5 10  0 0 0\nlook 1  5 5 1O  0 0 0\n");
    fclose(fp);
    expect_cli_fail("bad.path:3: '1O' is not a finite number", "%s run plane-box %s sm --out %s/x", test_binary(), f, g_tmp);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truncated_glb),     cmocka_unit_test(test_nan_vertex),
        cmocka_unit_test(test_bad_index),         cmocka_unit_test(test_unknown_parameter),
        cmocka_unit_test(test_malformed_path),
    };
    return cmocka_run_group_tests_name("badinput", tests, setup, teardown);
}
