/* The conformance set (scenes/conformance.h): each glTF feature drawn and
 * ray-cast as its author made it. Two checks a scene:
 *  - the reference's rays against the answer that follows from the geometry,
 *    on a grid of floor points (a feature the loader or the rays ignore moves
 *    or removes a shadow: no doubleSided, no alpha test, an unposed skin, one
 *    instance, misread quantized or sparse positions);
 *  - the rasterized techniques against the reference, through the CLI:
 *    raycast exact, the rasterizer and the rays on one geometry
 *    (geom_mismatch), and shadow maps that converge to the reference as their
 *    resolution grows (an alpha test or a culling rule the GL passes ignore
 *    leaves an error that no resolution removes). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene_load.h"
#include "conformance.h"
#include "reference.h"
#include "support.h"
#include "table.h"

static char g_out[16384];

#define sh(...) run_logged(g_out, sizeof g_out, __VA_ARGS__)

SB_TEST_SCRATCH("sbconf")

/* ---- the answers ---- */

typedef struct box {
    double lo[3], hi[3];
} box;

/* Does the ray p + t d (t > 0) cross the box? (slabs) */
static bool ray_box(sb_v3 p, sb_v3 d, const box *b) {
    double t0 = 1e-9, t1 = 1e30, o[3] = {p.x, p.y, p.z}, v[3] = {d.x, d.y, d.z};
    for (int k = 0; k < 3; k++) {
        if (fabs(v[k]) < 1e-15) {
            if (o[k] < b->lo[k] || o[k] > b->hi[k]) return false;
            continue;
        }
        double a = (b->lo[k] - o[k]) / v[k], c = (b->hi[k] - o[k]) / v[k];
        if (a > c) {
            double t = a;
            a = c, c = t;
        }
        t0 = fmax(t0, a), t1 = fmin(t1, c);
    }
    return t0 <= t1;
}

/* Where the ray from floor point p toward the sun crosses the casters' height. */
static void at_height(sb_v3 p, sb_v3 sun, double *x, double *z) {
    double t = (SB_CONF_H - p.y) / sun.y;
    *x = p.x + t * sun.x, *z = p.z + t * sun.z;
}

static bool in_rect(double x, double z, const double r[4]) { return x > r[0] && x < r[1] && z > r[2] && z < r[3]; }

typedef enum { A_NONE, A_RECT_A, A_RECT_B, A_RECTS, A_CARD, A_BOXES } answer_kind;

typedef struct answer {
    answer_kind kind;
    box boxes[8];
    int nboxes;
} answer;

static bool shadowed(const answer *a, sb_v3 p, sb_v3 sun) {
    const double ra[4] = SB_CONF_RECT_A, rb[4] = SB_CONF_RECT_B;
    double x, z;
    at_height(p, sun, &x, &z);
    switch (a->kind) {
    case A_NONE: return false;
    case A_RECT_A: return in_rect(x, z, ra);
    case A_RECT_B: return in_rect(x, z, rb);
    case A_RECTS: return in_rect(x, z, ra) || in_rect(x, z, rb);
    case A_CARD:
        return fabs(x) < SB_CONF_CARD && fabs(z) < SB_CONF_CARD &&
               ((long)floor(x + SB_CONF_CARD) + (long)floor(z + SB_CONF_CARD)) % 2 == 0;
    case A_BOXES:
        for (int k = 0; k < a->nboxes; k++)
            if (ray_box(p, sun, &a->boxes[k])) return true;
        return false;
    }
    return false;
}

/* The reference on a grid of floor points against the answer; points within
 * 0.03 of an edge of the answer are left out. Returns the points compared. */
static answer simple(answer_kind k) {
    answer a;
    memset(&a, 0, sizeof a);
    a.kind = k;
    return a;
}

static long check_reference(const char *scene, const sb_scene_opts *so, const answer *a) {
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, scene, so, &err));
    sb_reference r;
    assert_true(sb_reference_build(&r, &s, &err));
    const int n = 241;
    sb_ref_point *pts = calloc((size_t)n * n, sizeof *pts);
    unsigned char *vis = calloc((size_t)n * n, 1), *expect = calloc((size_t)n * n, 1);
    long m = 0, shadow = 0, wrong = 0;
    const double d = 0.03;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            sb_v3 p = sb_v3_make(-12 + 0.1 * i, 0, -12 + 0.1 * j);
            bool e = shadowed(a, p, s.sun);
            if (shadowed(a, sb_v3_make(p.x + d, 0, p.z), s.sun) != e || shadowed(a, sb_v3_make(p.x - d, 0, p.z), s.sun) != e ||
                shadowed(a, sb_v3_make(p.x, 0, p.z + d), s.sun) != e || shadowed(a, sb_v3_make(p.x, 0, p.z - d), s.sun) != e)
                continue;
            sb_v3 q = sb_v3_sub(p, s.origin);
            pts[m] = (sb_ref_point){{(float)q.x, (float)q.y, (float)q.z}, {0, 1, 0}, 1e-4f};
            expect[m++] = e;
        }
    sb_reference_visibility(&r, s.sun, pts, (int)m, vis, 2);
    for (long k = 0; k < m; k++) {
        shadow += expect[k];
        wrong += (vis[k] == 0) != expect[k];
    }
    print_message("%s (blend %s, pose %s): %ld floor points, %ld shadowed by the answer, %ld differ\n", scene,
                  sb_blend_policy_name(so->blend), so->pose ? "given" : "own", m, shadow, wrong);
    assert_int_equal(wrong, 0);
    assert_true(m > n * n / 2);
    free(pts);
    free(vis);
    free(expect);
    sb_reference_free(&r);
    sb_scene_free(&s);
    return shadow;
}

static void test_double_sided(void **st) {
    (void)st;
    sb_scene_opts so = {0};
    /* sheet A (double-sided) casts; sheet B (single-sided, facing down, away from the sun) does not */
    assert_true(check_reference("conf-double-sided", &so, (const answer[]){simple(A_RECT_A)}) > 500);
}

static void test_blend_policies(void **st) {
    (void)st;
    sb_scene_opts so = {0};
    assert_true(check_reference("conf-blend", &so, (const answer[]){simple(A_RECT_B)}) > 500); /* mask: only alpha 0.8 */
    so.blend = SB_BLEND_OPAQUE;
    assert_true(check_reference("conf-blend", &so, (const answer[]){simple(A_RECTS)}) > 1000);
    so.blend = SB_BLEND_NONE;
    assert_int_equal(check_reference("conf-blend", &so, (const answer[]){simple(A_NONE)}), 0);
}

static void test_alpha_card(void **st) {
    (void)st;
    sb_scene_opts so = {0};
    assert_true(check_reference("conf-alpha-card", &so, (const answer[]){simple(A_CARD)}) > 1000);
}

static void test_skin(void **st) {
    (void)st;
    const double L = SB_CONF_ARM_LEN, h = SB_CONF_H;
    /* the file's own pose: the elbow turned 90 degrees, segment two standing up */
    answer up = {A_BOXES, {{{0, h - 0.5, -0.5}, {L, h + 0.5, 0.5}}, {{L - 0.5, h, -0.5}, {L + 0.5, h + L, 0.5}}}, 2};
    sb_scene_opts so = {0};
    check_reference("conf-skin", &so, &up);
    /* --pose 0: the animation's first key, the arm straight (its bind pose) */
    answer flat = {A_BOXES, {{{0, h - 0.5, -0.5}, {2 * L, h + 0.5, 0.5}}}, 1};
    so.pose = true;
    so.pose_time = 0;
    check_reference("conf-skin", &so, &flat);
    so.pose_time = 1;
    check_reference("conf-skin", &so, &up);
}

static void test_instanced_quantized_sparse(void **st) {
    (void)st;
    answer inst = simple(A_BOXES);
    inst.nboxes = SB_CONF_INSTANCES;
    for (int k = 0; k < SB_CONF_INSTANCES; k++)
        inst.boxes[k] = (box){{-8 + 4 * k - 0.5, 0, -0.5}, {-8 + 4 * k + 0.5, 1 + 0.5 * k, 0.5}};
    sb_scene_opts so = {0};
    check_reference("conf-instanced", &so, &inst);
    answer q = {A_BOXES, {{{-6, 0, -2}, {-2, 2, 2}}, {{2, 0, -2}, {6, 2, 2}}}, 2};
    check_reference("conf-quantized", &so, &q);
}

/* ---- the rasterized techniques against the reference ---- */

static void load_summary(sb_table *t) {
    char dir[4096];
    size_t n = strcspn(g_out, "\n");
    assert_true(n < sizeof dir);
    memcpy(dir, g_out, n);
    dir[n] = 0;
    summary_table(dir, t);
}

/* Renders run with leak detection off in the sanitizer build (the loader
 * suite): Mesa's driver, unloaded before exit, leaves 112 bytes LeakSanitizer
 * cannot attribute; address and undefined-behaviour checks stay on. */
#define RENDER "ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\" %s run"

static double col(const sb_table *t, int r, const char *name) { return atof(sb_table_get(t, r, name)); }

/* raycast is exact, every run's rays and rasterizer agree, and sm's error
 * falls as its resolution grows to a small floor. */
static void check_raster(const char *scene, const char *opts, double sm_max) {
    assert_int_equal(sh(RENDER " %s %s raycast sm:res=256 sm:res=2048 --frames 3 --size 320x180 --error-every 1 "
                        "--warmup 0 --quiet --out %s/r %s", test_binary(), scene, scene, g_tmp, opts), 0);
    sb_table t;
    load_summary(&t);
    assert_int_equal(t.nrows, 3);
    for (int r = 0; r < 3; r++) {
        print_message("%s %s %s: err_rate %s, geom_mismatch %s, err_floor %s\n", scene, opts,
                      sb_table_get(&t, r, "params"), sb_table_get(&t, r, "err_rate_mean"),
                      sb_table_get(&t, r, "geom_mismatch"), sb_table_get(&t, r, "err_floor"));
        assert_string_equal(sb_table_get(&t, r, "status"), "ok");
        assert_true(col(&t, r, "geom_mismatch") <= 1e-4);
        assert_true(col(&t, r, "err_floor") <= 1e-3);
    }
    assert_true(col(&t, 0, "err_rate_mean") <= 1e-4);
    assert_true(col(&t, 2, "err_rate_mean") < col(&t, 1, "err_rate_mean"));
    assert_true(col(&t, 2, "err_rate_mean") <= sm_max);
    sb_table_free(&t);
}

static void test_raster_matches_reference(void **st) {
    (void)st;
    check_raster("conf-double-sided", "", 1e-3);
    check_raster("conf-blend", "", 1e-3);
    check_raster("conf-blend", "--blend-casters opaque", 1e-3);
    check_raster("conf-alpha-card", "", 2e-3);
    check_raster("conf-skin", "", 1e-3);
    check_raster("conf-skin", "--pose 0", 1e-3);
    check_raster("conf-instanced", "", 1e-3);
    check_raster("conf-quantized", "", 1e-3);
}

/* A single-sided wall facing a lamp and not the sun: the lamp's shadow
 * passes keep it (cube's error against the reference stays at its floor, and
 * both hemispheres of dpsm draw it), the sun's pass leaves it out, as the
 * reference does. Fails when a point-light technique culls against the sun
 * (cube err_rate 0.35 then). dpsm's own error here is the paraboloid's: two
 * large triangles across its rim, not checked. */
static void test_lamp_wall(void **st) {
    (void)st;
    assert_int_equal(sh(RENDER " conf-lamp-wall conf-lamp-wall raycast cube dpsm sm --frames 3 --size 320x180 "
                        "--error-every 1 --warmup 0 --quiet --out %s/l", test_binary(), g_tmp), 0);
    sb_table t;
    load_summary(&t);
    assert_int_equal(t.nrows, 4);
    for (int r = 0; r < 4; r++)
        print_message("conf-lamp-wall %s: err_rate %s, shadow_triangles %s, geom_mismatch %s\n", sb_table_get(&t, r, "technique"),
                      sb_table_get(&t, r, "err_rate_mean"), sb_table_get(&t, r, "shadow_triangles_mean"),
                      sb_table_get(&t, r, "geom_mismatch"));
    assert_true(col(&t, 0, "err_rate_mean") <= 1e-4);           /* raycast, toward the lamp */
    assert_true(col(&t, 1, "err_rate_mean") <= 1e-3);           /* cube */
    assert_true(col(&t, 2, "shadow_triangles_mean") == 2 * 14); /* dpsm: slab (12) and wall (2), both hemispheres */
    assert_true(col(&t, 3, "shadow_triangles_mean") == 12);     /* sm: the slab; the wall faces away from the sun */
    assert_true(col(&t, 3, "err_rate_mean") <= 1e-3);
    for (int r = 0; r < 4; r++) assert_true(col(&t, r, "geom_mismatch") <= 1e-4);
    sb_table_free(&t);
}

/* The alpha card's lamp: cube's shadow passes test the alpha of the card's
 * texels as the reference's rays do, per face and layered both ways (the
 * checker's cells, twice as large on the floor): err_rate 0.0013. Without the
 * test in the shadow pass the whole card casts: 0.124 (measured). dpsm's error
 * here is the paraboloid's over the slab's two large triangles (0.126), not
 * checked; that its pass has the test is planebox's
 * test_lamp_passes_skip_alpha_test. */
static void test_lamp_alpha_card(void **st) {
    (void)st;
    assert_int_equal(sh(RENDER " conf-alpha-card conf-alpha-card cube:layered=off cube:layered=gs cube:layered=vs dpsm "
                        "--frames 3 --size 320x180 --error-every 1 --warmup 0 --quiet --out %s/la", test_binary(), g_tmp), 0);
    sb_table t;
    load_summary(&t);
    assert_int_equal(t.nrows, 4);
    for (int r = 0; r < 4; r++) {
        print_message("conf-alpha-card %s %.16s: err_rate %s, shadow_triangles %s, geom_mismatch %s\n",
                      sb_table_get(&t, r, "technique"), strstr(sb_table_get(&t, r, "params"), "layered") ?
                      strstr(sb_table_get(&t, r, "params"), "layered") : "", sb_table_get(&t, r, "err_rate_mean"),
                      sb_table_get(&t, r, "shadow_triangles_mean"), sb_table_get(&t, r, "geom_mismatch"));
        assert_string_equal(sb_table_get(&t, r, "status"), "ok");
        assert_true(col(&t, r, "geom_mismatch") <= 1e-4);
    }
    for (int r = 0; r < 3; r++) assert_true(col(&t, r, "err_rate_mean") <= 3e-3);
    sb_table_free(&t);
}

/* The Draco copy of towers is the same scene: same triangles, same shadows.
 * Draco stores the triangles in another order, and where two faces of a box
 * meet at an edge at equal depth the shadow map keeps whichever came first:
 * a few pixels may differ (measured: 0.0221348 against 0.0221358 with a
 * normal offset of 1 texel, 0.00992545 against 0.00989955 with 0.25; one
 * pixel of a frame moves the mean by about 1e-5), nothing more. */
static void test_draco_copy(void **st) {
    (void)st;
    if (!SB_HAVE_DRACO) skip(); /* no towers-draco without Draco; test_gltf checks the refusal */
    double err[2], tris[2];
    const char *scenes[2] = {"towers", "towers-draco"};
    for (int k = 0; k < 2; k++) {
        assert_int_equal(sh(RENDER " %s towers sm:res=1024 --frames 3 --size 320x180 --error-every 1 --warmup 0 --quiet "
                            "--out %s/d", test_binary(), scenes[k], g_tmp), 0);
        sb_table t;
        load_summary(&t);
        err[k] = col(&t, 0, "err_rate_mean");
        tris[k] = col(&t, 0, "scene_triangles");
        sb_table_free(&t);
    }
    print_message("towers err_rate %g (%g triangles), towers-draco %g (%g)\n", err[0], tris[0], err[1], tris[1]);
    assert_true(tris[0] == tris[1] && tris[0] > 9000);
    assert_true(fabs(err[0] - err[1]) <= 1e-4);
}

/* The built-in paths stand outside the model: at every sampled camera no
 * surface within 1% of the scene's diagonal in 14 directions, no ray from it
 * meeting the back of a closed surface first (it would be inside), and the
 * view's centre ray free for 5% of the diagonal. Checked with Embree's rays,
 * not the path module's own ray casting. */
static void check_path_outside(const char *scene, const char *kind) {
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, scene, NULL, &err));
    sb_reference r;
    assert_true(sb_reference_build(&r, &s, &err));
    sb_path p;
    assert_true(sb_path_load(&p, kind, &s, &err));
    double diag = sb_v3_len(sb_v3_sub(s.bounds.hi, s.bounds.lo));
    int bad = 0;
    const int frames = 30;
    for (int i = 0; i < frames; i++) {
        sb_camera c = sb_path_camera(&p, i, frames, 16.0 / 9, &s);
        sb_v3 o = sb_v3_sub(c.pos, s.origin);
        float from[15][3], to[15][3];
        for (int k = 0; k < 15; k++) {
            sb_v3 d = k == 14 ? c.forward : k < 6 ? sb_v3_make(k == 0 ? 1 : k == 1 ? -1 : 0, k == 2 ? 1 : k == 3 ? -1 : 0,
                                                             k == 4 ? 1 : k == 5 ? -1 : 0)
                                          : sb_v3_make((k - 6) & 1 ? 1 : -1, (k - 6) & 2 ? 1 : -1, (k - 6) & 4 ? 1 : -1);
            sb_v3 q = sb_v3_add(o, sb_v3_scale(sb_v3_norm(d), 10 * diag));
            from[k][0] = (float)o.x, from[k][1] = (float)o.y, from[k][2] = (float)o.z;
            to[k][0] = (float)q.x, to[k][1] = (float)q.y, to[k][2] = (float)q.z;
        }
        sb_ref_hit h[15];
        sb_reference_rays(&r, (const float(*)[3])from, (const float(*)[3])to, 15, h, 1);
        int fail = h[14].t >= 0.05 * diag ? -1 : 14;
        for (int k = 0; k < 14 && fail < 0; k++)
            if (h[k].t < 0.01 * diag || (h[k].t < INFINITY && !h[k].front && s.single_sided_draws)) fail = k;
        if (fail >= 0) {
            print_message("%s %s frame %d at (%.3g, %.3g, %.3g): ray %d meets %s at %.3g (diagonal %.3g)\n", scene,
                          kind, i, c.pos.x, c.pos.y, c.pos.z, fail, h[fail].front ? "a front" : "a back", h[fail].t,
                          diag);
            bad++;
        }
    }
    print_message("%s %s: %d of %d views not clear\n", scene, kind, bad, frames);
    assert_int_equal(bad, 0);
    sb_path_free(&p);
    sb_reference_free(&r);
    sb_scene_free(&s);
}

static void test_auto_path_outside(void **st) {
    (void)st;
    const char *bundled[] = {"plane-box", "desert", "towers", "overhangs", "towers-night", "conf-skin", "conf-alpha-card"};
    for (size_t i = 0; i < sizeof bundled / sizeof bundled[0]; i++) {
        check_path_outside(bundled[i], "auto");
        check_path_outside(bundled[i], "orbit");
    }
    const char *shared[] = {"truck_town/town_model.gltf", "sauerbraten_zdm2/zdm2.glb",
                            "space_ship_hallway/space_ship_hallway.glb"};
    for (size_t i = 0; i < sizeof shared / sizeof shared[0]; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", getenv("SB_SHARED_SCENES"), shared[i]);
        if (access(path, R_OK) != 0) {
            print_message("%s: not here, left out\n", path);
            continue;
        }
        check_path_outside(path, "auto");
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_double_sided),
        cmocka_unit_test(test_blend_policies),
        cmocka_unit_test(test_alpha_card),
        cmocka_unit_test(test_skin),
        cmocka_unit_test(test_instanced_quantized_sparse),
        cmocka_unit_test(test_raster_matches_reference),
        cmocka_unit_test(test_lamp_wall),
        cmocka_unit_test(test_lamp_alpha_card),
        cmocka_unit_test(test_draco_copy),
        cmocka_unit_test(test_auto_path_outside),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
