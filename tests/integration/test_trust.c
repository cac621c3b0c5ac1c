/* Nothing wrong served, nothing damaged accepted (issue 47):
 *  - a results set damaged four ways (a per-frame CSV deleted, one cut in half, a summary row removed, the
 *    manifest edited) is refused by history add, compare, report and history check, each naming the file, and
 *    no history file or site is left behind where none was; a set from before manifests reads with a note;
 *  - every kind of bad input the command line gets answers in one line with the exit the table says: a folder
 *    where a file is wanted, an --out that is a file or cannot be made, a --resume folder that is missing or a
 *    file, a parameter with more values than the limit, a grid past --yes's threshold, a bisect run with a typo,
 *    contradictory options; --opt=value and --opt value make the same run;
 *  - a batch over two folders holding same-named scenes with different buffers measures two geometries (the
 *    scene cache keyed by what each load read). */
#define _DEFAULT_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "support.h"
#include "table.h"
#include "util.h"

SB_TEST_SCRATCH("sbtrust")

static char g_out[65536];
#define sh(...) run_logged(g_out, sizeof g_out, __VA_ARGS__)

static bool exists(const char *path) { return access(path, F_OK) == 0; }

/* A small results set: plane-box, two techniques, three frames. */
static void make_set(const char *tag, char *dir, size_t len) {
    assert_int_equal(sh("%s run plane-box plane-box sm:res=256 none --frames 3 --warmup 0 --size 96x54 "
                        "--error-every 1 --quiet --out %s/%s", test_binary(), g_tmp, tag), 0);
    snprintf(dir, len, "%s", last_line_of(g_out));
    char m[4200];
    snprintf(m, sizeof m, "%s/manifest", dir);
    assert_true(exists(m));
}

/* A copy of a set (cp -r), into dir. */
static void copy_set(const char *from, const char *tag, char *dir, size_t len) {
    snprintf(dir, len, "%s/%s", g_tmp, tag);
    assert_int_equal(sh("cp -r %s %s", from, dir), 0);
}

/* The four damages: each leaves a file of the set other than the manifest says, named in the refusal. */
static void damage(const char *dir, int how, char *file, size_t len) {
    sb_table t;
    summary_table(dir, &t);
    const char *id = sb_table_get(&t, 0, "run_id");
    switch (how) {
    case 0:   /* a per-frame CSV deleted */
        snprintf(file, len, "%s/%s.csv", dir, id);
        assert_int_equal(unlink(file), 0);
        break;
    case 1: { /* a per-frame CSV cut in half */
        snprintf(file, len, "%s/%s.csv", dir, id);
        struct stat st;
        assert_int_equal(stat(file, &st), 0);
        assert_int_equal(truncate(file, st.st_size / 2), 0);
        break;
    }
    case 2:   /* a summary row removed */
        snprintf(file, len, "%s/summary.csv", dir);
        assert_int_equal(sh("sed -i '$d' %s", file), 0);
        break;
    default:  /* the manifest edited: a size made to match a cut file */
        snprintf(file, len, "%s/manifest", dir);
        assert_int_equal(sh("sed -i '2s/ [0-9]* / 1 /' %s", file), 0);
    }
    sb_table_free(&t);
}

static void test_damaged_sets_refused(void **st) {
    (void)st;
    char good[4096], hist[4200];
    make_set("good", good, sizeof good);
    snprintf(hist, sizeof hist, "%s/h.sqlite", g_tmp);
    assert_int_equal(sh("%s history add %s --history %s --quiet", test_binary(), good, hist), 0);
    static const char *const names[] = {"deleted", "cut", "row", "manifest"};
    for (int how = 0; how < 4; how++) {
        char dir[4200], file[4400], fresh[4400], site[4400];
        copy_set(good, names[how], dir, sizeof dir);
        damage(dir, how, file, sizeof file);
        const char *base = strrchr(file, '/') + 1;
        print_message("damage: %s (%s)\n", names[how], file);
        snprintf(fresh, sizeof fresh, "%s/new-%s.sqlite", g_tmp, names[how]);
        expect_cli_fail(base, "%s history add %s --history %s", test_binary(), dir, fresh);
        assert_false(exists(fresh));   /* no history file left where none was */
        expect_cli_fail(base, "%s compare %s %s", test_binary(), good, dir);
        expect_cli_fail(base, "%s compare %s --pair technique=sm,none", test_binary(), dir);
        snprintf(site, sizeof site, "%s/site-%s", g_tmp, names[how]);
        expect_cli_fail(base, "%s report %s --out %s", test_binary(), dir, site);
        assert_false(exists(site));
        expect_cli_fail(base, "%s history check %s --history %s", test_binary(), dir, hist);
        expect_cli_fail(base, "%s merge %s --out %s/merged-%s", test_binary(), dir, g_tmp, names[how]);
    }
    /* a set from before manifests: read as it is, with a one-line note */
    char old[4200], m[4400];
    copy_set(good, "old", old, sizeof old);
    snprintf(m, sizeof m, "%s/manifest", old);
    assert_int_equal(unlink(m), 0);
    assert_int_equal(sh("%s compare %s %s --metric err_rate", test_binary(), good, old), 0);
    assert_non_null(strstr(g_out, "has no manifest (a set from before they were written): read as it is"));
    /* the whole set passes everywhere */
    assert_int_equal(sh("%s history check %s --history %s --quiet", test_binary(), good, hist), 0);
}

/* No output over an input (issue 65): report's site and merge's set are folders of their own. A site written into
 * the set it shows (or a merge into one of its inputs) mixed its files with the set's; merge rewrote the set's
 * manifest to list a meta.1 of its own. Each refused by every spelling (.., a symlink, a folder below), the set
 * and history left byte for byte. */
static void test_output_over_input(void **st) {
    (void)st;
    char set[4096], hist[4200], before[256];
    const char *b = test_binary();
    make_set("input", set, sizeof set);
    snprintf(hist, sizeof hist, "%s/over.sqlite", g_tmp);
    assert_int_equal(sh("%s history add %s --history %s --quiet", b, set, hist), 0);
    assert_int_equal(sh("cd %s && cat * %s | cksum", set, hist), 0);
    snprintf(before, sizeof before, "%.200s", g_out);
    assert_int_equal(sh("ln -sfn %s %s/link", set, g_tmp), 0);
    const char *name = strrchr(set, '/') + 1;
    char spell[3][4400];
    snprintf(spell[0], sizeof spell[0], "%s", set);
    snprintf(spell[1], sizeof spell[1], "%s/../%s/./site", set, name);
    snprintf(spell[2], sizeof spell[2], "%s/link/new/deeper", g_tmp);
    for (int i = 0; i < 3; i++) {
        expect_cli_fail("is its input or in it", "%s report %s --out %s", b, set, spell[i]);
        expect_cli_fail("the merge would write over it", "%s merge %s --out %s", b, set, spell[i]);
    }
    expect_cli_fail("is its input or in it", "%s report --history %s --out %s", b, hist, hist);
    /* a merge's output is new: another run's own set is not written over */
    char other[4096];
    make_set("other", other, sizeof other);
    expect_cli_fail("holds a run's own results set", "%s merge %s --out %s", b, set, other);
    assert_int_equal(sh("cd %s && cat * %s | cksum", set, hist), 0);
    assert_string_equal(before, g_out);
    char deeper[4400];
    snprintf(deeper, sizeof deeper, "%s/new", set);
    assert_false(exists(deeper));
    /* and the same commands with a folder of their own go on as before */
    assert_int_equal(sh("%s merge %s --out %s/merged", b, set, g_tmp), 0);
    assert_int_equal(sh("%s report %s/merged --out %s/site", b, g_tmp, g_tmp), 0);
}

/* Every bad input in one line, with the exit status the table says. */
static void test_bad_input_one_line(void **st) {
    (void)st;
    const char *b = test_binary();
    char folder[4200], file[4200];
    snprintf(folder, sizeof folder, "%s/afolder", g_tmp);
    assert_int_equal(mkdir(folder, 0755), 0);
    snprintf(file, sizeof file, "%s/afile", g_tmp);
    FILE *f = fopen(file, "w");
    assert_non_null(f);
    fputs("x\n", f);
    fclose(f);
    /* a folder where a file is wanted */
    expect_cli_fail("afolder: a folder, not a file", "%s run %s plane-box sm --out %s/o", b, folder, g_tmp);
    expect_cli_fail("afolder: a folder, not a file", "%s run plane-box %s sm --out %s/o", b, folder, g_tmp);
    expect_cli_fail("afolder: a folder, not a file", "%s batch %s --out %s/o", b, folder, g_tmp);
    expect_cli_fail("afolder: a folder, not a file", "%s info %s", b, folder);
    /* --out occupied by a file, or under one; --resume missing or a file: before anything runs */
    expect_cli_fail("--out", "%s run plane-box plane-box sm --out %s", b, file);
    expect_cli_fail("is a file, not a folder", "%s run plane-box plane-box sm --out %s/sub", b, file);
    expect_cli_fail("--out", "%s batch docs/tour.bench --out %s", b, file);
    expect_cli_fail("--resume", "%s run plane-box plane-box sm --resume %s/nosuch", b, g_tmp);
    expect_cli_fail("no such results folder", "%s tune plane-box --max-err 0.1 --resume %s/nosuch", b, g_tmp);
    expect_cli_fail("--resume", "%s batch docs/tour.bench --resume %s", b, file);
    /* limits named; a grid past the threshold said with its size, started only with --yes */
    expect_cli_fail("at most 16", "%s run plane-box plane-box sm:res=64,65,66,67,68,69,70,71,72,73,74,75,76,77,78,79,80 "
                    "--out %s/o", b, g_tmp);
    const char *said = expect_cli_fail("--yes", "%s run plane-box plane-box sm:res=64,65,66,67,68,69,70,71,72,73,74,"
                                       "75,76,77,78,79:bias=1,2,3,4,5,6,7,8:slope=0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15 "
                                       "--out %s/o", b, g_tmp);
    assert_non_null(strstr(said, "2048 runs"));
    /* contradictory options */
    expect_cli_fail("--quiet and --verbose", "%s columns --quiet --verbose", b);
    /* a history subcommand takes only its own options */
    expect_cli_fail("history list: --accept is not an option of history list", "%s history list --accept", b);
    expect_cli_fail("is not an option of history add", "%s history add x --since 2026-01-01", b);
    expect_cli_fail("is not an option of history regressions", "%s history regressions --series x", b);
    /* bisect: a typo in its run, and an unknown metric, before anything builds */
    expect_cli_fail("--framse", "%s bisect HEAD~1 HEAD -- run plane-box plane-box sm --framse 3", b);
    expect_cli_fail("unknown parameter 'rez'", "%s bisect HEAD~1 HEAD -- run plane-box plane-box sm:rez=2", b);
    expect_cli_fail("unknown metric 'gpu_sm'", "%s bisect HEAD~1 HEAD --metric gpu_sm -- run plane-box plane-box sm", b);
    /* nothing was written by any of them */
    char o[4300];
    snprintf(o, sizeof o, "%s/o", g_tmp);
    assert_false(exists(o));
}

/* --opt=value and --opt value: the same run (its id, its figures). */
static void test_equals_spelling(void **st) {
    (void)st;
    char a[4096], c[4096];
    assert_int_equal(sh("%s run plane-box plane-box sm --frames 2 --warmup 0 --size 64x36 --error-every 1 --quiet "
                        "--out %s/eq1", test_binary(), g_tmp), 0);
    snprintf(a, sizeof a, "%s", last_line_of(g_out));
    assert_int_equal(sh("%s run plane-box plane-box sm --frames=2 --warmup=0 --size=64x36 --error-every=1 --quiet "
                        "--out=%s/eq2", test_binary(), g_tmp), 0);
    snprintf(c, sizeof c, "%s", last_line_of(g_out));
    sb_table ta, tc;
    summary_table(a, &ta);
    summary_table(c, &tc);
    assert_string_equal(sb_table_get(&ta, 0, "run_id"), sb_table_get(&tc, 0, "run_id"));
    assert_string_equal(sb_table_get(&ta, 0, "err_rate_mean"), sb_table_get(&tc, 0, "err_rate_mean"));
    sb_table_free(&ta);
    sb_table_free(&tc);
}

/* A .gltf with a ground quad and a box whose height the .bin holds (positions, then indices). */
static void write_box_scene(const char *dir, double height) {
    char path[4400];
    snprintf(path, sizeof path, "%s/scene.gltf", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
          "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
          "\"buffers\":[{\"byteLength\":216,\"uri\":\"scene.bin\"}],"
          "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":144},"
          "{\"buffer\":0,\"byteOffset\":144,\"byteLength\":72}],"
          "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":12,\"type\":\"VEC3\"},"
          "{\"bufferView\":1,\"componentType\":5123,\"count\":36,\"type\":\"SCALAR\"}]}\n", f);
    fclose(f);
    /* 4 ground corners, 8 box corners (a 2 x h x 2 box at the origin); the quad and the box's 5 visible faces
       (its bottom on the ground left out: 10 triangles + 2) = 12 triangles, 36 indices */
    float v[36] = {-20, 0, -20, 20, 0, -20, 20, 0, 20, -20, 0, 20};
    float h = (float)height;
    float box[24] = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1, -1, h, -1, 1, h, -1, 1, h, 1, -1, h, 1};
    memcpy(v + 12, box, sizeof box);
    uint16_t idx[36] = {0, 2, 1, 0, 3, 2,                          /* ground, facing up */
                        8, 10, 9, 8, 11, 10,                       /* top */
                        4, 5, 9, 4, 9, 8, 5, 6, 10, 5, 10, 9,      /* sides */
                        6, 7, 11, 6, 11, 10, 7, 4, 8, 7, 8, 11};
    snprintf(path, sizeof path, "%s/scene.bin", dir);
    f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(v, sizeof v, 1, f), 1);
    assert_int_equal(fwrite(idx, sizeof idx, 1, f), 1);
    fclose(f);
}

/* Two folders with the same scene file beside different buffers, in one batch (and the scene cache on): two
 * geometries measured, each its own; `info` says each one's size. */
static void test_same_name_two_folders(void **st) {
    (void)st;
    char a[4200], c[4200], cache[4200], bench[4300];
    snprintf(a, sizeof a, "%s/a", g_tmp);
    snprintf(c, sizeof c, "%s/b", g_tmp);
    snprintf(cache, sizeof cache, "%s/cache", g_tmp);
    assert_int_equal(mkdir(a, 0755), 0);
    assert_int_equal(mkdir(c, 0755), 0);
    write_box_scene(a, 2);
    write_box_scene(c, 10);
    for (int pass = 0; pass < 2; pass++)   /* the second from the cache */
        for (int k = 0; k < 2; k++) {
            assert_int_equal(sh("SB_SCENE_CACHE=%s %s info %s/scene.gltf", cache, test_binary(), k ? c : a), 0);
            assert_non_null(strstr(g_out, k ? "40 x 10 x 40" : "40 x 2 x 40"));
        }
    snprintf(bench, sizeof bench, "%s/two.bench", g_tmp);
    FILE *f = fopen(bench, "w");
    assert_non_null(f);
    fprintf(f, "path o orbit\nscene low %s/scene.gltf o\nscene high %s/scene.gltf o\ndefaults --frames 2 --warmup 0 "
               "--size 96x54 --error-every 1 --sun 30,40\nraycast\n", a, c);
    fclose(f);
    assert_int_equal(sh("SB_SCENE_CACHE=%s %s batch %s --out %s/two --quiet", cache, test_binary(), bench, g_tmp), 0);
    sb_table t, fa, fb;
    summary_table(last_line_of(g_out), &t);
    assert_int_equal(t.nrows, 2);
    assert_string_not_equal(sb_table_get(&t, 0, "run_id"), sb_table_get(&t, 1, "run_id"));
    char dir[4200];
    snprintf(dir, sizeof dir, "%s", last_line_of(g_out));
    frames_table(dir, &t, 0, &fa);
    frames_table(dir, &t, 1, &fb);
    /* the taller box shades more of the ground: fewer lit-facing pixels to evaluate */
    print_message("eval_pixels: low %ld, high %ld\n", table_int(&fa, 0, "eval_pixels"), table_int(&fb, 0, "eval_pixels"));
    assert_true(table_int(&fa, 0, "eval_pixels") != table_int(&fb, 0, "eval_pixels"));
    sb_table_free(&fa);
    sb_table_free(&fb);
    sb_table_free(&t);
    /* what the cache read, held to the load's rules: its entry a FIFO (it blocked in open() for ever) is a miss, a
       dependency made a FIFO or a link out of the folder (same bytes) is refused as the uncached load refuses it */
    assert_int_equal(sh("cd %s && for e in *.sbscene; do rm $e && mkfifo $e; done", cache), 0);
    assert_int_equal(sh("SB_SCENE_CACHE=%s timeout -s KILL 30 %s info %s/scene.gltf", cache, test_binary(), a), 0);
    assert_non_null(strstr(g_out, "40 x 2 x 40"));
    assert_int_equal(sh("cd %s && cp scene.bin %s/outside.bin && mv scene.bin kept.bin && ln -s %s/outside.bin scene.bin",
                        a, g_tmp, g_tmp), 0);
    assert_int_equal(sh("SB_SCENE_CACHE=%s %s info %s/scene.gltf", cache, test_binary(), c), 0);   /* b untouched */
    expect_cli_fail("outside the scene's folder", "SB_SCENE_CACHE=%s %s info %s/scene.gltf", cache, test_binary(), a);
    assert_int_equal(sh("cd %s && rm scene.bin && mkfifo scene.bin", a), 0);
    expect_cli_fail("not a regular file", "SB_SCENE_CACHE=%s timeout -s KILL 30 %s info %s/scene.gltf", cache,
                    test_binary(), a);
}

/* A merge counts every run once: the same set by two spellings, or one command's run in two sets, is refused
 * before anything is written (it exited 0 with the run's row twice); a merge that fails leaves no folder, and an
 * --out that holds files is not mixed with the merge's. */
static void test_merge_counts_once(void **st) {
    (void)st;
    const char *b = test_binary();
    char one[4096], two[4096], spelled[4400], out[4300];
    make_set("once-a", one, sizeof one);
    make_set("once-b", two, sizeof two);   /* the same command: the same run ids */
    snprintf(spelled, sizeof spelled, "%s/../%s/.", one, strrchr(one, '/') + 1);
    snprintf(out, sizeof out, "%s/once-m", g_tmp);
    expect_cli_fail("given twice", "%s merge %s %s --out %s", b, one, spelled, out);
    expect_cli_fail("is also in", "%s merge %s %s --out %s", b, one, two, out);
    assert_false(exists(out));
    assert_int_equal(sh("ls -d %s/once-m.merging-* 2>/dev/null | wc -l", g_tmp), 0);
    assert_string_equal(g_out, "0\n");
    /* one set: merged; merged again over it: refused, the first merge whole */
    assert_int_equal(sh("%s merge %s --out %s", b, one, out), 0);
    expect_cli_fail("already holds files", "%s merge %s --out %s", b, one, out);
    assert_int_equal(sh("%s merge %s --out %s/once-slash//", b, one, g_tmp), 0);   /* written beside it, not in it */
    sb_table t;
    summary_table(out, &t);
    assert_int_equal(t.nrows, 2);
    sb_table_free(&t);
}

/* Nothing is written but where the user said, and nothing waits for ever: an empty path refused in one line, a
 * history that is a FIFO refused (not opened), a note on a missing history leaves no history behind, a date that
 * is none refused (it selected no night and exited 0). */
static void test_paths_and_dates_named(void **st) {
    (void)st;
    const char *b = test_binary();
    char set[4096], hist[4300], fifo[4300];
    make_set("named", set, sizeof set);
    expect_cli_fail("--out '': an empty path", "%s report %s --out ''", b, set);
    expect_cli_fail("--out '': an empty path", "%s merge %s --out ''", b, set);
    expect_cli_fail("--out '': an empty path", "%s run plane-box plane-box sm --out ''", b);
    expect_cli_fail("--history '': an empty path", "%s history add %s --history ''", b, set);
    expect_cli_fail("--history '': an empty path", "%s report --history '' --out %s/site-empty", b, g_tmp);
    snprintf(fifo, sizeof fifo, "%s/history-fifo.sqlite", g_tmp);
    assert_int_equal(mkfifo(fifo, 0644), 0);
    expect_cli_fail("a FIFO, not a history file", "timeout -s KILL 30 %s history add %s --history %s", b, set, fifo);
    expect_cli_fail("a FIFO, not a history file", "timeout -s KILL 30 %s history list --history %s", b, fifo);
    snprintf(hist, sizeof hist, "%s/missing.sqlite", g_tmp);
    expect_cli_fail("is no night of the history", "%s history annotate 1 note --history %s", b, hist);
    assert_false(exists(hist));
    assert_int_equal(sh("%s history add %s --history %s --quiet", b, set, hist), 0);
    const char *not_dates[] = {"yesterday", "2026-13-45", "2026-02-30", "2025-02-29", "2026-1-5", "2026-01-05T25:00",
                               "2026-01-05x", "20260105"};
    for (size_t i = 0; i < SB_COUNT(not_dates); i++)
        expect_cli_fail("expected a date", "%s history regressions --since '%s' --history %s", b, not_dates[i], hist);
    const char *dates[] = {"2024-02-29", "2026-01-05", "2026-01-05T10:30", "2026-01-05T10:30:00Z"};
    for (size_t i = 0; i < SB_COUNT(dates); i++)
        assert_int_equal(sh("%s history regressions --since '%s' --history %s", b, dates[i], hist), 0);
}

/* A shadow map the GL will not allocate in one texture (llvmpipe: 2 GiB) is skipped before anything renders,
 * naming its size and what the GL did allocate; where it allocates (a large GPU), the run is ok. Never a failed
 * run with an incomplete framebuffer. */
static void test_map_the_gl_refuses(void **st) {
    (void)st;
    assert_int_equal(sh("%s run plane-box plane-box pssm:res=16384 --frames 1 --warmup 0 --size 64x36 --error-every 0 "
                        "--gpu-memory 64G --quiet --out %s/big", test_binary(), g_tmp), 0);
    sb_table t;
    summary_table(last_line_of(g_out), &t);
    const char *status = sb_table_get(&t, 0, "status"), *reason = sb_table_get(&t, 0, "reason");
    print_message("%s: %s\n", status, reason);
    if (strcmp(status, "ok")) {
        assert_string_equal(status, "skipped");
        assert_non_null(strstr(reason, "does not allocate one depth texture of 16384x16384x4 (4.0 GiB)"));
        assert_non_null(strstr(reason, "layer(s) of that size"));
    }
    sb_table_free(&t);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_damaged_sets_refused), cmocka_unit_test(test_bad_input_one_line),
        cmocka_unit_test(test_equals_spelling),      cmocka_unit_test(test_same_name_two_folders),
        cmocka_unit_test(test_map_the_gl_refuses),   cmocka_unit_test(test_output_over_input),
        cmocka_unit_test(test_merge_counts_once),    cmocka_unit_test(test_paths_and_dates_named),
    };
    return cmocka_run_group_tests_name("trust", tests, setup, teardown);
}
