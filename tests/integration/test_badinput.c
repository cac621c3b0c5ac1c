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

#include "commands.h"
#include "support.h"

#include <sys/stat.h>


SB_TEST_SCRATCH("sbbad")

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

/* An unused accessor whose componentType is beyond any int: left out with a note, as every unused object is. The
 * fuzzer's find: the loader converted it to an int before anything refused it, undefined (UBSan, suite loader). */
static void test_unused_number_beyond_int(void **st) {
    (void)st;
    char f[256];
    snprintf(f, sizeof f, "%s/huge.gltf", g_tmp);
    FILE *fp = fopen(f, "w");
    assert_non_null(fp);
    fputs("{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
          "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
          "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
          "{\"bufferView\":0,\"componentType\":518446744073709551616123,\"count\":3,\"type\":\"SCALAR\"}],"
          "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"buffers\":[{\"byteLength\":36,\"uri\":"
          "\"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}", fp);
    fclose(fp);
    char out[8192];
    assert_int_equal(run_logged(out, sizeof out, "%s info %s", test_binary(), f), 0);
    assert_non_null(strstr(out, "/accessors/1/componentType: 518446744073709551616123 is too large (beyond 2^64 - 1) "
                                "(nothing reads this accessor)"));
    assert_non_null(strstr(out, "triangles: 1 in 1 draws"));
}

static void test_unknown_parameter(void **st) {
    (void)st;
    expect_cli_fail("sm: unknown parameter 'rez' (valid: res, depth, bias, slope, normal, filter, sun_size, stable, format, blur, bleed, exponent, distance)",
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

static void write_text(const char *path, const char *text) {
    FILE *fp = fopen(path, "w");
    assert_non_null(fp);
    fputs(text, fp);
    fclose(fp);
}

/* Every command, with each kind of bad input it can get: an unknown option, an
 * option of another command, a value out of range, a missing file, a
 * malformed file. Each is exit 2 and one line naming the option or the file. */
static void test_every_command_exit_2(void **st) {
    (void)st;
    const char *b = test_binary(), *t = g_tmp;
    char glb[256], path[256], bench[256], csvdir[256], hist[256];
    snprintf(glb, sizeof glb, "%s/broken.glb", t);
    write_text(glb, "glTF this is no binary glTF");
    snprintf(path, sizeof path, "%s/typo.path", t);
    write_text(path, "fov 60\nlook 0 0 5 10 0 0 0\nlok 1 5 5 1 0 0 0\n");
    snprintf(bench, sizeof bench, "%s/typo.bench", t);
    write_text(bench, "scene a plane-box\ndefaults --frames 4\nsm:rez=2\n");
    snprintf(csvdir, sizeof csvdir, "%s/set", t);
    mkdir(csvdir, 0755);
    char sum[300];
    snprintf(sum, sizeof sum, "%s/summary.csv", csvdir);
    write_text(sum, "run_id,scene\n\"unterminated\n");
    snprintf(hist, sizeof hist, "%s/not.sqlite", t);
    write_text(hist, "this is not an SQLite database, not even close to one, padded past its header size.....");
    /* options: unknown, another command's, out of range */
    for (int c = 0; c < SB_CMD_COUNT; c++) {
        const char *cmd = sb_commands[c].name;
        char want[128];
        snprintf(want, sizeof want, "%s: unknown option --nope", cmd);
        expect_cli_fail(want, "%s %s --nope 1", b, cmd);
        const char *foreign = c == SB_CMD_COMPARE ? "--frames 3" : "--pair technique=a,b";
        snprintf(want, sizeof want, "is not an option of %s", cmd);
        expect_cli_fail(want, "%s %s %s", b, cmd, foreign);
        for (int i = 0; i < sb_option_count; i++) { /* the first ranged option the command takes */
            const sb_option *o = &sb_options[i];
            if (!sb_option_taken(o, &sb_commands[c]) || (o->kind != SB_OPT_INT && o->kind != SB_OPT_NUM) || isinf(o->max)) continue;
            char v[64], head[128];
            snprintf(v, sizeof v, "%.15g", o->max * 2 + 1);
            snprintf(head, sizeof head, "%s %s: expected", o->name, v);
            expect_cli_fail(head, "%s %s %s %s", b, cmd, o->name, v);
            break;
        }
    }
    /* files: missing, then malformed */
    expect_cli_fail("nosuch.glb", "%s run %s/nosuch.glb auto sm --out %s/x", b, t, t);
    expect_cli_fail("broken.glb", "%s run %s auto sm --out %s/x", b, glb, t);
    expect_cli_fail("nosuch.path", "%s run plane-box %s/nosuch.path sm --out %s/x", b, t, t);
    expect_cli_fail("typo.path:3", "%s run plane-box %s sm --out %s/x", b, path, t);
    expect_cli_fail("nosuch.bench", "%s batch %s/nosuch.bench --out %s/x", b, t, t);
    expect_cli_fail("typo.bench:3", "%s batch %s --out %s/x", b, bench, t);
    expect_cli_fail("nosuch", "%s compare %s/nosuch %s", b, t, csvdir);
    expect_cli_fail("summary.csv", "%s compare %s %s", b, csvdir, csvdir);
    expect_cli_fail("summary.csv", "%s compare %s --pair technique=sm,pssm", b, csvdir);
    expect_cli_fail("nosuch", "%s merge %s/nosuch --out %s/m", b, t, t);
    expect_cli_fail("summary.csv", "%s merge %s --out %s/m", b, csvdir, t);
    expect_cli_fail("nosuch.glb", "%s tune %s/nosuch.glb --max-err 0.1 --out %s/x", b, t, t);
    expect_cli_fail("broken.glb", "%s tune %s --max-err 0.1 --out %s/x", b, glb, t);
    expect_cli_fail("nosuchcase", "%s stress nosuchcase", b);
    expect_cli_fail("smm", "%s stress all smm", b);
    expect_cli_fail("nosuch", "%s history add %s/nosuch --history %s/h.sqlite", b, t, t);
    expect_cli_fail("summary.csv", "%s history add %s --history %s/h.sqlite", b, csvdir, t);
    expect_cli_fail("nosuch.sqlite", "%s history list --history %s/nosuch.sqlite", b, t);
    expect_cli_fail("not.sqlite", "%s history regressions --history %s", b, hist);
    expect_cli_fail("nosuch.sqlite", "%s report --history %s/nosuch.sqlite --out %s/site", b, t, t);
    expect_cli_fail("not.sqlite", "%s report --history %s --out %s/site", b, hist, t);
    expect_cli_fail("nosuch", "%s report %s/nosuch --out %s/site", b, t, t);
    expect_cli_fail("summary.csv", "%s report %s --out %s/site", b, csvdir, t);
    expect_cli_fail("nosuch.glb", "%s info %s/nosuch.glb", b, t);
    expect_cli_fail("broken.glb", "%s info %s", b, glb);
    expect_cli_fail("nosuch.path", "%s path %s/nosuch.path", b, t);
    expect_cli_fail("typo.path:3", "%s path %s", b, path);
    /* operands a command does not take */
    expect_cli_fail("usage: shadowbench techniques", "%s techniques extra", b);
    expect_cli_fail("usage: shadowbench columns", "%s columns extra", b);
    expect_cli_fail("unknown command 'rnu'", "%s rnu plane-box", b);
    /* nothing was written by any of them */
    char x[300];
    snprintf(x, sizeof x, "%s/x", t);
    assert_int_not_equal(access(x, F_OK), 0);
}

/* A name every result holds is one line of text (issue 65): a scene file named with an escape sequence, and a batch
 * scene name holding one, are refused before anything runs, the refusal showing the byte as \\x1b (never the raw
 * sequence, which rewrote the terminal in compare's table). */
static void test_names_refused(void **st) {
    (void)st;
    const char *b = test_binary(), *t = g_tmp;
    char esc[256], bench[256];
    snprintf(esc, sizeof esc, "%s/a\x1b[31mb.glb", t);
    copy_bundled("plane-box.glb", esc);
    const char *out = expect_cli_fail("its name (the scene column of every result) holds a control character (byte 27 "
                                      "at 1)", "%s run '%s' plane-box sm --frames 2 --out %s/names", b, esc, t);
    assert_non_null(strstr(out, "a\\x1b[31mb.glb"));
    assert_null(strchr(out, 0x1b));
    snprintf(bench, sizeof bench, "%s/esc.bench", t);
    write_text(bench, "scene pb\x1b]0;title\x07 plane-box\nsm\n");
    expect_cli_fail("esc.bench:1: the scene's name holds a control character (byte 27 at 2)", "%s batch %s --out %s/names",
                    b, bench, t);
    char names[300];
    snprintf(names, sizeof names, "%s/names", t);
    assert_int_not_equal(access(names, F_OK), 0);
}

/* A spot light (or a sun) whose node scales its -Z to 0 points nowhere: it lit nothing and a run scored err_rate 0,
 * status ok. Left out with its place, in info and every run's warnings; a point light there keeps its place. */
static void test_light_without_direction(void **st) {
    (void)st;
    char file[300];
    snprintf(file, sizeof file, "%s/spot0.gltf", g_tmp);
    write_text(file, "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_lights_punctual\"],"
                     "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\",\"intensity\":9,\"spot\":{}},"
                     "{\"type\":\"point\",\"intensity\":9}]}},\"scene\":0,\"scenes\":[{\"nodes\":[0,1,2]}],"
                     "\"nodes\":[{\"mesh\":0},{\"translation\":[0,2,0],\"scale\":[0,0,0],"
                     "\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}},{\"translation\":[0,2,0],\"scale\":[0,0,0],"
                     "\"extensions\":{\"KHR_lights_punctual\":{\"light\":1}}}],"
                     "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                     "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;base64,"
                     "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
                     "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                     "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
                     "\"min\":[0,0,0],\"max\":[1,1,0]}]}");
    char out[8192];
    assert_int_equal(run_logged(out, sizeof out, "SB_SCENE_CACHE=off %s info %s", test_binary(), file), 0);
    assert_non_null(strstr(out, "/nodes/1: its spot light 0 has no direction (the node's world transform scales its -Z "
                                "to 0)"));
    assert_non_null(strstr(out, "lights: 1"));   /* the point light kept */
    assert_null(strstr(out, "/nodes/2:"));
}

/* A skin's rules the loader holds a real file to (conf-skin.glb, one rule broken each): a joint listed twice (glTF's
 * uniqueItems) and a negative weight were played without a word; each is refused with its place, exit 2. */
static void test_skin_rules(void **st) {
    (void)st;
    const char *edits[][2] = {
        {"doc[\"skins\"][0][\"joints\"] = [1, 1]", "/skins/0/joints/1: node 1 is listed twice (a skin's joints are unique)"},
        {"f32(doc[\"meshes\"][1][\"primitives\"][0][\"attributes\"][\"WEIGHTS_0\"], 5, [1.25, -0.25, 0, 0])",
         "/meshes/1/primitives/0/attributes/WEIGHTS_0: weight 1 of vertex 5 is -0.25 (glTF: joint weights are not negative)"},
    };
    for (int i = 0; i < 2; i++) {
        char out[8192], file[300];
        snprintf(file, sizeof file, "%s/skin%d.glb", g_tmp, i);
        assert_int_equal(run_logged(out, sizeof out, "python3 %s/tests/support/glb_edit.py %s/conf-skin.glb %s '%s'",
                                    getenv("SB_SOURCE_ROOT"), getenv("SB_DATA_DIR"), file, edits[i][0]), 0);
        expect_cli_fail(edits[i][1], "SB_SCENE_CACHE=off %s info %s", test_binary(), file);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truncated_glb),     cmocka_unit_test(test_nan_vertex),
        cmocka_unit_test(test_bad_index),         cmocka_unit_test(test_unknown_parameter),
        cmocka_unit_test(test_unused_number_beyond_int),
        cmocka_unit_test(test_malformed_path),    cmocka_unit_test(test_every_command_exit_2),
        cmocka_unit_test(test_names_refused),     cmocka_unit_test(test_light_without_direction),
        cmocka_unit_test(test_skin_rules),
    };
    return cmocka_run_group_tests_name("badinput", tests, setup, teardown);
}
