/* `score SCENE PATH DIR`: another renderer's frames against the exact reference.
 *
 * - three.js (examples/engines: its own shadow map, in headless Chromium) draws plane-box's exported cameras;
 *   score takes its frames as a results set whose technique is three.js: status ok, no timings, the mask lined
 *   up with the scene (geom_mismatch under 0.1 %), an error a 2048 map of a box on a plane makes (under 1 % of
 *   the pixels), and that error equal, within 1 %, to the same frames counted by hand against the reference a
 *   run of the tool draws (--images: its ref.png, lit white, shadowed black, grey not scored).
 * - A wrong camera is refused, exit 2, saying what was found: the projection mirrored left to right ("mirrored"),
 *   the field of view a degree wider ("not the exported one").
 * - compare --pair of the scored renderer against sm on the same cameras prints both side by side; the report's
 *   run page of the scored set draws no empty timing chart and says why (headless Chromium).
 * - Bad input, each one line and exit 2 before anything is written: no --mask, a pattern without %d, a missing
 *   frame, another size, an unreadable image, --lights (the sun's shadows alone), a folder that is not there. */
#define _DEFAULT_SOURCE
#include <libgen.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "image.h"
#include "support.h"
#include "table.h"

SB_TEST_SCRATCH("sbscore")

static char g_out[1 << 16];

#define FRAMES 4
#define SIZE "320x180"
#define W 320
#define H 180

/* The bundled scene file beside the binary. */
static void bundled(const char *name, char *out, size_t len) {
    char bin[4096];
    snprintf(bin, sizeof bin, "%s", test_binary());
    snprintf(out, len, "%s/%s", dirname(bin), name);
}

/* Whether the example can run here (chromium and three from npm: scripts/setup installs both). */
static bool example_here(void) {
    char three[4200];
    snprintf(three, sizeof three, "%s/examples/engines/node_modules/three/build/three.module.js", getenv("SB_SOURCE_ROOT"));
    if (access(three, R_OK) != 0 || run_capture("command -v chromium", g_out, sizeof g_out) != 0) {
        print_message("no chromium or no three.js (scripts/setup installs them): skipped\n");
        return false;
    }
    return true;
}

/* cameras of plane-box into DIR/NAME.json, changed by a line of Python (`cams` the document) when edit is given;
 * then three.js draws them into DIR/NAME/. */
static void three_frames(const char *name, const char *edit) {
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s cameras plane-box plane-box --frames %d --size " SIZE " > %s/%s.json",
                                test_binary(), FRAMES, g_tmp, name), 0);
    if (edit)
        assert_int_equal(run_logged(g_out, sizeof g_out, "python3 -c 'import json, math; p = \"%s/%s.json\"; "
                                    "cams = json.load(open(p)); %s; json.dump(cams, open(p, \"w\"))'",
                                    g_tmp, name, edit), 0);
    char glb[4200];
    bundled("plane-box.glb", glb, sizeof glb);
    assert_int_equal(run_logged(g_out, sizeof g_out, "python3 %s/examples/engines/render.py %s/%s.json %s %s/%s",
                                getenv("SB_SOURCE_ROOT"), g_tmp, name, glb, g_tmp, name), 0);
}

static int score(const char *name, const char *extra) {
    return run_logged(g_out, sizeof g_out, "%s score plane-box plane-box %s/%s --mask 'mask_%%04d.png' --frames %d "
                      "--size " SIZE " --quiet --out %s/scored-%s %s", test_binary(), g_tmp, name, FRAMES, g_tmp, name,
                      extra);
}

/* One channel of an image read through the image module (rows top-down). */
static float *grey(const char *path) {
    int w, h;
    float *rgb;
    sb_err err;
    if (!sb_image_read_rgb(path, &w, &h, &rgb, &err)) fail_msg("%s", err.msg);
    assert_int_equal(w, W);
    assert_int_equal(h, H);
    return rgb;   /* r, g, b a pixel: the red one serves */
}

/* The set `score` just printed (into dir): one run of the renderer, status ok, nothing of it timed, its mask lined
 * up with the scene (geom_mismatch under 0.1 %); its err_rate_mean. */
static double scored_run(char *dir, size_t len, const char *renderer, sb_table *t) {
    snprintf(dir, len, "%s", last_line_of(g_out));
    summary_table(dir, t);
    assert_int_equal(t->nrows, 1);
    assert_string_equal(sb_table_get(t, 0, "technique"), renderer);
    assert_string_equal(sb_table_get(t, 0, "status"), "ok");
    assert_string_equal(sb_table_get(t, 0, "gpu_ms_median"), "");   /* nothing of it was timed here */
    assert_string_equal(sb_table_get(t, 0, "draw_calls_mean"), "");
    const double geom = atof(sb_table_get(t, 0, "geom_mismatch")), err = atof(sb_table_get(t, 0, "err_rate_mean"));
    print_message("%s on plane-box: err_rate %.6g, geom_mismatch %.3g\n", renderer, err, geom);
    assert_true(geom < 1e-3);
    return err;
}

/* ENGINE's page (render.py --engine ENGINE OPTS, its npm package at MODULE) on plane-box's cameras, scored with
 * `--renderer RENDERER --params PARAMS`: the page names RENDERER, its mask lines up with the scene; its err_rate. */
static double engine_scored(const char *engine, const char *module, const char *opts, const char *renderer,
                            const char *params) {
    char path[4200];
    snprintf(path, sizeof path, "%s/examples/engines/node_modules/%s", getenv("SB_SOURCE_ROOT"), module);
    if (!example_here() || access(path, R_OK) != 0) skip();
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s cameras plane-box plane-box --frames %d --size " SIZE " > %s/%s.json",
                                test_binary(), FRAMES, g_tmp, engine), 0);
    char glb[4200];
    bundled("plane-box.glb", glb, sizeof glb);
    assert_int_equal(run_logged(g_out, sizeof g_out, "python3 %s/examples/engines/render.py %s/%s.json %s %s/%s "
                                "--engine %s %s", getenv("SB_SOURCE_ROOT"), g_tmp, engine, glb, g_tmp, engine, engine,
                                opts), 0);
    assert_non_null(strstr(g_out, renderer));
    char extra[512];
    snprintf(extra, sizeof extra, "--renderer '%s' --params '%s'", renderer, params);
    assert_int_equal(score(engine, extra), 0);
    char scored[4096];
    sb_table t;
    const double err = scored_run(scored, sizeof scored, renderer, &t);
    sb_table_free(&t);
    return err;
}

/* Babylon.js's cascaded shadow generator (examples/engines/babylon-shadows.html) on the same cameras, at a bias
 * that clears its acne here (its default, 5e-5, shadows the lit plane with itself: about 0.4 of the pixels): scored
 * like three.js's, its mask lined up with the scene, its error that of a box's outline. */
static void test_babylon_scored(void **st) {
    (void)st;
    const double err = engine_scored("babylon", "babylonjs/babylon.js", "--map 1024 --bias 0.002", "Babylon.js",
                                     "map=1024:cascades=4:bias=0.002");
    assert_true(err < 0.01);
}

/* Filament's sun at its C++ defaults (examples/engines/filament-shadows.html: its npm build cannot set shadow options
 * from JavaScript): the box's shadow drawn, so the error is that of its outline (a page that drew no shadow, or
 * read back a frame Filament skipped, misses the whole shadow: 0.4 % of the pixels here); an option the build
 * cannot set is refused with one line, exit 2, before a page opens. */
static void test_filament_scored(void **st) {
    (void)st;
    const double err = engine_scored("filament", "filament/filament.js", "", "Filament", "at=defaults");
    assert_true(err > 0 && err < 0.002);
    char glb[4200];
    bundled("plane-box.glb", glb, sizeof glb);
    assert_int_equal(run_logged(g_out, sizeof g_out, "python3 %s/examples/engines/render.py %s/filament.json %s %s/fb "
                                "--engine filament --bias 0.01", getenv("SB_SOURCE_ROOT"), g_tmp, glb, g_tmp), 2);
    assert_non_null(strstr(g_out, "--bias: Filament's npm build cannot set"));
    assert_null(strchr(g_out, '\n') == NULL ? NULL : strchr(strchr(g_out, '\n') + 1, '\n'));   /* one line */
}

/* --repeat 2 of the three.js frames' spec: the untimed frames are recorded once and scored as they were (the run
 * asked for a second pass for ever, at 85 % CPU, SIGTERM unheard); under a limit, so a hang fails here and does
 * not stall the suite. by_spec: the same spec's run without --repeat. */
static void repeat_scores_once(const sb_table *by_spec) {
    sb_table rep;
    assert_int_equal(run_logged(g_out, sizeof g_out, "timeout -s KILL 120 %s run plane-box plane-box "
                                "'score:dir=%s/three:mask=mask_%%04d.png:renderer=three.js:settings=map=2048' --frames %d "
                                "--size " SIZE " --error-every 1 --repeat 2 --quiet --out %s/by-spec-repeat",
                                test_binary(), g_tmp, FRAMES, g_tmp), 0);
    summary_table(last_line_of(g_out), &rep);
    assert_string_equal(sb_table_get(&rep, 0, "err_rate_mean"), sb_table_get(by_spec, 0, "err_rate_mean"));
    sb_table_free(&rep);
}

/* The history files each row of the merged set under its own renderer (every row went under the first row's:
 * the tool's llvmpipe runs judged with the noise floor of the scored renderer's): g_tmp/both, three.js's frames
 * merged with the tool's sm. */
static void merged_rows_keep_renderer(void) {
    sb_table both;
    char both_dir[4200];
    snprintf(both_dir, sizeof both_dir, "%s/both", g_tmp);
    summary_table(both_dir, &both);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s history add %s --history %s/both.sqlite --quiet", test_binary(),
                                both_dir, g_tmp), 0);
    for (int r = 0; r < both.nrows; r++) {
        assert_int_equal(run_logged(g_out, sizeof g_out, "python3 -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1])"
                                    ".execute(\"SELECT renderer FROM runs WHERE run_id = ?\", (sys.argv[2],)).fetchone()[0])' "
                                    "%s/both.sqlite %s", g_tmp, sb_table_get(&both, r, "run_id")), 0);
        print_message("%s: stored under %s", sb_table_get(&both, r, "technique"), g_out);
        char want[600];
        snprintf(want, sizeof want, "%s\n", sb_table_get(&both, r, "renderer"));
        assert_string_equal(g_out, want);
    }
    assert_string_not_equal(sb_table_get(&both, 0, "renderer"), sb_table_get(&both, 1, "renderer"));
    sb_table_free(&both);
}

static void test_three_scored(void **st) {
    (void)st;
    if (!example_here()) skip();
    three_frames("three", NULL);
    assert_int_equal(score("three", "--renderer three.js --params map=2048:type=basic"), 0);
    char scored[4096];
    sb_table t;
    const double err = scored_run(scored, sizeof scored, "three.js", &t);
    assert_string_equal(sb_table_get(&t, 0, "params"), "map=2048:type=basic");
    assert_true(err > 0 && err < 0.01);   /* a box's shadow on a plane, a 2048 map: its outline's pixels */

    /* the same frames as a technique's spec through `run`: the same run (its id from the one rule, the command's
       and the spec's alike), the same error to every digit */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s score plane-box plane-box %s/three --mask 'mask_%%04d.png' "
                                "--frames %d --size " SIZE " --quiet --out %s/by-cmd --renderer three.js --params map=2048",
                                test_binary(), g_tmp, FRAMES, g_tmp), 0);
    sb_table by_cmd, by_spec;
    summary_table(last_line_of(g_out), &by_cmd);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run plane-box plane-box 'score:dir=%s/three:mask=mask_%%04d.png:"
                                "renderer=three.js:settings=map=2048' --frames %d --size " SIZE " --error-every 1 --quiet "
                                "--out %s/by-spec", test_binary(), g_tmp, FRAMES, g_tmp), 0);
    summary_table(last_line_of(g_out), &by_spec);
    print_message("run ids: score %s, run score:... %s\n", sb_table_get(&by_cmd, 0, "run_id"),
                  sb_table_get(&by_spec, 0, "run_id"));
    assert_string_equal(sb_table_get(&by_spec, 0, "run_id"), sb_table_get(&by_cmd, 0, "run_id"));
    assert_string_equal(sb_table_get(&by_spec, 0, "technique"), "three.js");
    assert_string_equal(sb_table_get(&by_spec, 0, "params"), "map=2048");
    assert_string_equal(sb_table_get(&by_spec, 0, "err_rate_mean"), sb_table_get(&t, 0, "err_rate_mean"));
    assert_string_equal(sb_table_get(&by_spec, 0, "err_rate_mean"), sb_table_get(&by_cmd, 0, "err_rate_mean"));
    assert_true(strcmp(sb_table_get(&by_cmd, 0, "run_id"), sb_table_get(&t, 0, "run_id")));   /* its settings differ */
    repeat_scores_once(&by_spec);
    sb_table_free(&by_cmd);
    sb_table_free(&by_spec);

    /* by hand: the tool's reference images of the same cameras, the renderer's frames against them */
    sb_table r;
    char ref_dir[4096];
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run plane-box plane-box none --frames %d --size " SIZE " --error-every 1 "
                                "--images 1 --warmup 0 --quiet --out %s/ref", test_binary(), FRAMES, g_tmp), 0);
    snprintf(ref_dir, sizeof ref_dir, "%s", last_line_of(g_out));
    summary_table(ref_dir, &r);
    double sum = 0;
    for (int f = 0; f < FRAMES; f++) {
        char path[4300];
        snprintf(path, sizeof path, "%s/images/%s_f%04d_ref.png", ref_dir, sb_table_get(&r, 0, "run_id"), f);
        float *ref = grey(path);
        snprintf(path, sizeof path, "%s/three/vis_%04d.png", g_tmp, f);
        float *vis = grey(path);
        long n = 0, wrong = 0;
        for (int i = 0; i < W * H; i++) {
            float v = ref[3 * i];
            if (v > 0.25f && v < 0.75f) continue;   /* grey: not scored (sky, facing away) */
            n++;
            wrong += (v >= 0.5f) != (vis[3 * i] >= 0.5f);
        }
        free(ref);
        free(vis);
        print_message("  frame %d by hand: %ld of %ld pixels wrong\n", f, wrong, n);
        sum += (double)wrong / n;
    }
    print_message("by hand: err_rate %.6g\n", sum / FRAMES);
    assert_true(fabs(sum / FRAMES - err) <= 0.01 * err);
    sb_table_free(&r);

    /* side by side with a technique of the tool on the same cameras: one set, compare --pair */
    char tool[4096];
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run plane-box plane-box sm --frames %d --size " SIZE " --error-every 1 "
                                "--warmup 0 --quiet --out %s/tool", test_binary(), FRAMES, g_tmp), 0);
    snprintf(tool, sizeof tool, "%s", last_line_of(g_out));
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s merge %s %s --out %s/both", test_binary(), scored, tool, g_tmp), 0);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s compare %s/both --pair technique=three.js,sm", test_binary(), g_tmp), 0);
    assert_non_null(strstr(g_out, "three.js err_rate"));
    assert_non_null(strstr(g_out, "sm err_rate"));
    assert_non_null(strstr(g_out, "sm gpu_ms"));
    assert_non_null(strstr(g_out, "1 pair(s)"));
    merged_rows_keep_renderer();
    /* the report's run page, as a person sees it: no empty timing charts, a line that says why */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s report %s --out %s/site", test_binary(), scored, g_tmp), 0);
    assert_int_equal(run_logged(g_out, sizeof g_out, "chromium --headless --no-sandbox --disable-gpu "
                                "--allow-file-access-from-files --virtual-time-budget=10000 --dump-dom "
                                "'file://%s/site/run.html?n=1&r=%s' 2>/dev/null", g_tmp, sb_table_get(&t, 0, "run_id")), 0);
    assert_non_null(strstr(g_out, "data-ready=\"yes\""));
    assert_non_null(strstr(g_out, "data-errors=\"0\""));
    assert_non_null(strstr(g_out, "data-charts=\"0\""));
    assert_non_null(strstr(g_out, "the frames are another renderer's"));
    sb_table_free(&t);
}

static void test_wrong_camera_refused(void **st) {
    (void)st;
    if (!example_here()) skip();
    /* the projection's x negated: what a camera of the other handedness draws */
    three_frames("mirrored", "[c[\"projection\"].__setitem__(0, -c[\"projection\"][0]) for c in cams[\"cameras\"]]");
    assert_int_equal(score("mirrored", ""), 2);
    assert_non_null(strstr(g_out, "mask_0"));
    assert_non_null(strstr(g_out, "mirrored left to right"));
    /* the field of view a degree wider */
    three_frames("fov", "[c[\"projection\"].__setitem__(k, c[\"projection\"][k] / math.tan((c[\"yfov\"] + math.radians(1)) "
                        "/ 2) * math.tan(c[\"yfov\"] / 2)) for c in cams[\"cameras\"] for k in (0, 5)]");
    assert_int_equal(score("fov", ""), 2);
    assert_non_null(strstr(g_out, "not the exported one"));
}

/* Frames 0..n-1 of a w x h renderer that drew every pixel white, into DIR/NAME/. */
static void white_frames(const char *name, int n, int w, int h) {
    char dir[4200], path[4300];
    snprintf(dir, sizeof dir, "%s/%s", g_tmp, name);
    assert_int_equal(run_logged(g_out, sizeof g_out, "mkdir -p %s", dir), 0);
    unsigned char *px = malloc((size_t)w * h);
    memset(px, 255, (size_t)w * h);
    sb_err err;
    for (int f = 0; f < n; f++)
        for (int k = 0; k < 2; k++) {
            snprintf(path, sizeof path, "%s/%s_%04d.png", dir, k ? "mask" : "vis", f);
            if (!sb_image_write_u8(path, w, h, 1, px, &err)) fail_msg("%s", err.msg);
        }
    free(px);
}

static void test_bad_input(void **st) {
    (void)st;
    const char *bin = test_binary();
    white_frames("white", 2, W, H);
    const char *common = "--frames 2 --size " SIZE;
    expect_cli_fail("--mask FILE is needed", "%s score plane-box plane-box %s/white %s", bin, g_tmp, common);
    expect_cli_fail("needs one %d", "%s score plane-box plane-box %s/white --mask mask.png %s", bin, g_tmp, common);
    expect_cli_fail("not '%s'", "%s score plane-box plane-box %s/white --mask 'mask_%%s.png' %s", bin, g_tmp, common);
    expect_cli_fail("at most 16 digits wide, not 999",
                    "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' --pattern 'vis_%%999d.png' %s", bin,
                    g_tmp, common);
    expect_cli_fail("frame 2 of 3", "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' --frames 3 --size " SIZE,
                    bin, g_tmp);
    expect_cli_fail("320x180, the run's --size is 160x90",
                    "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' --frames 2 --size 160x90", bin, g_tmp);
    expect_cli_fail("--lights is not an option of score", "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' %s --lights lamps",
                    bin, g_tmp, common);
    expect_cli_fail("--renderer is empty", "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' %s --renderer ''",
                    bin, g_tmp, common);
    expect_cli_fail("--renderer holds a control character (byte 10 at 3)",
                    "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' %s --renderer \"$(printf 'one\\ntwo')\"",
                    bin, g_tmp, common);
    expect_cli_fail("--params holds a control character (byte 9 at 5)",
                    "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' %s --params \"$(printf 'map=1\\tx')\"",
                    bin, g_tmp, common);
    expect_cli_fail("no such folder of frames", "%s score plane-box plane-box %s/nowhere --mask 'mask_%%04d.png' %s", bin,
                    g_tmp, common);
    /* a file that is no image where frame 0's visibility should be */
    white_frames("broken", 2, W, H);
    assert_int_equal(run_logged(g_out, sizeof g_out, "echo not a png > %s/broken/vis_0000.png", g_tmp), 0);
    expect_cli_fail("broken/vis_0000.png", "%s score plane-box plane-box %s/broken --mask 'mask_%%04d.png' %s", bin, g_tmp,
                    common);
    /* white everywhere: the sky is not geometry, so the mask does not line up: refused after the frame was drawn */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s score plane-box plane-box %s/white --mask 'mask_%%04d.png' %s "
                                "--quiet --out %s/refused", bin, g_tmp, common, g_tmp), 2);
    assert_non_null(strstr(g_out, "white/mask_0000.png: frame 0: the mask and the tool's geometry differ at"));
    /* its results set says it too: the run failed, the reason its row's */
    sb_table t;
    summary_table(last_line_of(g_out), &t);
    assert_string_equal(sb_table_get(&t, 0, "status"), "failed");
    assert_non_null(strstr(sb_table_get(&t, 0, "reason"), "differ at"));
    sb_table_free(&t);
    /* score is a technique: through `run` its spec is checked as any technique's, and a frame it refuses is bad
       input there too */
    expect_cli_fail("dir=FOLDER is needed", "%s run plane-box plane-box score %s", bin, common);
    expect_cli_fail("mask=PATTERN is needed", "%s run plane-box plane-box score:dir=%s/white %s", bin, g_tmp, common);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run plane-box plane-box 'score:dir=%s/white:mask=mask_%%04d.png' "
                                "%s --error-every 1 --quiet --out %s/refused-run", bin, g_tmp, common, g_tmp), 2);
    assert_non_null(strstr(g_out, "shadowbench: run: "));
    assert_non_null(strstr(g_out, "white/mask_0000.png: frame 0: the mask and the tool's geometry differ at"));
    /* a file whose clips move: score scores the renderer's still frames against the file held still (--anim none,
       its own default; it played the clips, scoring still frames against casters that moved: 0.0050 against
       0.00076 on movers), and a spec through `run` with the clips playing says so in the run's warnings */
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s score movers movers %s/white --mask 'mask_%%04d.png' %s --quiet "
                                "--out %s/movers-score", bin, g_tmp, common, g_tmp), 2);
    summary_table(last_line_of(g_out), &t);
    assert_string_equal(sb_table_get(&t, 0, "anim"), "none");
    sb_table_free(&t);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run movers movers 'score:dir=%s/white:mask=mask_%%04d.png' %s "
                                "--error-every 1 --quiet --out %s/movers-run", bin, g_tmp, common, g_tmp), 2);
    summary_table(last_line_of(g_out), &t);
    assert_string_equal(sb_table_get(&t, 0, "anim"), "");
    assert_non_null(strstr(sb_table_get(&t, 0, "warnings"), "scored with the file's clips playing (--anim all)"));
    sb_table_free(&t);
    /* and with --repeat 2 the same (it spun for ever before the evaluation was reached) */
    assert_int_equal(run_logged(g_out, sizeof g_out, "timeout -s KILL 60 %s run plane-box plane-box "
                                "'score:dir=%s/white:mask=mask_%%04d.png' %s --repeat 2 --quiet --out %s/refused-repeat",
                                bin, g_tmp, common, g_tmp), 2);
    assert_non_null(strstr(g_out, "white/mask_0000.png: frame 0: the mask and the tool's geometry differ at"));
}

/* A PNG in g_tmp whose header claims w x h pixels of a colour type (0 grey, 2 RGB) with 64 bytes of data behind
 * it. */
static void png_claiming(const char *name, int w, int h, int colour) {
    assert_int_equal(run_logged(g_out, sizeof g_out,
                                "python3 -c 'import struct, zlib, sys; h = struct.pack(\">IIBBBBB\", %d, %d, 8, %d, 0, 0, 0); "
                                "c = lambda t, d: struct.pack(\">I\", len(d)) + t + d + struct.pack(\">I\", zlib.crc32(t + d)); "
                                "open(sys.argv[1], \"wb\").write(b\"\\x89PNG\\r\\n\\x1a\\n\" + c(b\"IHDR\", h) + "
                                "c(b\"IDAT\", zlib.compress(bytes(64))) + c(b\"IEND\", b\"\"))' %s/%s",
                                w, h, colour, g_tmp, name), 0);
}

/* The one reader of images from outside (sb_image_read_rgb: score's frames, flip's images): a device behind a
 * link, a header that claims more pixels than any data behind it, NaN, each one line with exit 2 and nothing
 * allocated or spun on; an alpha channel read as stored, never multiplied in. */
static void test_image_reader(void **st) {
    (void)st;
    const char *bin = test_binary(), *common = "--frames 2 --size " SIZE;
    /* a visibility frame that is a link to /dev/zero: refused at once, named (it spun for ever, SIGTERM or not) */
    white_frames("device", 2, W, H);
    assert_int_equal(run_logged(g_out, sizeof g_out, "ln -sf /dev/zero %s/device/vis_0000.png", g_tmp), 0);
    expect_cli_fail("device/vis_0000.png: not a regular file (a device or socket)",
                    "timeout 20 %s score plane-box plane-box %s/device --mask 'mask_%%04d.png' %s", bin, g_tmp, common);
    expect_cli_fail("not a regular file (a folder)", "%s flip %s/device %s/device/mask_0000.png", bin, g_tmp, g_tmp);
    /* a PNG header claiming 60000 x 60000 with no data: refused on its header (it aborted on std::bad_alloc) */
    png_claiming("huge.png", 60000, 60000, 0);
    expect_cli_fail("huge.png: 60000x60000 with 1 channels: more than the 268435456 pixels",
                    "%s flip %s/huge.png %s/huge.png", bin, g_tmp, g_tmp);
    /* within the pixel limit but more than its file could hold (8000 x 8000 RGB, 192 MB, in 100 bytes): refused
       on its header against the file's length, before 768 MB of floats are allocated */
    png_claiming("claims.png", 8000, 8000, 2);
    expect_cli_fail("claims.png: its header claims 8000x8000 with 3 channels (192000000 bytes) in a file of",
                    "%s flip %s/claims.png %s/claims.png", bin, g_tmp, g_tmp);
    /* NaN in a float image: refused with its pixel (score read it as shadow: err_rate 0.0027 -> 0.50) */
    char nan_path[4200], ok_path[4200];
    snprintf(nan_path, sizeof nan_path, "%s/nan.exr", g_tmp);
    snprintf(ok_path, sizeof ok_path, "%s/ok.exr", g_tmp);
    float px[4 * 3 * 2];
    for (int i = 0; i < 4 * 3 * 2; i++) px[i] = 0.5f;
    sb_err err;
    assert_true(sb_image_write_f32(ok_path, 4, 2, 3, px, &err));
    px[3 * 6 + 1] = NAN;   /* written bottom-up: row 1 from the bottom is the top row, pixel 2 of it */
    assert_true(sb_image_write_f32(nan_path, 4, 2, 3, px, &err));
    expect_cli_fail("nan.exr: pixel (2, 0) channel 1 is NaN", "%s flip %s %s", bin, ok_path, nan_path);
    /* flip's map over one of its inputs, by any spelling (it replaced the input and exited 0): refused, the input
       kept; a map into a folder that is not there: the folder named, exit 4 (the write failed), no figures */
    char before[64], after[64];
    assert_int_equal(run_logged(g_out, sizeof g_out, "cksum < %s/white/vis_0000.png", g_tmp), 0);
    snprintf(before, sizeof before, "%.63s", g_out);
    assert_int_equal(run_logged(g_out, sizeof g_out, "ln -f %s/white/vis_0000.png %s/hard.png && ln -sf "
                                "white/vis_0000.png %s/soft.png", g_tmp, g_tmp, g_tmp), 0);
    const char *spellings[] = {"%s/white/vis_0000.png", "%s/white/../white/./vis_0000.png", "%s/hard.png", "%s/soft.png"};
    for (int i = 0; i < 4; i++) {
        char target[4300];
        snprintf(target, sizeof target, spellings[i], g_tmp);
        expect_cli_fail("it would be written over", "%s flip %s/white/vis_0000.png %s/white/vis_0001.png --map %s", bin,
                        g_tmp, g_tmp, target);
    }
    assert_int_equal(run_logged(g_out, sizeof g_out, "cksum < %s/white/vis_0000.png", g_tmp), 0);
    snprintf(after, sizeof after, "%.63s", g_out);
    assert_string_equal(before, after);
    /* a map named without an extension (/dev/full): refused before anything is computed (it ran, then failed on
       "no image writer for /dev/full.tmp" with exit 4) */
    expect_cli_fail("--map /dev/full has no extension to choose its format by", "%s flip %s/white/vis_0000.png "
                    "%s/white/vis_0001.png --map /dev/full", bin, g_tmp, g_tmp);
    char nodir[4200];
    snprintf(nodir, sizeof nodir, "%s/nodir/m.png: no such folder %s/nodir", g_tmp, g_tmp);
    /* a missing folder, an extension no writer has: bad input named before anything is computed (exit 2; they ran,
       then failed the write with exit 4) */
    expect_cli_fail(nodir, "%s flip %s/white/vis_0000.png %s/white/vis_0001.png --map %s/nodir/m.png", bin, g_tmp,
                    g_tmp, g_tmp);
    expect_cli_fail("no image writer for the extension .nosuchformat", "%s flip %s/white/vis_0000.png "
                    "%s/white/vis_0001.png --map %s/m.nosuchformat", bin, g_tmp, g_tmp, g_tmp);
    /* RGBA: the colour as stored, whatever the alpha (alpha 100 read 255 as 0.39 before) */
    char rgba_path[4200];
    snprintf(rgba_path, sizeof rgba_path, "%s/rgba.png", g_tmp);
    unsigned char rgba[2 * 2 * 4];
    for (int i = 0; i < 4; i++) rgba[4 * i] = rgba[4 * i + 1] = rgba[4 * i + 2] = 255, rgba[4 * i + 3] = 100;
    assert_true(sb_image_write_u8(rgba_path, 2, 2, 4, rgba, &err));
    int w, h;
    float *rgb;
    assert_true(sb_image_read_rgb(rgba_path, &w, &h, &rgb, &err));
    for (int i = 0; i < 3 * w * h; i++) assert_float_equal(rgb[i], 1.0f, 1e-6);
    free(rgb);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_bad_input), cmocka_unit_test(test_image_reader),
                                       cmocka_unit_test(test_three_scored),
                                       cmocka_unit_test(test_babylon_scored),
                                       cmocka_unit_test(test_filament_scored),
                                       cmocka_unit_test(test_wrong_camera_refused)};
    return cmocka_run_group_tests_name("score", tests, setup, teardown);
}
