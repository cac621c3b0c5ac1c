/* The scripts that write scenes (scripts/add-lamps, place-movers, tile-gltf) follow the tool's own rules
 * (scripts/sbscene.py): OUT equal to IN and an existing OUT without --force are refused with the input's bytes
 * untouched; a .gltf's buffer outside its folder is refused (the loader's rule) unless --allow-external-uris;
 * a missing file, a folder, broken JSON, a non-finite or out-of-range number, an unknown option: one line and
 * exit 2 each, never a traceback and never a half-written file; --help on each; what they write loads (the
 * tool's loader reads it before it is renamed into place). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "support.h"

SB_TEST_SCRATCH("sbscripts")

static char g_out[16384];

static const char *script(const char *name) {
    static char buf[4][4096];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "SHADOWBENCH=%s %s/scripts/%s", test_binary(), getenv("SB_SOURCE_ROOT"), name);
    return buf[k];
}

static long file_size(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

/* No temporary left in the scratch folder (a half-written output). */
static void nothing_half_written(void) {
    char cmd[300];
    snprintf(cmd, sizeof cmd, "ls -a %s | grep -c '\\.part$\\|\\.part\\.glb$\\|\\.tmp$'", g_tmp);
    assert_int_equal(run_capture(cmd, g_out, sizeof g_out), 1);   /* grep -c: 0 lines found, exit 1 */
    assert_int_equal(atoi(g_out), 0);
}

static void test_outputs_never_overwrite(void **st) {
    (void)st;
    char in[4096], out[4096];
    snprintf(in, sizeof in, "%s/pb.glb", g_tmp);
    snprintf(out, sizeof out, "%s/out.glb", g_tmp);
    copy_bundled("plane-box.glb", in);
    long size = file_size(in);
    expect_cli_fail("the output is the input", "%s %s %s --count 2", script("add-lamps"), in, in);
    expect_cli_fail("the output is the input", "%s %s %s/movers.glb 2 %s", script("place-movers"), in,
                    getenv("SB_DATA_DIR"), in);
    expect_cli_fail("the output is the input", "%s %s %s 2", script("tile-gltf"), in, in);
    assert_int_equal(file_size(in), size);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s %s %s --count 2", script("add-lamps"), in, out), 0);
    long first = file_size(out);
    expect_cli_fail("exists (--force writes over it)", "%s %s %s --count 3", script("add-lamps"), in, out);
    expect_cli_fail("exists (--force writes over it)", "%s %s %s/movers.glb 2 %s", script("place-movers"), in,
                    getenv("SB_DATA_DIR"), out);
    expect_cli_fail("exists (--force writes over it)", "%s %s %s 2", script("tile-gltf"), in, out);
    assert_int_equal(file_size(out), first);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s %s %s --count 3 --force", script("add-lamps"), in, out), 0);
    /* what it wrote loads, with its three lamps */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s info %s", test_binary(), out), 0);
    assert_non_null(strstr(g_out, "lights: 4"));   /* the sun and three lamps */
    nothing_half_written();
}

static void test_buffers_stay_in_the_folder(void **st) {
    (void)st;
    char dir[1024], cmd[4096];
    snprintf(dir, sizeof dir, "%s/level", g_tmp);
    snprintf(cmd, sizeof cmd, "mkdir -p %s && head -c 44 /dev/zero > %s/secret.bin && printf '%%s' "
             "'{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"../secret.bin\",\"byteLength\":44}]}' > %s/x.gltf",
             dir, g_tmp, dir);
    assert_int_equal(system(cmd), 0);
    expect_cli_fail("../secret.bin leaves the scene's folder", "%s %s/x.gltf %s/s.glb --count 1 --line 0,0,0:1,1,1",
                    script("add-lamps"), dir, g_tmp);
    expect_cli_fail("../secret.bin leaves the scene's folder", "%s %s/x.gltf %s/movers.glb 1 %s/s.glb",
                    script("place-movers"), dir, getenv("SB_DATA_DIR"), g_tmp);
    expect_cli_fail("../secret.bin leaves the scene's folder", "%s %s/x.gltf %s/s.glb 2", script("tile-gltf"), dir,
                    g_tmp);
    char s_glb[4200];
    snprintf(s_glb, sizeof s_glb, "%s/s.glb", g_tmp);
    assert_int_equal(access(s_glb, F_OK), -1);   /* nothing written */
}

static void test_bad_input_one_line(void **st) {
    (void)st;
    char in[4096], broken[4096];
    snprintf(in, sizeof in, "%s/pb2.glb", g_tmp);
    snprintf(broken, sizeof broken, "%s/broken.gltf", g_tmp);
    copy_bundled("plane-box.glb", in);
    FILE *f = fopen(broken, "w");
    assert_non_null(f);
    fputs("{\"asset\":", f);
    fclose(f);
    const char *lamps = script("add-lamps"), *movers = script("place-movers"), *tile = script("tile-gltf");
    expect_cli_fail("no such file", "%s %s/nope.glb %s/a.glb --count 1", lamps, g_tmp, g_tmp);
    expect_cli_fail("not a file", "%s %s %s/a.glb --count 1", lamps, g_tmp, g_tmp);
    expect_cli_fail("not glTF JSON", "%s %s %s/a.glb --count 1", lamps, broken, g_tmp);
    expect_cli_fail("--range inf: expected a finite number", "%s %s %s/a.glb --count 1 --range inf", lamps, in, g_tmp);
    expect_cli_fail("--height nan: expected a finite number", "%s %s %s/a.glb --count 1 --height nan", lamps, in,
                    g_tmp);
    expect_cli_fail("--count 0: expected a whole number from 1 to 256", "%s %s %s/a.glb --count 0", lamps, in, g_tmp);
    expect_cli_fail("--line start 1e400: expected a finite number", "%s %s %s/a.glb --count 1 --line=1e400,0,0:1,1,1",
                    lamps, in, g_tmp);
    expect_cli_fail("--walk-period 0: a duration above 0", "%s %s %s/movers.glb 1 %s/a.glb --walk-period 0", movers,
                    in, getenv("SB_DATA_DIR"), g_tmp);
    expect_cli_fail("--walk-period nan: expected a finite number", "%s %s %s/movers.glb 1 %s/a.glb --walk-period nan",
                    movers, in, getenv("SB_DATA_DIR"), g_tmp);
    expect_cli_fail("no such file", "%s %s/none %s/movers.glb 1 %s/a.glb", movers, g_tmp, getenv("SB_DATA_DIR"), g_tmp);
    expect_cli_fail("not glTF JSON", "%s %s %s/movers.glb 1 %s/a.glb", movers, broken, getenv("SB_DATA_DIR"), g_tmp);
    expect_cli_fail("unknown option --nope", "%s %s %s/movers.glb 1 %s/a.glb --nope", movers, in, getenv("SB_DATA_DIR"),
                    g_tmp);
    expect_cli_fail("N x: expected a whole number", "%s %s %s/a.glb x", tile, in, g_tmp);
    expect_cli_fail("not glTF JSON", "%s %s %s/a.glb 2", tile, broken, g_tmp);
    nothing_half_written();
    /* --help: exit 0 and the usage */
    const char *names[] = {"add-lamps", "place-movers", "tile-gltf"};
    for (int i = 0; i < 3; i++) {
        assert_int_equal(run_logged(g_out, sizeof g_out, "%s --help", script(names[i])), 0);
        assert_non_null(strstr(g_out, names[i]));
        assert_null(strstr(g_out, "Traceback"));
    }
}

/* What a script writes, the tool loads (issue 65): the output is loaded by the tool's own loader under its
 * temporary name before the rename. A floor at the loader's bound (place-movers wrote a level whose movers stood
 * past 1e12) and a document whose `scene` is -1 (tile-gltf copied it) are refused, nothing written; without a
 * binary a one-line note says the file went unchecked. */
static void test_outputs_load(void **st) {
    (void)st;
    char in[4096], neg[4096], out[4096];
    snprintf(in, sizeof in, "%s/pb3.glb", g_tmp);
    snprintf(neg, sizeof neg, "%s/neg.glb", g_tmp);
    snprintf(out, sizeof out, "%s/loads.glb", g_tmp);
    copy_bundled("plane-box.glb", in);
    expect_cli_fail("loads.glb: not written: the tool would refuse it", "%s %s %s/movers.glb 2 %s --floor 1e12",
                    script("place-movers"), in, getenv("SB_DATA_DIR"), out);
    assert_int_equal(access(out, F_OK), -1);
    assert_int_equal(run_logged(g_out, sizeof g_out,
                                "python3 -c 'import json, struct, sys; d = open(sys.argv[1], \"rb\").read(); "
                                "n = struct.unpack(\"<I\", d[12:16])[0]; j = json.loads(d[20:20 + n]); j[\"scene\"] = -1; "
                                "b = json.dumps(j).encode(); b += b\" \" * (-len(b) %% 4); "
                                "c = struct.pack(\"<II\", len(b), 0x4E4F534A) + b + d[20 + n:]; "
                                "open(sys.argv[2], \"wb\").write(struct.pack(\"<III\", 0x46546C67, 2, 12 + len(c)) + c)' %s %s",
                                in, neg), 0);
    expect_cli_fail("/scene: -1 is negative", "%s %s %s 2", script("tile-gltf"), neg, out);
    assert_int_equal(access(out, F_OK), -1);
    nothing_half_written();
    /* no binary: written, with the note */
    assert_int_equal(run_logged(g_out, sizeof g_out, "SHADOWBENCH=%s/none %s/scripts/tile-gltf %s %s 2", g_tmp,
                                getenv("SB_SOURCE_ROOT"), in, out), 0);
    assert_non_null(strstr(g_out, "not loaded by the tool before writing (no binary at"));
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s info %s", test_binary(), out), 0);
    /* with the mode of any new file (the temporary's 0600 made the scene unreadable to anyone else) */
    mode_t mask = umask(0);
    umask(mask);
    struct stat sto;
    assert_int_equal(stat(out, &sto), 0);
    assert_int_equal(sto.st_mode & 0777, 0666 & ~mask);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_outputs_never_overwrite),
        cmocka_unit_test(test_buffers_stay_in_the_folder),
        cmocka_unit_test(test_bad_input_one_line),
        cmocka_unit_test(test_outputs_load),
    };
    return cmocka_run_group_tests_name("scripts", tests, setup, teardown);
}
