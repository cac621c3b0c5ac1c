/* The optional parts of a build (meson -Dosmesa, -Dimages): present, they
 * work; absent, the binary says so in one line and links nothing of them.
 * scripts/test runs this suite in the default build (both present) and in
 * the sanitizer build, configured as a GPU machine's (both disabled). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <glob.h>

#include "support.h"
#include "table.h"

static char g_out[16384];

#define sh(...) run_logged(g_out, sizeof g_out, __VA_ARGS__)

SB_TEST_SCRATCH("sbfeat")

/* The first line of the last command's output: the results folder. */
static void out_dir(char *dir, size_t len) {
    size_t n = strcspn(g_out, "\n");
    assert_true(n < len);
    memcpy(dir, g_out, n);
    dir[n] = 0;
}

/* A PNG's IHDR: width, height, bit depth, colour type (0 grey, 2 RGB, 6 RGBA). */
static void expect_png(const char *path, int w, int h, int color_type) {
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    unsigned char b[32];
    assert_int_equal(fread(b, 1, sizeof b, f), sizeof b);
    fclose(f);
    assert_memory_equal(b, "\x89PNG\r\n\x1a\n", 8);
    assert_memory_equal(b + 12, "IHDR", 4);
    assert_int_equal((b[16] << 24 | b[17] << 16 | b[18] << 8 | b[19]), w);
    assert_int_equal((b[20] << 24 | b[21] << 16 | b[22] << 8 | b[23]), h);
    assert_int_equal(b[24], 8);
    assert_int_equal(b[25], color_type);
}

static int count(const char *pattern) {
    glob_t g;
    int n = glob(pattern, 0, NULL, &g) == 0 ? (int)g.gl_pathc : 0;
    globfree(&g);
    return n;
}

/* --images K: six files for every K-th frame, none for the others, none half-written. */
static void test_images(void **st) {
    (void)st;
    const char *cmd = "%s run plane-box plane-box sm:res=256 --frames 3 --warmup 0 --size 64x36 --error-every 1 "
                      "--images 2 --quiet --out %s/img";
    if (!SB_HAVE_IMAGES) {
        expect_cli_fail("--images 2: this shadowbench was built without OpenImageIO (meson -Dimages=disabled)", cmd,
                        test_binary(), g_tmp);
        return;
    }
    /* the module is opened on first use: without it, one line and nothing rendered */
    expect_cli_fail("--images 2: the image module cannot be opened: /nonexistent/libsbimages.so",
                    "SB_IMAGE_MODULE=/nonexistent/libsbimages.so %s run plane-box plane-box sm:res=256 --frames 3 "
                    "--warmup 0 --size 64x36 --error-every 1 --images 2 --quiet --out %s/img",
                    test_binary(), g_tmp);
    assert_int_equal(sh(cmd, test_binary(), g_tmp), 0);
    char dir[4096], p[4400];
    out_dir(dir, sizeof dir);
    sb_table t;
    summary_table(dir, &t);
    const char *id = sb_table_get(&t, 0, "run_id");
    const struct {
        const char *kind;
        int type;
    } png[] = {{"color", 6}, {"vis", 0}, {"ref", 0}, {"error", 2}, {"cascades", 2}, {"flicker", 2}};
    for (int f = 0; f <= 2; f += 2)
        for (size_t k = 0; k < sizeof png / sizeof png[0]; k++) {
            snprintf(p, sizeof p, "%s/images/%s_f%04d_%s.png", dir, id, f, png[k].kind);
            expect_png(p, 64, 36, png[k].type);
        }
    snprintf(p, sizeof p, "%s/images/%s_f0002_texel_px.exr", dir, id);
    FILE *f = fopen(p, "rb");
    assert_non_null(f);
    unsigned char magic[4];
    assert_int_equal(fread(magic, 1, 4, f), 4);
    fclose(f);
    assert_memory_equal(magic, "\x76\x2f\x31\x01", 4);
    snprintf(p, sizeof p, "%s/images/*_f0001_*", dir);
    assert_int_equal(count(p), 0);
    snprintf(p, sizeof p, "%s/images/*", dir);
    assert_int_equal(count(p), 14);   /* six PNGs and an EXR a frame */
    snprintf(p, sizeof p, "%s/images/*.tmp*", dir);
    assert_int_equal(count(p), 0);
    sb_table_free(&t);
}

/* --backend osmesa renders on llvmpipe, or says this build has no OSMesa. */
static void test_osmesa(void **st) {
    (void)st;
    const char *cmd = "%s run plane-box plane-box sm:res=256 --frames 2 --warmup 0 --size 64x36 --error-every 0 "
                      "--backend osmesa --quiet --out %s/osm";
    if (!SB_HAVE_OSMESA) {
        expect_cli_fail("built without OSMesa (meson -Dosmesa=disabled)", cmd, test_binary(), g_tmp);
        return;
    }
    assert_int_equal(sh(cmd, test_binary(), g_tmp), 0);
    char dir[4096];
    out_dir(dir, sizeof dir);
    sb_table t;
    summary_table(dir, &t);
    assert_string_equal(sb_table_get(&t, 0, "status"), "ok");
    assert_string_equal(sb_table_get(&t, 0, "backend"), "osmesa");
    assert_non_null(strstr(sb_table_get(&t, 0, "renderer"), "llvmpipe"));
    sb_table_free(&t);
}

/* No GL at all (glvnd finds no EGL vendor): one line and exit 1, no crash
 * tearing down what never opened. */
static void test_no_gl(void **st) {
    (void)st;
    expect_cli_exit(1, "egl: no usable EGL device or platform",
                    "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json %s run plane-box plane-box sm --frames 2 --quiet "
                    "--out %s/nogl",
                    test_binary(), g_tmp);
}

/* libOSMesa (and the LLVM behind it) and OpenImageIO (about 250 libraries)
 * are opened only when asked for, never linked: OpenImageIO through the image
 * module beside the binary, built only with images. */
static void test_linked_libraries(void **st) {
    (void)st;
    /* grep -c prints the count (and exits 1 when it is 0) */
    sh("ldd %s | grep -c -E 'libOSMesa|libLLVM|libOpenImageIO'", test_binary());
    assert_int_equal(atoi(g_out), 0);
    char module[4200];
    snprintf(module, sizeof module, "%s", test_binary());
    snprintf(strrchr(module, '/') + 1, sizeof module - (size_t)(strrchr(module, '/') + 1 - module), "libsbimages.so");
    sh("ldd %s | grep -c libOpenImageIO", module);
    assert_int_equal(atoi(g_out) > 0, SB_HAVE_IMAGES);
    sh("ldd %s | grep -c libEGL", test_binary());
    assert_true(atoi(g_out) > 0); /* the check can see a linked library */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_images),
        cmocka_unit_test(test_osmesa),
        cmocka_unit_test(test_linked_libraries),
        cmocka_unit_test(test_no_gl),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
