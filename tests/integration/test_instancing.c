/* Shared geometry (sb_draw.proto): a level tiled by node instancing is drawn
 * and traced from one copy of each mesh, each repeat through its transform;
 * the same level with a mesh of its own per node (tile-gltf --copies) is
 * drawn and traced from its own vertices. The two must give the same
 * pictures and figures, frame by frame, up to the rounding of where a copy's
 * vertices lie (a few pixels of an error rate), while the shared one holds a
 * fraction of the memory, on the GPU and on the CPU:
 *  - towers tiled 3 x 3 with the tiles turned (closed meshes: shared even
 *    when turned), cascades per cascade and layered, SDSM;
 *  - zdm2 tiled 2 x 1 (open single-sided meshes moved only: their
 *    light-facing triangles shared with the sun);
 *  - a lamp between two moved copies of an open wall, one facing it and one
 *    turned away from it: a lamp's copies face it each their own way, so the
 *    shared scene must draw the turned-away one as the copies do (no
 *    shadow), not with its proto's facing. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "glb.h"
#include "image.h"
#include "render.h"
#include "scene_load.h"
#include "support.h"
#include "table.h"

static char g_out[65536];

SB_TEST_SCRATCH("sbinstancing")

/* per frame, equal whichever way the level is held */
static const char *const g_counts[] = {"triangles", "shadow_triangles", "draw_calls", "shadow_draw_calls"};
static const char *const g_errors[] = {"err_rate", "err_false_shadow", "err_false_lit"};

/* Renders specs on scene along `auto` (frames of it, each evaluated); the results folder into dir. */
static void render_frames(const char *scene, const char *specs, const char *size, int frames, const char *tag, char *dir,
                          size_t len) {
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s run %s auto %s --frames %d --size %s --error-every 1 "
                                "--warmup 0 --quiet --out %s/%s", test_binary(), scene, specs, frames, size, g_tmp, tag),
                     0);
    snprintf(dir, len, "%s", last_line_of(g_out));
}

static void render(const char *scene, const char *specs, const char *size, const char *tag, char *dir, size_t len) {
    render_frames(scene, specs, size, 3, tag, dir, len);
}

static void tile(const char *src, const char *dst, const char *how) {
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "%s/scripts/tile-gltf %s %s %s > /dev/null", getenv("SB_SOURCE_ROOT"), src, dst, how);
    assert_int_equal(system(cmd), 0);
}

/* The scene's shared draws, GPU bytes and CPU bytes (its arrays). */
static double gpu_bytes(const char *path, uint32_t *shared, double *cpu) {
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, path, NULL, &err));
    *shared = s.instance_draws;
    *cpu = sb_scene_cpu_bytes(&s);
    double b = sb_gpu_scene_bytes(&s);
    sb_scene_free(&s);
    return b;
}

/* src tiled `how` into g_tmp/NAME-shared.glb and (--copies) NAME-copies.glb; their shared draws and GPU bytes. */
typedef struct pair {
    char shared[4096], copies[4096];
    uint32_t ns, nc;
    double bs, bc;              /* GPU bytes */
    double cs, cc;              /* CPU bytes */
} pair;

static void tile_pair(const char *src, const char *name, const char *how, pair *p) {
    char copies_how[256];
    snprintf(p->shared, sizeof p->shared, "%s/%s-shared.glb", g_tmp, name);
    snprintf(p->copies, sizeof p->copies, "%s/%s-copies.glb", g_tmp, name);
    snprintf(copies_how, sizeof copies_how, "%s --copies", how);
    tile(src, p->shared, how);
    tile(src, p->copies, copies_how);
    p->bs = gpu_bytes(p->shared, &p->ns, &p->cs);
    p->bc = gpu_bytes(p->copies, &p->nc, &p->cc);
    print_message("%s %s: %u shared draws, GPU %.2f MiB, CPU %.2f MiB; copies: %u, %.2f MiB, %.2f MiB\n", name, how,
                  p->ns, p->bs / 1048576.0, p->cs / 1048576.0, p->nc, p->bc / 1048576.0, p->cc / 1048576.0);
}

/* The two results folders run for run and frame for frame: counts equal within count_tol (relative), error
 * figures within `pixels` pixels of the w x h picture, no warning, every run ok. */
static void same_figures(const char *a_dir, const char *b_dir, double count_tol, double pixels, int w, int h) {
    sb_table A, B;
    summary_table(a_dir, &A);
    summary_table(b_dir, &B);
    assert_int_equal(B.nrows, A.nrows);
    for (int r = 0; r < A.nrows; r++) {
        const char *tech = sb_table_get(&A, r, "technique");
        assert_string_equal(sb_table_get(&A, r, "status"), "ok");
        assert_string_equal(sb_table_get(&B, r, "status"), "ok");
        assert_string_equal(sb_table_get(&A, r, "warnings"), "");
        assert_string_equal(sb_table_get(&B, r, "warnings"), "");
        assert_string_equal(sb_table_get(&A, r, "params"), sb_table_get(&B, r, "params"));
        sb_table fa, fb;
        char path[8300];
        sb_err err;
        snprintf(path, sizeof path, "%s/%s.csv", a_dir, sb_table_get(&A, r, "run_id"));
        assert_true(sb_table_load(&fa, path, &err));
        snprintf(path, sizeof path, "%s/%s.csv", b_dir, sb_table_get(&B, r, "run_id"));
        assert_true(sb_table_load(&fb, path, &err));
        assert_int_equal(fb.nrows, fa.nrows);
        double worst = 0, shadowed = 0;
        for (int f = 0; f < fa.nrows; f++) {
            for (size_t k = 0; k < sizeof g_counts / sizeof *g_counts; k++) {
                double x = atof(sb_table_get(&fa, f, g_counts[k])), y = atof(sb_table_get(&fb, f, g_counts[k]));
                if (fabs(x - y) > count_tol * fmax(x, 1)) {
                    print_message("%s frame %d: %s %g shared, %g copies\n", tech, f, g_counts[k], x, y);
                    fail();
                }
            }
            for (size_t k = 0; k < sizeof g_errors / sizeof *g_errors; k++) {
                double x = atof(sb_table_get(&fa, f, g_errors[k])), y = atof(sb_table_get(&fb, f, g_errors[k]));
                worst = fmax(worst, fabs(x - y) * w * h);
            }
            shadowed += atof(sb_table_get(&fa, f, "err_false_shadow"));
            assert_true(atof(sb_table_get(&fa, f, "geom_mismatch")) == 0);
            assert_true(atof(sb_table_get(&fb, f, "geom_mismatch")) == 0);
        }
        print_message("%-6s %-44.44s: error figures at most %.1f pixels apart (false shadow, shared: %.5f)\n", tech,
                      sb_table_get(&A, r, "params"), worst, shadowed / fa.nrows);
        assert_true(worst <= pixels);
        sb_table_free(&fa);
        sb_table_free(&fb);
    }
    sb_table_free(&A);
    sb_table_free(&B);
}

static void test_towers_turned(void **st) {
    (void)st;
    char src[4096], a[4096], b[4096];
    snprintf(src, sizeof src, "%s/towers.glb", g_tmp);
    copy_bundled("towers.glb", src);
    pair p;
    tile_pair(src, "towers", "3 3 --turn", &p);
    assert_true(p.ns >= 500);
    assert_int_equal(p.nc, 0);
    assert_true(p.bs < 0.25 * p.bc);
    assert_true(p.cs < 0.25 * p.cc);   /* the CPU holds each mesh once too */
    const char *specs = "sm:res=512 pssm:res=512 pssm:res=512:layered=gs sdsm:res=512";
    render(p.shared, specs, "320x180", "towers-shared", a, sizeof a);
    render(p.copies, specs, "320x180", "towers-copies", b, sizeof b);
    same_figures(a, b, 0, 4, 320, 180);
}

static void test_zdm2_open_moved(void **st) {
    (void)st;
    char src[4096], a[4096], b[4096];
    snprintf(src, sizeof src, "%s/sauerbraten_zdm2/zdm2.glb", getenv("SB_SHARED_SCENES"));
    if (access(src, R_OK) != 0) {
        print_message("%s not present; skipped\n", src);
        skip();
    }
    pair p;
    tile_pair(src, "zdm2", "2 1", &p);
    assert_true(p.ns >= 16);
    assert_int_equal(p.nc, 0);
    assert_true(p.bs < 0.55 * p.bc);
    assert_true(p.cs < 0.55 * p.cc);
    render(p.shared, "sm:res=1024 pssm:res=1024", "320x180", "zdm2-shared", a, sizeof a);
    render(p.copies, "sm:res=1024 pssm:res=1024", "320x180", "zdm2-copies", b, sizeof b);
    /* a copy chunked on its own may cut its triangles elsewhere, and an edge-on one face the sun either way */
    same_figures(a, b, 1e-3, 12, 320, 180);
}

/* A floor, and an open quad facing +x at x = -2 and at x = +2 (one mesh twice, or two meshes), a lamp between. */
static void write_walls(const char *path, bool shared) {
    sb_glb_scene s = {0};
    s.no_sun = true;
    s.lamps[0] = sb_v3_make(0, 1.2, 0);
    s.nlamps = 1;
    sb_glb_mesh *floor = sb_glb_new_mesh(&s, 0);
    sb_glb_box(floor, -8, -0.2, -4, 8, 0, 4);
    for (int k = 0; k < (shared ? 1 : 2); k++) {
        sb_glb_mesh *q = sb_glb_new_mesh(&s, 2);
        double x = shared ? 0 : (k ? 2 : -2);
        uint32_t v0 = sb_glb_vert(q, x, 0, -1.5, 1, 0, 0), v1 = sb_glb_vert(q, x, 0, 1.5, 1, 0, 0);
        uint32_t v2 = sb_glb_vert(q, x, 2.5, 1.5, 1, 0, 0), v3 = sb_glb_vert(q, x, 2.5, -1.5, 1, 0, 0);
        sb_glb_tri(q, v0, v2, v1);   /* counter-clockwise seen from +x */
        sb_glb_tri(q, v0, v3, v2);
        q->no_node = shared;
    }
    if (shared) {
        sb_glb_node(&s, true, "{\"mesh\":1,\"translation\":[-2,0,0]}");
        sb_glb_node(&s, true, "{\"mesh\":1,\"translation\":[2,0,0]}");
    }
    assert_int_equal(sb_glb_write(&s, path), 0);
}

/* A scene of the test's own written shared and as copies (write(path, shared)): the shared one has `want_shared`
 * shared draws, the copies none, and the two render `specs` to the same figures within `pixels`. */
static void own_scene_twins(const char *name, void (*write)(const char *path, bool shared), uint32_t want_shared,
                            const char *specs, double pixels) {
    char shared[4096], copies[4096], a[4096], b[4096], tag[300];
    snprintf(shared, sizeof shared, "%s/%s-shared.glb", g_tmp, name);
    snprintf(copies, sizeof copies, "%s/%s-copies.glb", g_tmp, name);
    write(shared, true);
    write(copies, false);
    uint32_t ns, nc;
    double cpu;
    gpu_bytes(shared, &ns, &cpu);
    gpu_bytes(copies, &nc, &cpu);
    print_message("%s: %u shared draws (copies twin %u)\n", name, ns, nc);
    assert_int_equal(ns, want_shared);
    assert_int_equal(nc, 0);
    snprintf(tag, sizeof tag, "%s-shared", name);
    render(shared, specs, "320x180", tag, a, sizeof a);
    snprintf(tag, sizeof tag, "%s-copies", name);
    render(copies, specs, "320x180", tag, b, sizeof b);
    same_figures(a, b, 0, pixels, 320, 180);
}

static void test_lamp_between_copies(void **st) {
    (void)st;
    own_scene_twins("walls", write_walls, 1, "cube dpsm", 4);
}

/* A floor and one box mesh placed three times: first at 1e-6 of its size far out on the floor, then twice at its
 * size (shared: one mesh for the three nodes; else a mesh of its own each, the same vertices). */
static void write_tiny_first(const char *path, bool shared) {
    sb_glb_scene s = {0};
    sb_glb_mesh *floor = sb_glb_new_mesh(&s, 0);
    sb_glb_box(floor, -8, -0.2, -8, 8, 0, 8);
    static const char *const placed[3] = {"\"translation\":[7.3,0,6.1],\"scale\":[1e-6,1e-6,1e-6]",
                                          "\"translation\":[0.37,0,-0.21]", "\"translation\":[-3.1,0,2.3]"};
    for (int k = 0; k < (shared ? 1 : 3); k++) {
        sb_glb_mesh *box = sb_glb_new_mesh(&s, 2);
        sb_glb_box(box, -0.7, 0, -0.7, 0.7, 1.9, 0.7);
        box->no_node = true;
    }
    for (int k = 0; k < 3; k++) sb_glb_node(&s, true, "{\"mesh\":%d,%s}", shared ? 1 : 1 + k, placed[k]);
    assert_int_equal(sb_glb_write(&s, path), 0);
}

/* Shared geometry is as precise as its copies: a placement is never drawn or traced magnified from a proto placed
 * smaller (a first placement at 1e-6 held the box in floats quantized at its position, and the placements at
 * scale 1 drew and traced that magnified: sm's err_rate 0.032 against the copies' 0.0016). The two full-size
 * boxes share one copy of their own. */
static void test_tiny_first_placement(void **st) {
    (void)st;
    /* one shared draw: the third placement from the second, the tiny first a copy of its own */
    own_scene_twins("tiny", write_tiny_first, 1, "sm:res=1024 raycast", 2);
}

/* Two images of one frame: how many pixels differ (any channel by more than a step of 8 bits). */
static long pixels_apart(const char *a, const char *b) {
    int wa, ha, wb, hb;
    float *pa, *pb;
    sb_err err;
    assert_true(sb_image_read_rgb(a, &wa, &ha, &pa, &err));
    assert_true(sb_image_read_rgb(b, &wb, &hb, &pb, &err));
    assert_int_equal(wa, wb);
    assert_int_equal(ha, hb);
    long n = 0;
    for (long i = 0; i < (long)wa * ha; i++)
        n += fabsf(pa[3 * i] - pb[3 * i]) > 1.5f / 255 || fabsf(pa[3 * i + 1] - pb[3 * i + 1]) > 1.5f / 255 ||
             fabsf(pa[3 * i + 2] - pb[3 * i + 2]) > 1.5f / 255;
    free(pa);
    free(pb);
    return n;
}

/* Every bundled scene tiled 2 x 1 by node instancing against its copies twin, in one batch: the same visibility
 * and error images and the same err_rate of a frame along its auto path (a sun map and a lamp's cube, each where
 * the scene has its light). */
static void test_every_bundled_scene_tiled(void **st) {
    (void)st;
    char list[8192], bench[4200];
    assert_int_equal(run_logged(list, sizeof list, "cd %s && ls *.glb", getenv("SB_DATA_DIR")), 0);
    snprintf(bench, sizeof bench, "%s/bundled.bench", g_tmp);
    FILE *f = fopen(bench, "w");
    assert_non_null(f);
    fprintf(f, "path au auto\n");
    int n = 0;
    for (char *name = strtok(list, "\n"); name; name = strtok(NULL, "\n")) {
        char src[4300], stem[256];
        snprintf(stem, sizeof stem, "all-%.*s", (int)(strlen(name) - 4), name);   /* beside the other tests' tiles */
        snprintf(src, sizeof src, "%s/%s", getenv("SB_DATA_DIR"), name);
        pair p;
        tile_pair(src, stem, "2 1", &p);
        fprintf(f, "scene %s-s %s au\nscene %s-c %s au\n", stem, p.shared, stem, p.copies);
        n++;
    }
    fprintf(f, "defaults --frames 1 --warmup 0 --size 160x90 --error-every 1 --images 1\nsm:res=512 cube:res=128\n");
    fclose(f);
    assert_true(n >= 16);
    assert_int_equal(run_logged(g_out, sizeof g_out, "%s batch %s --out %s/bundled --quiet", test_binary(), bench, g_tmp),
                     0);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", last_line_of(g_out));
    sb_table t;
    summary_table(dir, &t);
    int compared = 0;
    for (int r = 0; r < t.nrows; r++) {
        const char *scene = sb_table_get(&t, r, "scene");
        size_t len = strlen(scene);
        if (len < 2 || strcmp(scene + len - 2, "-s")) continue;
        int twin = -1;
        for (int q = 0; q < t.nrows; q++)
            if (!strncmp(sb_table_get(&t, q, "scene"), scene, len - 2) && !strcmp(sb_table_get(&t, q, "scene") + len - 2, "-c") &&
                strlen(sb_table_get(&t, q, "scene")) == len && !strcmp(sb_table_get(&t, q, "params"), sb_table_get(&t, r, "params")) &&
                !strcmp(sb_table_get(&t, q, "technique"), sb_table_get(&t, r, "technique")))
                twin = q;
        assert_true(twin >= 0);
        assert_string_equal(sb_table_get(&t, r, "status"), sb_table_get(&t, twin, "status"));
        if (strcmp(sb_table_get(&t, r, "status"), "ok")) continue;   /* skipped both: no light of its kind */
        long apart = 0;
        for (int fr = 0; fr < 1; fr++)
            for (int k = 0; k < 2; k++) {
                char a[4400], b[4400];
                snprintf(a, sizeof a, "%s/images/%s_f%04d_%s.png", dir, sb_table_get(&t, r, "run_id"), fr, k ? "error" : "vis");
                snprintf(b, sizeof b, "%s/images/%s_f%04d_%s.png", dir, sb_table_get(&t, twin, "run_id"), fr, k ? "error" : "vis");
                apart += pixels_apart(a, b);
            }
        double ea = atof(sb_table_get(&t, r, "err_rate_mean")), eb = atof(sb_table_get(&t, twin, "err_rate_mean"));
        print_message("%-22s %-6s err_rate %.6g shared, %.6g copies; %ld pixels of the images apart\n", scene,
                      sb_table_get(&t, r, "technique"), ea, eb, apart);
        assert_true(apart <= 4);
        assert_true(fabs(ea - eb) * 160 * 90 <= 2);
        compared++;
    }
    assert_true(compared >= 16);
    sb_table_free(&t);
}

/* Every technique in every draw path it has (per pass or layered by a geometry shader or by the vertex shader's
 * gl_Layer; one GL call a draw or one indirect call a pass) on towers-night tiled 2 x 1, against its copies twin:
 * a draw path that reads a shared draw's vertices without its transform (common.glsl's sb_world) draws the second
 * tile's casters over the first's, and its error parts from the copies' by thousands of pixels. The lamp
 * techniques shadow lamp 7, one of the second tile's. The instancing suite's figures are the conformance test of
 * shared geometry: every technique and mode here, held to its copies twin. */
static void test_every_mode_on_shared_geometry(void **st) {
    (void)st;
    char src[4096], a[4096], b[4096];
    snprintf(src, sizeof src, "%s/towers-night.glb", g_tmp);
    copy_bundled("towers-night.glb", src);
    pair p;
    tile_pair(src, "night", "2 1", &p);
    assert_true(p.ns > 0);
    assert_int_equal(p.nc, 0);
    /* planar last: its receiver pass draws by scene triangle numbers, so it leaves nothing shared for the runs
       after it (sb_gpu_share), which would then pass whatever their vertex stages do */
    /* maps of 512 texels (256 a lamp's face): a caster drawn at the wrong tile moves thousands of pixels at any
       resolution, and the default 2048s took 2.5 s of these 4.5 s a set on llvmpipe */
    const char *specs = "sm:res=512 pssm:res=512:layered=off,gs,vs,on sdsm:res=512:layered=off,gs,vs,on volumes "
                        "lispsm:res=512 tsm:res=512 psm:res=512 psm:res=512:cube=on:layered=off,gs,vs,on virtual raycast "
                        "cube:res=256:light=7:layered=off,gs,vs,on dpsm:res=256:light=7 atlas:res=256 planar";
    /* one indirect call a pass goes through the same vertex stages: every stage there once (the layered ones, the
       lamps', virtual's pages, the atlas's tiles), not every parameter again */
    const char *indirect = "sm:res=512 pssm:res=512:layered=gs,vs psm:res=512:cube=on:layered=vs virtual "
                           "cube:res=256:light=7:layered=gs,vs dpsm:res=256:light=7 atlas:res=256 planar";
    const char *submits[] = {"direct", "indirect"}, *sets[] = {specs, indirect};
    for (int k = 0; k < 2; k++) {
        char run[8192], tag[64];
        snprintf(run, sizeof run, "%s --sun 135,40 --submit %s", sets[k], submits[k]);
        snprintf(tag, sizeof tag, "night-shared-%s", submits[k]);
        render_frames(p.shared, run, "160x90", 1, tag, a, sizeof a);
        snprintf(tag, sizeof tag, "night-copies-%s", submits[k]);
        render_frames(p.copies, run, "160x90", 1, tag, b, sizeof b);
        same_figures(a, b, 0, 4, 160, 90);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_towers_turned),
        cmocka_unit_test(test_zdm2_open_moved),
        cmocka_unit_test(test_lamp_between_copies),
        cmocka_unit_test(test_tiny_first_placement),
        cmocka_unit_test(test_every_bundled_scene_tiled),
        cmocka_unit_test(test_every_mode_on_shared_geometry),
    };
    return cmocka_run_group_tests_name("instancing", tests, setup, teardown);
}
