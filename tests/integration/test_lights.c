/* --lights: several lights shadowed and scored in one run, on real renders.
 *
 * - towers-night with its six lamps: raycast's error is exactly 0 over every
 *   (pixel, lamp) pair, cube's and dpsm's are small and finite, the run names
 *   its lights (a series of its own), shadow_mb holds a map set a lamp, and a
 *   sun technique is skipped with its reason.
 * - Each lamp's shadows are its own: on street-lamps (lamps of range 7), one
 *   lamp moved changes only pixels within its range (before or after), for the
 *   per-light cube maps and for raycast.
 * - A --lights run's figures are its lights' own: frame by frame, cube's over lamps 0 and 1 are the pixel-weighted
 *   figures of the two one-lamp runs (each light's targets and reference key, not the first light's).
 * - A light the scene lacks, or a word --lights does not know: exit 2, one line. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "glb.h"
#include "session.h"
#include "spec.h"
#include "support.h"
#include "table.h"

SB_TEST_SCRATCH("sblights")

static double cell(const sb_table *t, int r, const char *col) {
    const char *v = sb_table_get(t, r, col);
    return v && *v ? atof(v) : NAN;
}

static int row_of(const sb_table *t, const char *technique, const char *light) {
    for (int r = 0; r < t->nrows; r++)
        if (!strcmp(sb_table_get(t, r, "technique"), technique) && !strcmp(sb_table_get(t, r, "light"), light)) return r;
    fail_msg("no %s run with light '%s'", technique, light);
    return -1;
}

static void test_every_lamp_of_towers_night(void **st) {
    (void)st;
    char out[16384], dir[512];
    int rc = run_logged(out, sizeof out,
                        "%s run towers-night towers-night raycast cube:res=512 dpsm:res=512 atlas:res=512:kind=cube,dpsm pssm --frames 2 --warmup 0 "
                        "--size 256x144 --error-every 1 --lights lamps --quiet --out %s/all",
                        test_binary(), g_tmp);
    assert_int_equal(rc, 0);
    snprintf(dir, sizeof dir, "%s", last_line_of(out));
    rc = run_logged(out, sizeof out,
                    "%s run towers-night towers-night cube:res=512 --frames 2 --warmup 0 --size 256x144 --error-every 1 "
                    "--quiet --out %s/one",
                    test_binary(), g_tmp);
    assert_int_equal(rc, 0);
    sb_table all, one;
    summary_table(dir, &all);
    summary_table(last_line_of(out), &one);
    const char *six = "lights lamps (6)";
    int ray = row_of(&all, "raycast", six), cube = row_of(&all, "cube", six), dpsm = row_of(&all, "dpsm", six);
    int atlas = row_of(&all, "atlas", six), atlas_dpsm = atlas + 1;
    assert_string_equal(sb_table_get(&all, atlas_dpsm, "technique"), "atlas");
    assert_non_null(strstr(sb_table_get(&all, atlas_dpsm, "params"), "kind=dpsm"));
    /* the atlas's tiles hold what the per-light maps hold: the same lookups, the same error within a tile's edge */
    print_message("atlas kind=cube %g (cube %g), kind=dpsm %g (dpsm %g)\n", cell(&all, atlas, "err_rate_mean"),
                  cell(&all, cube, "err_rate_mean"), cell(&all, atlas_dpsm, "err_rate_mean"), cell(&all, dpsm, "err_rate_mean"));
    assert_true(fabs(cell(&all, atlas, "err_rate_mean") - cell(&all, cube, "err_rate_mean")) < 0.002);
    assert_true(fabs(cell(&all, atlas_dpsm, "err_rate_mean") - cell(&all, dpsm, "err_rate_mean")) < 0.002);
    print_message("err_rate over (pixel, lamp): raycast %g, cube %g, dpsm %g, atlas %g; lights_px %g\n",
                  cell(&all, ray, "err_rate_mean"), cell(&all, cube, "err_rate_mean"), cell(&all, dpsm, "err_rate_mean"),
                  cell(&all, atlas, "err_rate_mean"), cell(&all, ray, "lights_px_mean"));
    assert_true(cell(&all, atlas, "lights_dropped_mean") == 0 && cell(&all, atlas, "lights_downscaled_mean") == 0);
    assert_true(fabs(cell(&all, atlas, "shadow_mb") - 64) < 1e-9);   /* one 4096^2 32F atlas, however many lamps */
    assert_true(cell(&all, ray, "err_rate_mean") == 0);   /* exact, every lamp */
    for (int r = 0; r < all.nrows; r++) {
        if (strcmp(sb_table_get(&all, r, "technique"), "pssm")) {
            assert_string_equal(sb_table_get(&all, r, "status"), "ok");
            double e = cell(&all, r, "err_rate_mean"), lp = cell(&all, r, "lights_px_mean");
            assert_true(isfinite(e) && e < 0.03);
            assert_true(lp >= 1 && lp <= 6);
            assert_true(cell(&all, r, "error_frames") == 2);
        }
    }
    /* a sun technique says why it has nothing to do: here no sun; beside a sun, that it shadows the sun alone */
    int pssm = row_of(&all, "pssm", six);
    assert_string_equal(sb_table_get(&all, pssm, "status"), "skipped");
    assert_non_null(strstr(sb_table_get(&all, pssm, "reason"), "no sun"));
    rc = run_logged(out, sizeof out, "%s run plane-box-lamp plane-box-lamp pssm raycast --frames 1 --warmup 0 --size 64x36 "
                    "--error-every 0 --lights all --quiet --out %s/sun", test_binary(), g_tmp);
    assert_int_equal(rc, 0);
    sb_table sun;
    summary_table(last_line_of(out), &sun);
    pssm = row_of(&sun, "pssm", "lights all (2)");
    assert_string_equal(sb_table_get(&sun, pssm, "status"), "skipped");
    assert_non_null(strstr(sb_table_get(&sun, pssm, "reason"), "pssm shadows the sun alone; --lights all names a lamp"));
    assert_string_equal(sb_table_get(&sun, row_of(&sun, "raycast", "lights all (2)"), "status"), "ok");
    sb_table_free(&sun);
    /* the per-light techniques' lamps found by cluster (grid=on): the light grid is a stage of their frame and lists
       each lamp in view at least once; one lamp has no grid to build */
    int single = row_of(&one, "cube", "");
    for (int r = 0; r < 2; r++) {
        int row = r ? dpsm : cube;
        print_message("%s: clusters_ms %g, grid_items %g\n", sb_table_get(&all, row, "technique"),
                      cell(&all, row, "clusters_ms_median"), cell(&all, row, "grid_items_mean"));
        assert_true(cell(&all, row, "clusters_ms_median") > 0 && cell(&all, row, "grid_items_mean") >= 1);
    }
    assert_true(isnan(cell(&one, single, "clusters_ms_median")) && !(cell(&one, single, "grid_items_mean") > 0));
    /* a map set a lamp; the same technique without --lights is another run (and series) */
    assert_true(fabs(cell(&all, cube, "shadow_mb") - 6 * cell(&one, single, "shadow_mb")) < 1e-9);
    assert_string_not_equal(sb_table_get(&all, cube, "run_id"), sb_table_get(&one, single, "run_id"));
    assert_true(isnan(cell(&one, single, "lights_px_mean")));   /* one light: not a figure of several */
    sb_table_free(&all);
    sb_table_free(&one);
}

/* The set's figures over two lamps, from the one-lamp runs' (each frame: pixels add, shares weight by them). */
static void test_set_is_its_lights(void **st) {
    (void)st;
    char out[16384], dir[512];
    const char *common = "--frames 2 --warmup 0 --size 256x144 --error-every 1 --quiet";
    int rc = run_logged(out, sizeof out, "%s run towers-night towers-night cube:res=512 --lights 0,1 %s --out %s/set",
                        test_binary(), common, g_tmp);
    assert_int_equal(rc, 0);
    snprintf(dir, sizeof dir, "%s", last_line_of(out));
    rc = run_logged(out, sizeof out, "%s run towers-night towers-night cube:res=512:light=0,1 %s --out %s/singles",
                    test_binary(), common, g_tmp);
    assert_int_equal(rc, 0);
    sb_table set, singles, fs, f0, f1;
    summary_table(dir, &set);
    summary_table(last_line_of(out), &singles);
    frames_table(dir, &set, 0, &fs);
    frames_table(last_line_of(out), &singles, 0, &f0);
    frames_table(last_line_of(out), &singles, 1, &f1);
    assert_int_equal(fs.nrows, 2);
    for (int f = 0; f < 2; f++) {
        double p0 = cell(&f0, f, "eval_pixels"), p1 = cell(&f1, f, "eval_pixels"), ps = cell(&fs, f, "eval_pixels");
        assert_true(p0 > 0 && p1 > 0);
        assert_true(ps == p0 + p1);
        const char *shares[] = {"err_rate", "res_err_mean"};
        for (int k = 0; k < 2; k++) {
            double want = (cell(&f0, f, shares[k]) * p0 + cell(&f1, f, shares[k]) * p1) / (p0 + p1);
            double got = cell(&fs, f, shares[k]);
            print_message("frame %d %s: set %g, from the lamps %g\n", f, shares[k], got, want);
            if (isnan(want)) assert_true(isnan(got));   /* lamps' maps give no texel density: none either way */
            else assert_true(fabs(got - want) <= 1e-5 * fabs(want) + 1e-9);
        }
    }
    sb_table_free(&f1);
    sb_table_free(&f0);
    sb_table_free(&fs);
    sb_table_free(&singles);
    sb_table_free(&set);
}

/* Renders frame 0 with the technique over the session's lights: its colour as a timed frame draws it (timed: a
 * further lamp's pass cut to its footprint and range) or as an evaluation pass shading every light of the set
 * draws it (every pass whole), and then (pos, aux not NULL) the evaluation's positions and normals. */
static void colour_of(sb_session *s, const char *technique, bool timed, unsigned char *rgba, float *pos, float *aux) {
    sb_err err;
    sb_run_spec *runs = NULL;
    int n = 0;
    assert_true(sb_spec_expand(technique, NULL, &runs, &n, &err));
    sb_instance in;
    if (!sb_instance_create(&in, s, &runs[0], 1, &err)) fail_msg("%s", err.msg);
    sb_timer t;
    sb_timer_init(&t, SB_TIMING_SYNC, 1, 1);
    sb_timer_frame_begin(&t, 0);
    sb_frame f;
    memset(&f, 0, sizeof f);
    if (timed) sb_render_frame(s, &in, &f, 0, 1, 0, &t);
    else render_frame_eval(s, &in, &f, 0, 1, 0, &t);   /* every light of the set: the colour a timed frame draws */
    sb_gpu_readback(&s->gpu, NULL, NULL, rgba);
    if (pos) sb_gpu_readback_eval(&s->gpu, pos, aux);
    sb_timer_free(&t);
    sb_instance_destroy(&in);
    free(runs);
}

static double dist(const float *p, sb_v3 q) {
    return sqrt((p[0] - q.x) * (p[0] - q.x) + (p[1] - q.y) * (p[1] - q.y) + (p[2] - q.z) * (p[2] - q.z));
}

static void moved_lamp(const char *technique) {
    sb_session s;
    sb_err err;
    const int w = 320, h = 180, np = w * h;
    assert_true(test_open(&s, "street-lamps", "street-lamps", w, h, &err));
    assert_true(sb_scene_light_set(&s.scene, "0,1", false, &s.lights, &err));
    unsigned char *a = malloc(4 * (size_t)np), *b = malloc(4 * (size_t)np);
    float *pos = malloc(sizeof(float) * 4 * np), *aux = malloc(sizeof(float) * 4 * np);
    colour_of(&s, technique, false, a, pos, aux);
    sb_light *lamp1 = (sb_light *)sb_scene_point_light(&s.scene, 1, NULL);
    sb_v3 before = lamp1->position, after = sb_v3_add(before, sb_v3_make(0, 0, 2.5));
    double range = lamp1->range;
    lamp1->position = after;
    colour_of(&s, technique, false, b, pos, aux);
    int differ = 0, outside = 0, lit0 = 0, ground = 0;
    sb_v3 lamp0 = sb_scene_point_light(&s.scene, 0, NULL)->position;
    for (int i = 0; i < np; i++) {
        const float *p = pos + 4 * (size_t)i;
        const float *n = aux + 4 * (size_t)i;
        if (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] < 0.25) continue;   /* sky */
        ground++;
        bool in1 = dist(p, before) <= range * 1.001 || dist(p, after) <= range * 1.001;
        lit0 += dist(p, lamp0) <= range && !in1;
        if (!memcmp(a + 4 * (size_t)i, b + 4 * (size_t)i, 4)) continue;
        differ++;
        outside += !in1;
    }
    print_message("%s: lamp 1 moved 2.5 along z: %d pixels changed, %d of them beyond its range; %d pixels lit by lamp 0 "
                  "alone (of %d not sky)\n", technique, differ, outside, lit0, ground);
    assert_true(differ > 500);
    assert_true(lit0 > 500);      /* pixels that only lamp 0 lights exist, and none of them changed */
    assert_int_equal(outside, 0);
    free(a);
    free(b);
    free(pos);
    free(aux);
    sb_session_close(&s);
}

static void test_moved_lamp_changes_only_its_pixels(void **st) {
    (void)st;
    moved_lamp("cube:res=512");
    moved_lamp("atlas:res=512");
    moved_lamp("raycast");
}

/* Pixels of two colour images that differ, and by how much at most (8-bit channels). */
static int differing(const unsigned char *a, const unsigned char *b, int np, int *most) {
    int n = 0;
    *most = 0;
    for (int i = 0; i < np; i++) {
        int d = 0;
        for (int c = 0; c < 3; c++) d = abs(a[4 * i + c] - b[4 * i + c]) > d ? abs(a[4 * i + c] - b[4 * i + c]) : d;
        n += d > 0;
        *most = d > *most ? d : *most;
    }
    return n;
}

/* A per-light technique's timed frame with grid=on (one pass through the light grid, every lamp's maps layers of one
 * texture) against its evaluated frame with every lamp (a pass a lamp, uncut, each lamp's maps a view of its layers):
 * the evaluated passes add 8-bit colours lamp by lamp where the one pass sums them first, so a pixel a lamp reaches may
 * differ by one level of rounding, and none may differ by more; a pixel no lamp's range reaches not at all. A lamp the
 * grid missed, or a lookup in another lamp's layers, would differ by tens of levels over whole patches. */
static void one_pass_matches(sb_session *s, const char *spec, int lamps, const unsigned char *eval,
                             const unsigned char *timed, const float *pos, const float *aux, int np) {
    int differ = 0, most = 0, beyond = 0, reached = 0;
    for (int i = 0; i < np; i++) {
        const float *n = aux + 4 * (size_t)i;
        bool sky = n[0] * n[0] + n[1] * n[1] + n[2] * n[2] < 0.25;
        bool in = false;
        for (int k = 0; k < lamps && !sky && !in; k++) {
            const sb_light *l = sb_scene_point_light(&s->scene, k, NULL);
            in = dist(pos + 4 * (size_t)i, l->position) <= l->range * 1.001;
        }
        reached += in;
        int d = 0;
        for (int c = 0; c < 3; c++) d = abs(eval[4 * i + c] - timed[4 * i + c]) > d ? abs(eval[4 * i + c] - timed[4 * i + c]) : d;
        differ += d > 0, beyond += d > 0 && !in;
        most = d > most ? d : most;
    }
    print_message("%s, one pass through the grid against a pass a lamp: %d pixels differ (%d of them beyond every "
                  "lamp's range), by at most %d; %d pixels in a lamp's range\n", spec, differ, beyond, most, reached);
    assert_true(reached > np / 10);
    assert_int_equal(beyond, 0);
    assert_true(most <= 1);
}

/* Lamps found by cluster change no pixel: on street-lamps with 24 lamps (range 7), the atlas's camera pass with
 * grid=on (each pixel loops over its cluster's lamps) draws grid=off's image (every lamp in view); the per-light
 * cube's and dpsm's one pass (grid=on) draws their per-light passes' image but for rounding (one_pass_matches), and
 * cube's timed frame with grid=off, whose further lamps' passes are cut to their footprints and ranges, draws the
 * image of its uncut passes. Each cut or grid that missed a lamp where it lights would darken whole patches of
 * pixels. */
static void test_lamps_by_cluster(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    const int w = 320, h = 180, np = w * h, lamps = 24;
    assert_true(test_open(&s, "street-lamps", "street-lamps", w, h, &err));
    char set[200] = "";
    for (int i = 0; i < lamps; i++) snprintf(set + strlen(set), sizeof set - strlen(set), "%s%d", i ? "," : "", i);
    assert_true(sb_scene_light_set(&s.scene, set, false, &s.lights, &err));
    unsigned char *a = malloc(4 * (size_t)np), *b = malloc(4 * (size_t)np);
    float *pos = malloc(sizeof(float) * 4 * np), *aux = malloc(sizeof(float) * 4 * np);
    int most = 0, n;
    colour_of(&s, "atlas:res=128:grid=on", false, a, NULL, NULL);
    colour_of(&s, "atlas:res=128:grid=off", false, b, NULL, NULL);
    n = differing(a, b, np, &most);
    print_message("atlas grid=on against grid=off: %d pixels differ, by at most %d\n", n, most);
    assert_int_equal(n, 0);
    colour_of(&s, "atlas:res=128:grid=on", true, b, NULL, NULL);   /* the timed frame draws the grid's image too */
    n = differing(a, b, np, &most);
    print_message("atlas grid=on, timed against evaluated: %d pixels differ, by at most %d\n", n, most);
    assert_true(n <= np / 1000 && most <= 1);
    static const char *const one_pass[] = {"cube:res=128", "cube:res=128:filter=pcf", "dpsm:res=128"};
    for (size_t k = 0; k < SB_COUNT(one_pass); k++) {
        colour_of(&s, one_pass[k], false, a, pos, aux);
        colour_of(&s, one_pass[k], true, b, NULL, NULL);
        one_pass_matches(&s, one_pass[k], lamps, a, b, pos, aux, np);
    }
    colour_of(&s, "cube:res=128:grid=off", false, a, NULL, NULL);
    colour_of(&s, "cube:res=128:grid=off", true, b, NULL, NULL);
    n = differing(a, b, np, &most);
    print_message("cube grid=off, further lamps cut to their footprints against whole: %d pixels differ, by at most "
                  "%d\n", n, most);
    assert_true(n <= np / 1000 && most <= 1);
    free(a);
    free(b);
    free(pos);
    free(aux);
    sb_session_close(&s);
}

/* An atlas too small for street-lamps' 64 lamps, or capped below them: the exact counts in the warning, per-frame
 * columns that agree, a finite error; policy=screen beats fixed at the same size (near lamps get the texels). */
static void test_atlas_under_budget(void **st) {
    (void)st;
    char out[16384], dir[512];
    int rc = run_logged(out, sizeof out,
                        "%s run street-lamps street-lamps atlas:size=512:res=256 atlas:res=256:max_lights=8 "
                        "atlas:size=2048:res=256:policy=fixed,screen --frames 3 --warmup 0 --size 320x180 --error-every 1 "
                        "--quiet --out %s/budget", test_binary(), g_tmp);
    assert_int_equal(rc, 0);
    snprintf(dir, sizeof dir, "%s", last_line_of(out));
    sb_table sum;
    summary_table(dir, &sum);
    assert_int_equal(sum.nrows, 4);
    for (int r = 0; r < sum.nrows; r++) {
        assert_string_equal(sb_table_get(&sum, r, "status"), "ok");
        assert_true(isfinite(cell(&sum, r, "err_rate_mean")) && cell(&sum, r, "err_rate_mean") < 0.05);
        sb_table fr;
        frames_table(dir, &sum, r, &fr);
        long dropped = 0, down = 0, inview = 0, frames = 0;
        for (int i = 0; i < fr.nrows; i++) {
            long d = table_int(&fr, i, "lights_dropped"), w = table_int(&fr, i, "lights_downscaled");
            long v = table_int(&fr, i, "lights_shadowed") + d;
            if (!d && !w) continue;   /* the warning is over the frames short of room */
            frames++;
            dropped = d > dropped ? d : dropped, down = w > down ? w : down, inview = v > inview ? v : inview;
        }
        sb_table_free(&fr);
        char want[256];
        if (dropped && down)
            snprintf(want, sizeof want, "atlas: up to %ld lamp(s) dropped (lit without shadows) and up to %ld downscaled, "
                     "of up to %ld in view, in %ld of 3 frames", dropped, down, inview, frames);
        else if (dropped)
            snprintf(want, sizeof want, "atlas: up to %ld lamp(s) dropped (lit without shadows), of up to %ld in view, in "
                     "%ld of 3 frames", dropped, inview, frames);
        else
            snprintf(want, sizeof want, "atlas: up to %ld lamp(s) downscaled, of up to %ld in view, in %ld of 3 frames",
                     down, inview, frames);
        print_message("%s: err_rate %g; %s\n", sb_table_get(&sum, r, "params"), cell(&sum, r, "err_rate_mean"),
                      sb_table_get(&sum, r, "warnings"));
        assert_true(frames > 0);
        assert_non_null(strstr(sb_table_get(&sum, r, "warnings"), want));
    }
    /* 512^2 holds 64 lamps' six tiles only at the smallest (16): every lamp downscaled; max_lights=8: 56 dropped */
    assert_true(cell(&sum, 0, "lights_downscaled_max") >= 56);
    assert_true(cell(&sum, 1, "lights_dropped_max") >= 50 && cell(&sum, 1, "lights_shadowed_mean") == 8);
    double fixed = cell(&sum, 2, "err_rate_mean"), screen = cell(&sum, 3, "err_rate_mean");
    print_message("size=2048: fixed %g, screen %g\n", fixed, screen);
    assert_true(screen < fixed);
    sb_table_free(&sum);
}

/* cache=on with still lamps, casters and camera: no tile drawn after the first frame, figures equal cache=off's. */
static void test_atlas_cache_still(void **st) {
    (void)st;
    char out[16384], path[512];
    snprintf(path, sizeof path, "%s/still.path", g_tmp);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("near 0.5\nfar 220\nlook 0  0 3 -6  0 1 40\nlook 4  0 3 -6  0 1 40\n", f);
    fclose(f);
    int rc = run_logged(out, sizeof out, "%s run street-lamps %s atlas:res=128:cache=off,on --frames 4 --warmup 0 --size "
                        "256x144 --error-every 1 --quiet --out %s/cache", test_binary(), path, g_tmp);
    assert_int_equal(rc, 0);
    char dir[512];
    snprintf(dir, sizeof dir, "%s", last_line_of(out));
    sb_table sum, off, on;
    summary_table(dir, &sum);
    frames_table(dir, &sum, 0, &off);
    frames_table(dir, &sum, 1, &on);
    assert_int_equal(off.nrows, 4);
    assert_int_equal(on.nrows, 4);
    for (int i = 0; i < 4; i++) {
        long drawn = table_int(&on, i, "cascades_rendered"), kept = table_int(&on, i, "cascades_cached");
        print_message("frame %d: cache=on drew %ld tiles, kept %ld; cache=off drew %ld\n", i, drawn, kept,
                      table_int(&off, i, "cascades_rendered"));
        assert_true(i == 0 ? drawn > 0 && kept == 0 : drawn == 0 && kept > 0);
        assert_string_equal(sb_table_get(&on, i, "err_rate"), sb_table_get(&off, i, "err_rate"));
    }
    assert_string_equal(sb_table_get(&sum, 1, "err_rate_mean"), sb_table_get(&sum, 0, "err_rate_mean"));
    sb_table_free(&off);
    sb_table_free(&on);
    sb_table_free(&sum);
}

/* scripts/add-lamps on a file with moving casters (the bundled movers: a sliding box, a turning bar): four lamps of
 * range 5 along the slider's track. atlas:cache=on draws again only the lamps the slider reaches, keeps the
 * others, and is never stale (stale_px 0; its error frame for frame cache=off's). */
static void test_atlas_cache_with_movers(void **st) {
    (void)st;
    char out[16384], scene[512], dir[512];
    snprintf(scene, sizeof scene, "%s/movers-lamps.glb", g_tmp);
    int rc = run_logged(out, sizeof out, "SHADOWBENCH=%s %s/scripts/add-lamps %s/movers.glb %s --count 4 --range 5 "
                        "--line=-12,4,-4:12,4,-4", test_binary(), getenv("SB_SOURCE_ROOT"), getenv("SB_DATA_DIR"), scene);
    assert_int_equal(rc, 0);
    rc = run_logged(out, sizeof out, "%s info %s", test_binary(), scene);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "lights: 5\n"));   /* the file's sun and four lamps */
    rc = run_logged(out, sizeof out, "%s run %s movers atlas:res=128:cache=off,on --lights lamps --frames 6 --warmup 0 "
                    "--size 160x90 --error-every 1 --quiet --out %s/movers", test_binary(), scene, g_tmp);
    assert_int_equal(rc, 0);
    snprintf(dir, sizeof dir, "%s", last_line_of(out));
    sb_table sum, off, on;
    summary_table(dir, &sum);
    frames_table(dir, &sum, 0, &off);
    frames_table(dir, &sum, 1, &on);
    long drawn = 0, kept = 0;
    for (int i = 0; i < on.nrows; i++) {
        print_message("frame %d: cache=on drew %ld tiles, kept %ld; stale_px %s; err_rate %s (off %s)\n", i,
                      table_int(&on, i, "cascades_rendered"), table_int(&on, i, "cascades_cached"),
                      sb_table_get(&on, i, "stale_px"), sb_table_get(&on, i, "err_rate"), sb_table_get(&off, i, "err_rate"));
        if (i) drawn += table_int(&on, i, "cascades_rendered"), kept += table_int(&on, i, "cascades_cached");
        assert_true(cell(&on, i, "stale_px") == 0);
        assert_string_equal(sb_table_get(&on, i, "err_rate"), sb_table_get(&off, i, "err_rate"));
    }
    assert_true(drawn > 0);   /* the lamps the slider reaches, drawn again */
    assert_true(kept > 0);    /* the others kept */
    assert_true(cell(&sum, 1, "stale_px_max") == 0);
    sb_table_free(&off);
    sb_table_free(&on);
    sb_table_free(&sum);
    rc = run_logged(out, sizeof out, "%s/scripts/add-lamps %s/movers.glb %s --count 0", getenv("SB_SOURCE_ROOT"),
                    getenv("SB_DATA_DIR"), scene);
    assert_int_equal(rc, 2);
    assert_non_null(strstr(out, "add-lamps: --count 0: expected a whole number from 1 to 256"));
}

/* A batch line's --lights: its runs shadow those lamps (a series of their own); a lamp a scene lacks is refused with
 * the file and line before anything renders. */
static void test_batch_lights(void **st) {
    (void)st;
    char file[512], out[16384];
    snprintf(file, sizeof file, "%s/lamps.bench", g_tmp);
    FILE *f = fopen(file, "w");
    assert_non_null(f);
    fputs("scene street street-lamps\npath street street-lamps\ndefaults --frames 1 --warmup 0 --size 64x36 --error-every 1\n"
          "cube:res=64\n@street cube:res=64 atlas:res=64 --lights 0,1,2\n", f);
    fclose(f);
    int rc = run_logged(out, sizeof out, "%s batch %s --quiet --out %s/batch", test_binary(), file, g_tmp);
    assert_int_equal(rc, 0);
    sb_table sum;
    summary_table(last_line_of(out), &sum);
    assert_int_equal(sum.nrows, 3);
    assert_string_equal(sb_table_get(&sum, 0, "light"), "");
    assert_string_equal(sb_table_get(&sum, 1, "light"), "lights 0,1,2 (3)");
    assert_string_equal(sb_table_get(&sum, 2, "light"), "lights 0,1,2 (3)");
    assert_true(fabs(cell(&sum, 1, "shadow_mb") - 3 * cell(&sum, 0, "shadow_mb")) < 1e-9);
    sb_table_free(&sum);
    f = fopen(file, "w");
    fputs("scene street street-lamps\nscene night towers-night\npath street street-lamps\npath night towers-night\n"
          "cube\n@street,night cube --lights 0,9\n", f);
    fclose(f);
    expect_cli_fail("lamps.bench:6: scene night: --lights 0,9: the scene has no lamp 9 (its point and spot lights are 0..5)",
                    "%s batch %s --quiet --out %s/batch2", test_binary(), file, g_tmp);
}

/* tune --max-mb on a many-lamp scene: the per-light maps hold a set a lamp (four lamps of 512² cubes: 24 MiB, over
 * 20), the atlas one texture; the answer is an atlas of 2048², its batch line carries the lamps. */
static void test_tune_atlas_under_memory(void **st) {
    (void)st;
    char out[65536];
    int rc = run_logged(out, sizeof out, "%s tune street-lamps street-lamps --techniques atlas,cube --lights 0,1,2,3 "
                        "--max-err 0.05 --max-mb 20 --size 96x54 --frames 5 --out %s/tune", test_binary(), g_tmp);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "skipped cube:res=512: holds 24 MiB of shadow storage, over --max-mb 20"));
    assert_non_null(strstr(out, "recommended: atlas:size=2048"));
    const char *pin = strstr(out, "batch line (pin it in a nightly):\n  @street-lamps atlas:size=2048");
    assert_non_null(pin);
    assert_non_null(strstr(pin, " --lights 0,1,2,3\n"));
}

/* Spot lights (scripts/add-lamps --spot): scored and shaded only inside their cones (fewer evaluated pixels than
 * point lamps in the same places), raycast exact, and in the atlas one perspective tile a spot down its cone. */
static long frames_sum(const char *dir, const sb_table *sum, int r, const char *col) {
    sb_table t;
    frames_table(dir, sum, r, &t);
    long v = 0;
    for (int i = 0; i < t.nrows; i++) v += table_int(&t, i, col);
    sb_table_free(&t);
    return v;
}

static void test_spots(void **st) {
    (void)st;
    char out[16384], spots[512], points[512], dirs[2][512];
    snprintf(spots, sizeof spots, "%s/spots.glb", g_tmp);
    snprintf(points, sizeof points, "%s/points.glb", g_tmp);
    const char *make = "SHADOWBENCH=%s %s/scripts/add-lamps %s/street-lamps.glb %s --count 8 --range 8 %s "
                       "--line=-4,4.5,3:-4,4.5,45";
    assert_int_equal(run_logged(out, sizeof out, make, test_binary(), getenv("SB_SOURCE_ROOT"), getenv("SB_DATA_DIR"),
                                spots, "--spot 30"), 0);
    assert_int_equal(run_logged(out, sizeof out, make, test_binary(), getenv("SB_SOURCE_ROOT"), getenv("SB_DATA_DIR"),
                                points, ""), 0);
    const char *files[2] = {spots, points};
    for (int k = 0; k < 2; k++) {
        int rc = run_logged(out, sizeof out, "%s run %s street-lamps raycast cube:res=256 atlas:res=256 --lights "
                            "64,65,66,67,68,69,70,71 --frames 3 --warmup 0 --size 160x90 --error-every 1 --quiet --out %s/%s",
                            test_binary(), files[k], g_tmp, k ? "points" : "spots");
        assert_int_equal(rc, 0);
        snprintf(dirs[k], sizeof dirs[k], "%s", last_line_of(out));
    }
    sb_table s, p;
    summary_table(dirs[0], &s);
    summary_table(dirs[1], &p);
    long spot_px = frames_sum(dirs[0], &s, 0, "eval_pixels"), point_px = frames_sum(dirs[1], &p, 0, "eval_pixels");
    long tiles = frames_sum(dirs[0], &s, 2, "cascades_rendered"), lamps = frames_sum(dirs[0], &s, 2, "lights_shadowed");
    print_message("spots: %ld (pixel, lamp) pairs evaluated against %ld as points; atlas drew %ld tiles for %ld lamps; "
                  "err_rate raycast %g, cube %g, atlas %g\n", spot_px, point_px, tiles, lamps, cell(&s, 0, "err_rate_mean"),
                  cell(&s, 1, "err_rate_mean"), cell(&s, 2, "err_rate_mean"));
    assert_true(spot_px > 0 && spot_px < point_px / 2);   /* a 30-degree cone lights far less than the sphere */
    assert_true(cell(&s, 0, "err_rate_mean") == 0);
    assert_true(lamps > 0 && tiles == lamps);             /* one tile a spot */
    assert_true(frames_sum(dirs[1], &p, 2, "cascades_rendered") > 4 * frames_sum(dirs[1], &p, 2, "lights_shadowed"));
    assert_true(cell(&s, 2, "err_rate_mean") <= cell(&s, 1, "err_rate_mean") + 0.002);
    sb_table_free(&s);
    sb_table_free(&p);
}

static void test_bad_lights(void **st) {
    (void)st;
    expect_cli_fail("--lights 0,64: the scene has no lamp 64 (its point and spot lights are 0..63)",
                    "%s run street-lamps street-lamps cube --frames 1 --lights 0,64 --out %s/x", test_binary(), g_tmp);
    expect_cli_fail("--lights sun: the scene has no sun", "%s run towers-night towers-night raycast --frames 1 --lights sun "
                    "--out %s/x", test_binary(), g_tmp);
    expect_cli_fail("--lights lamp: 'lamp' is not sun, lamps, all or a lamp number",
                    "%s run towers-night towers-night cube --frames 1 --lights lamp --out %s/x", test_binary(), g_tmp);
    expect_cli_fail("atlas:size=3000: not a power of two", "%s run street-lamps street-lamps atlas:size=3000 --frames 1 "
                    "--out %s/x", test_binary(), g_tmp);
    expect_cli_fail("max_lights", "%s run street-lamps street-lamps atlas:max_lights=300 --frames 1 --out %s/x",
                    test_binary(), g_tmp);
    expect_cli_fail("--lights 1,1: a light named twice",
                    "%s run towers-night towers-night cube --frames 1 --lights 1,1 --out %s/x", test_binary(), g_tmp);
    /* grid=on keeps every lamp's maps in one texture: 64 lamps' 384 cube faces of 1280^2 (2.3 GiB) are more than
       llvmpipe allocates in one (2 GiB), said before anything renders, with the way out */
    char out[8192];
    assert_int_equal(run_logged(out, sizeof out, "%s run street-lamps street-lamps cube:res=1280 --lights lamps "
                                "--frames 1 --warmup 0 --size 64x36 --error-every 0 --quiet --out %s/onetex",
                                test_binary(), g_tmp), 0);
    sb_table sum;
    summary_table(last_line_of(out), &sum);
    print_message("cube:res=1280 with 64 lamps: %s: %s\n", sb_table_get(&sum, 0, "status"), sb_table_get(&sum, 0, "reason"));
    assert_string_equal(sb_table_get(&sum, 0, "status"), "skipped");
    assert_non_null(strstr(sb_table_get(&sum, 0, "reason"), "the 64 lamps' 384 maps in one texture exceed what"));
    assert_non_null(strstr(sb_table_get(&sum, 0, "reason"), "grid=off keeps a texture a lamp"));
    sb_table_free(&sum);
}

/* A floor and a box under one lamp of the given range. */
static void write_lamp_scene(const char *path, double range) {
    sb_glb_scene s = {0};
    s.no_sun = true;
    s.lamps[0] = sb_v3_make(1.5, 3, 0.5);
    s.lamp_range[0] = range;
    s.nlamps = 1;
    sb_glb_box(sb_glb_new_mesh(&s, 0), -6, -0.2, -6, 6, 0, 6);
    sb_glb_box(sb_glb_new_mesh(&s, 0), -1, 0, -1, 1, 2, 1);
    assert_int_equal(sb_glb_write(&s, path), 0);
}

/* A lamp whose range reaches past the scene (valid glTF: 1e38) is the same lamp as one whose range is the scene's
 * diagonal: its range is held to the farthest corner of the scene's box, said once. Before, cube's far plane at
 * 1e38 put its near plane past every caster (err 0.94). */
static void test_range_past_the_scene(void **st) {
    (void)st;
    char far[4096], diag[4096], dirs[2][4096];
    snprintf(far, sizeof far, "%s/range-far.glb", g_tmp);
    snprintf(diag, sizeof diag, "%s/range-diag.glb", g_tmp);
    write_lamp_scene(far, 1e38);
    write_lamp_scene(diag, sqrt(12 * 12 + 2.2 * 2.2 + 12 * 12));   /* the box's diagonal */
    const char *files[2] = {far, diag};
    char out[16384];
    bool noted = false;
    for (int k = 0; k < 2; k++) {
        int rc = run_logged(out, sizeof out, "%s run %s auto cube:res=512 dpsm:res=512 atlas:res=512 raycast --frames 2 "
                            "--warmup 0 --size 160x90 --error-every 1 --out %s/range%d", test_binary(), files[k], g_tmp, k);
        assert_int_equal(rc, 0);
        if (k == 0) noted = strstr(out, "its range 1e+38 reaches past everything the scene holds: held to") != NULL;
        snprintf(dirs[k], sizeof dirs[k], "%s", last_line_of(out));
    }
    sb_table a, b;
    summary_table(dirs[0], &a);
    summary_table(dirs[1], &b);
    assert_int_equal(a.nrows, 4);
    for (int r = 0; r < a.nrows; r++) {
        double ea = cell(&a, r, "err_rate_mean"), eb = cell(&b, r, "err_rate_mean");
        print_message("%s: err_rate %g (range 1e38), %g (range the diagonal)\n", sb_table_get(&a, r, "technique"), ea, eb);
        assert_string_equal(sb_table_get(&a, r, "status"), "ok");
        assert_true(isfinite(ea) && ea < 0.15);   /* dpsm: 0.086 at its seam; 1e38 unfitted: 0.94 */
        assert_true(ea == eb);
    }
    sb_table_free(&a);
    sb_table_free(&b);
    assert_true(noted);   /* said once, at load */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_lamp_of_towers_night),
        cmocka_unit_test(test_set_is_its_lights),
        cmocka_unit_test(test_moved_lamp_changes_only_its_pixels),
        cmocka_unit_test(test_lamps_by_cluster),
        cmocka_unit_test(test_atlas_under_budget),
        cmocka_unit_test(test_atlas_cache_still),
        cmocka_unit_test(test_atlas_cache_with_movers),
        cmocka_unit_test(test_batch_lights),
        cmocka_unit_test(test_tune_atlas_under_memory),
        cmocka_unit_test(test_spots),
        cmocka_unit_test(test_bad_lights),
        cmocka_unit_test(test_range_past_the_scene),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
