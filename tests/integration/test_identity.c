/* A results set knows the command that made it, and a run_id names one run:
 *
 * - --resume of another command (another --lights, --anim-speed, another spec) is refused in one line naming
 *   the option and both values, exit 2, the set's bytes untouched; the same command resumes as before; a set
 *   whose meta predates the "set:" lines is refused when its summary holds runs the command does not make.
 * - a spec given twice (in a command, in a batch grid) is run once, one row a run_id.
 * - --lights is one name a set: "01" and "1", "2,0" and "0,2" are one run id; "+1" is no lamp number.
 * - light=K beside --lights, a lamp number past the scene's lamps (light= or --lights), --pose with --anim and
 *   --anim CLIP on a file without clips are each exit 2 in one line.
 * - what plays is in the summary (anim) and in compare's pairing: --anim none, --anim-speed 3 and the default
 *   are three series; naming every clip is the default. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "table.h"

SB_TEST_SCRATCH("sbidentity")

static char g_out[65536];

/* `run SCENE PATH SPECS --frames 2 --size 64x36 ... EXTRA` into OUT/TAG, exit 0 asserted: the folder into dir. */
static void small_run(const char *scene, const char *specs, const char *extra, char *dir, size_t len) {
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run %s %s %s --frames 2 --size 64x36 --warmup 0 "
                                "--error-every 0 --quiet --out %s/runs %s", test_binary(), scene, scene, specs, g_tmp,
                                extra),
                     0);
    snprintf(dir, len, "%s", last_line_of(g_out));
}

static char *slurp(const char *dir, const char *name) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    sb_err err;
    char *t = sb_read_file(path, NULL, &err);
    assert_non_null(t);
    return t;
}

static void test_resume_of_another_command(void **st) {
    (void)st;
    char dir[4096];
    small_run("towers-night", "cube:res=256 dpsm:res=256", "--lights 0,2", dir, sizeof dir);
    char *before = slurp(dir, "summary.csv"), *manifest = slurp(dir, "manifest");
    /* another --lights: refused, naming the option and both values; nothing written */
    const char *o = expect_cli_fail("--lights: the set was made with 0,2, this command gives lamps",
                                    "%s run towers-night towers-night cube:res=256 dpsm:res=256 --frames 2 --size 64x36 "
                                    "--warmup 0 --error-every 0 --quiet --lights lamps --resume %s", test_binary(), dir);
    assert_non_null(strstr(o, "--resume"));
    /* another spec list: the command's words */
    expect_cli_fail("word 4: the set was made with dpsm:res=256, this command gives none",
                    "%s run towers-night towers-night cube:res=256 --frames 2 --size 64x36 --warmup 0 --error-every 0 "
                    "--quiet --lights 0,2 --resume %s", test_binary(), dir);
    /* another size */
    expect_cli_fail("--size: the set was made with 64x36, this command gives 96x54",
                    "%s run towers-night towers-night cube:res=256 dpsm:res=256 --frames 2 --size 96x54 --warmup 0 "
                    "--error-every 0 --quiet --lights 0,2 --resume %s", test_binary(), dir);
    char *after = slurp(dir, "summary.csv"), *manifest2 = slurp(dir, "manifest");
    assert_string_equal(after, before);
    assert_string_equal(manifest2, manifest);   /* still sealed: the refusal touched nothing */
    free(after);
    free(manifest2);
    /* the same command (the lights in another order: the same set) resumes: both runs kept, none rendered */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run towers-night towers-night cube:res=256 dpsm:res=256 "
                                "--frames 2 --size 64x36 --warmup 0 --error-every 0 --lights 2,0 --resume %s",
                                test_binary(), dir),
                     0);
    assert_non_null(strstr(g_out, "2 run(s) complete, 0 to do"));
    after = slurp(dir, "summary.csv");
    assert_string_equal(after, before);
    free(after);
    free(before);
    free(manifest);
    /* a meta whose line is garbage with control bytes (an escape sequence that clears the screen, a bell): the
       refusal shows them as \xNN, never raw (they were printed as they were) */
    assert_int_equal(run_logged(g_out, sizeof g_out, "cp -r %s %s/garbled && sed -i 's/^set: --size .*/set: --size "
                                "\\x1b[2Jx\\x07/' %s/garbled/meta", dir, g_tmp, g_tmp), 0);
    o = expect_cli_fail("--size: the set was made with \\x1b[2Jx\\x07, this command gives 64x36",
                        "%s run towers-night towers-night cube:res=256 dpsm:res=256 --frames 2 --size 64x36 --warmup 0 "
                        "--error-every 0 --quiet --lights 0,2 --resume %s/garbled", test_binary(), g_tmp);
    assert_null(strchr(o, 0x1b));
    assert_null(strchr(o, 0x07));
}

/* tune's folder knows its search: --resume with another bound is refused, nothing written. */
static void test_resume_of_another_search(void **st) {
    (void)st;
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s tune plane-box --max-err 0.05 --techniques sm --size 64x36 "
                                "--frames 3 --quiet --out %s/tune", test_binary(), g_tmp),
                     0);
    char out[4096], dir[4096], cmd[512];
    snprintf(cmd, sizeof cmd, "ls -d %s/tune/tune-plane-box/* | head -1", g_tmp);
    assert_int_equal(run_capture(cmd, out, sizeof out), 0);
    snprintf(dir, sizeof dir, "%s", last_line_of(out));
    char *csv = slurp(dir, "tune.csv");
    expect_cli_fail("--max-err: the set was made with 0.05, this command gives 0.02",
                    "%s tune plane-box --max-err 0.02 --techniques sm --size 64x36 --frames 3 --quiet --resume %s",
                    test_binary(), dir);
    char *after = slurp(dir, "tune.csv");
    assert_string_equal(after, csv);
    free(after);
    free(csv);
}

/* A set written before meta said what made it: its summary's runs decide. */
static void test_resume_of_an_older_set(void **st) {
    (void)st;
    char dir[4096], cmd[8192];
    small_run("plane-box", "sm:res=512", "", dir, sizeof dir);
    snprintf(cmd, sizeof cmd, "sed -i '/^set: /d' %s/meta", dir);
    assert_int_equal(system(cmd), 0);
    expect_cli_fail("holds 1 run(s) this command does not make",
                    "%s run plane-box plane-box sm:res=1024 --frames 2 --size 64x36 --warmup 0 --error-every 0 --quiet "
                    "--resume %s", test_binary(), dir);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run plane-box plane-box sm:res=512 --frames 2 --size 64x36 "
                                "--warmup 0 --error-every 0 --resume %s", test_binary(), dir),
                     0);
    assert_non_null(strstr(g_out, "1 run(s) complete, 0 to do"));
}

static void test_a_run_given_twice(void **st) {
    (void)st;
    char dir[4096];
    small_run("plane-box", "sm sm:res=2048 pssm:res=512,512", "", dir, sizeof dir);
    sb_table t;
    summary_table(dir, &t);
    assert_int_equal(t.nrows, 2);   /* sm (res=2048 is its default) and pssm:res=512, once each */
    assert_string_not_equal(sb_table_get(&t, 0, "run_id"), sb_table_get(&t, 1, "run_id"));
    sb_table_free(&t);
    /* a batch's grid naming a value twice */
    char bench[4200];
    snprintf(bench, sizeof bench, "%s/twice.bench", g_tmp);
    FILE *f = fopen(bench, "w");
    assert_non_null(f);
    fprintf(f, "scene plane-box plane-box\ndefaults --frames 2 --size 64x36 --warmup 0 --error-every 0\n"
               "sm:res=512,512\nsm:res=512\n");
    fclose(f);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s batch %s --out %s/batch", test_binary(), bench, g_tmp), 0);
    assert_non_null(strstr(g_out, "run once"));
    summary_table(last_line_of(g_out), &t);
    assert_int_equal(t.nrows, 1);
    sb_table_free(&t);
    /* the batch file edited since: its set is another command's */
    char set[4096];
    snprintf(set, sizeof set, "%s", last_line_of(g_out));
    f = fopen(bench, "a");
    assert_non_null(f);
    fprintf(f, "sm:res=1024\n");
    fclose(f);
    expect_cli_fail("batch-file-checksum: the set was made with", "%s batch %s --resume %s --quiet", test_binary(), bench,
                    set);
}

/* The run_id of `run towers-night ... cube:res=256 EXTRA`. */
static void id_of(const char *extra, char *id) {
    char dir[4096];
    small_run("towers-night", "cube:res=256", extra, dir, sizeof dir);
    sb_table t;
    summary_table(dir, &t);
    assert_int_equal(t.nrows, 1);
    snprintf(id, 17, "%s", sb_table_get(&t, 0, "run_id"));
    print_message("%s: %s (light '%s')\n", extra, id, sb_table_get(&t, 0, "light"));
    sb_table_free(&t);
}

static void test_lights_one_name_a_set(void **st) {
    (void)st;
    char a[17], b[17], c[17], d[17], e[17];
    id_of("--lights 1", a);
    id_of("--lights 01", b);
    id_of("--lights 0,2", c);
    id_of("--lights 2,0", d);
    id_of("--lights 0,1,2,3,4,5", e);
    assert_string_equal(a, b);
    assert_string_equal(c, d);
    assert_string_not_equal(a, c);
    char f[17];
    id_of("--lights lamps", f);
    assert_string_equal(e, f);   /* every lamp listed is `lamps` */
    expect_cli_fail("'+1' is not sun, lamps, all or a lamp number",
                    "%s run towers-night towers-night cube --frames 1 --size 64x36 --lights +1 --quiet --out %s/x",
                    test_binary(), g_tmp);
    expect_cli_fail("' 1' is not sun, lamps, all or a lamp number",
                    "%s run towers-night towers-night cube --frames 1 --size 64x36 --lights ' 1' --quiet --out %s/x",
                    test_binary(), g_tmp);
}

static void test_contradictions_refused(void **st) {
    (void)st;
    expect_cli_fail("cube:light=1 with --lights 0,2: both say which lights the run shadows",
                    "%s run towers-night towers-night cube:light=1 --frames 1 --size 64x36 --lights 0,2 --quiet "
                    "--out %s/x", test_binary(), g_tmp);
    expect_cli_fail("cube:light=10: the scene has no lamp 10 (its point and spot lights are 0..5)",
                    "%s run towers-night towers-night cube:light=10 --frames 1 --size 64x36 --quiet --out %s/x",
                    test_binary(), g_tmp);
    expect_cli_fail("the scene has no lamp 10 (its point and spot lights are 0..5)",
                    "%s run towers-night towers-night cube --frames 1 --size 64x36 --lights 10 --quiet --out %s/x",
                    test_binary(), g_tmp);
    char bench[4200];
    snprintf(bench, sizeof bench, "%s/lamp10.bench", g_tmp);
    FILE *f = fopen(bench, "w");
    assert_non_null(f);
    fprintf(f, "scene night towers-night\ndefaults --frames 1 --size 64x36\ndpsm:light=10\n");
    fclose(f);
    expect_cli_fail("lamp10.bench:3: scene night: dpsm:light=10: the scene has no lamp 10", "%s batch %s --out %s/x",
                    test_binary(), bench, g_tmp);
    expect_cli_fail("--anim and --pose: give one of them",
                    "%s run movers movers sm --frames 1 --size 64x36 --pose 1 --anim slide --quiet --out %s/x",
                    test_binary(), g_tmp);
    expect_cli_fail("--anim slide,slide: clip slide named twice",
                    "%s run movers movers sm --frames 1 --size 64x36 --anim slide,slide --quiet --out %s/x", test_binary(),
                    g_tmp);
    expect_cli_fail("--anim slide: the file has no animation clip",
                    "%s run plane-box plane-box sm --frames 1 --size 64x36 --anim slide --quiet --out %s/x",
                    test_binary(), g_tmp);
}

/* The anim column and run id of `run movers ... sm EXTRA`. */
static void anim_of(const char *extra, char *dir, char *id, char *anim) {
    small_run("movers", "sm:res=512", extra, dir, 4096);
    sb_table t;
    summary_table(dir, &t);
    snprintf(id, 17, "%s", sb_table_get(&t, 0, "run_id"));
    snprintf(anim, 64, "%s", sb_table_get(&t, 0, "anim"));
    sb_table_free(&t);
}

static void test_what_plays_is_a_series(void **st) {
    (void)st;
    char d0[4096], d1[4096], d2[4096], d3[4096], i0[17], i1[17], i2[17], i3[17], a0[64], a1[64], a2[64], a3[64];
    anim_of("", d0, i0, a0);
    anim_of("--anim none", d1, i1, a1);
    anim_of("--anim-speed 3", d2, i2, a2);
    anim_of("--anim turn,slide", d3, i3, a3);   /* every clip named: the default */
    assert_string_equal(a0, "");
    assert_string_equal(a1, "none");
    assert_string_equal(a2, "all x3");
    assert_string_equal(a3, "");
    assert_string_equal(i3, i0);
    assert_string_not_equal(i1, i0);
    assert_string_not_equal(i2, i0);
    /* compare pairs runs of the same animation only: none here, said in one line */
    expect_cli_fail("match", "%s compare %s %s", test_binary(), d0, d2);
    expect_cli_fail("same scene, path, technique, parameters, light, animation and run options", "%s compare %s %s", test_binary(),
                    d0, d1);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s compare %s %s --metric shadow_draw_calls", test_binary(), d0,
                                d3),
                     0);
    assert_non_null(strstr(g_out, "1 run(s) matched"));
}

/* compare --pair (and the report's pairs) never pair runs of other lights: a set with a --lights section beside
 * the plain runs pairs only the runs of one light. */
static void test_pairs_keep_their_lights(void **st) {
    (void)st;
    char bench[4200];
    snprintf(bench, sizeof bench, "%s/pairs.bench", g_tmp);
    FILE *f = fopen(bench, "w");
    assert_non_null(f);
    fprintf(f, "scene night towers-night towers-night\npath towers-night towers-night\n"
               "defaults --frames 2 --warmup 0 --size 64x36 --error-every 0\ncube:res=256:layered=off\n"
               "cube:res=256:layered=on --lights 0,1\ncube:res=256:layered=on\n");
    fclose(f);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s batch %s --out %s/pairs --quiet", test_binary(), bench, g_tmp), 0);
    char set[4096];
    snprintf(set, sizeof set, "%s", last_line_of(g_out));
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s compare %s --pair layered=off,on", test_binary(), set), 0);
    assert_non_null(strstr(g_out, "1 pair(s) layered=on against layered=off"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_resume_of_another_command),
        cmocka_unit_test(test_resume_of_an_older_set),
        cmocka_unit_test(test_resume_of_another_search),
        cmocka_unit_test(test_a_run_given_twice),
        cmocka_unit_test(test_lights_one_name_a_set),
        cmocka_unit_test(test_contradictions_refused),
        cmocka_unit_test(test_what_plays_is_a_series),
        cmocka_unit_test(test_pairs_keep_their_lights),
    };
    return cmocka_run_group_tests_name("identity", tests, setup, teardown);
}
