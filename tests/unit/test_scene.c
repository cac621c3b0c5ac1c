/* Scene loading (real glTF through tinygltf), chunking, BVH culling. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene.h"

static const char *shared(const char *rel) {
    static char buf[4096];
    const char *d = getenv("SB_SHARED_SCENES");
    snprintf(buf, sizeof buf, "%s/%s", d ? d : "../shared/scenes", rel);
    return buf;
}

static void test_plane_box(void **st) {
    (void)st;
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, "plane-box", NULL, &err));
    assert_int_equal(sb_scene_triangles(&s), 24);
    assert_int_equal(s.draw_count, 2);
    assert_true(s.has_sun);
    /* bounds: slab [-20,20]x[-0.5,0]x[-20,20] plus the box up to y=2 */
    sb_v3 lo = sb_v3_add(s.bounds.lo, s.origin), hi = sb_v3_add(s.bounds.hi, s.origin);
    assert_true(fabs(lo.x + 20) < 1e-6 && fabs(hi.y - 2) < 1e-6 && fabs(lo.y + 0.5) < 1e-6);
    sb_scene_free(&s);
}

static void test_desert_size(void **st) {
    (void)st;
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, "desert", NULL, &err));
    print_message("desert: %llu triangles, %u draws\n", (unsigned long long)sb_scene_triangles(&s), s.draw_count);
    assert_true(sb_scene_triangles(&s) >= 200000);
    sb_scene_free(&s);
}

/* A unit cube as 24 vertices (4 per face, welded by position) and 12
 * outward-wound triangles; `drop` leaves out that many triangles from the
 * end, `flip` turns triangle 0 around. */
static void add_cube(sb_scene *s, double x0, int drop, bool flip, bool double_sided) {
    static const int face[6][4][3] = {
        {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
        {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},
        {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}};
    double pos[72];
    uint32_t idx[36];
    for (int f = 0; f < 6; f++) {
        for (int v = 0; v < 4; v++)
            for (int k = 0; k < 3; k++) pos[3 * (4 * f + v) + k] = face[f][v][k] + (k == 0 ? x0 : 0);
        const uint32_t q[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++) idx[6 * f + k] = 4 * (uint32_t)f + q[k];
    }
    if (flip) {
        uint32_t t = idx[1];
        idx[1] = idx[2];
        idx[2] = t;
    }
    sb_prim_desc d = {.positions = pos, .vertex_count = 24, .indices = idx, .index_count = 36 - 3 * (uint32_t)drop,
                      .color = {1, 1, 1, 1}, .double_sided = double_sided};
    sb_scene_add_prim(s, &d);
}

/* Closed meshes (back faces culled in shadow passes) and large planes
 * (planar shadows), found in linear time: checked against hand-made cases. */
static void test_closed_and_planes(void **st) {
    (void)st;
    sb_scene s;
    sb_err err;
    sb_scene_begin(&s);
    add_cube(&s, 0, 0, false, false);  /* closed */
    add_cube(&s, 2, 1, false, false);  /* a hole */
    add_cube(&s, 4, 0, true, false);   /* one triangle wound the other way */
    add_cube(&s, 6, 0, false, true);   /* double-sided */
    add_cube(&s, 8, 0, false, false);  /* closed */
    /* a 100 x 100 ground quad at y = 0 split into 8 triangles, the first 4 before the cubes' */
    double g[27];
    uint32_t gi[24];
    for (int i = 0; i < 9; i++) g[3 * i] = (i % 3) * 50.0 - 50, g[3 * i + 1] = 0, g[3 * i + 2] = (i / 3) * 50.0 - 50;
    for (int c = 0, k = 0; c < 4; c++) {
        uint32_t a = (uint32_t)(c % 2 + 3 * (c / 2));
        const uint32_t t[6] = {a, a + 3, a + 4, a, a + 4, a + 1};
        for (int j = 0; j < 6; j++) gi[k++] = t[j];
    }
    sb_prim_desc d = {.positions = g, .vertex_count = 9, .indices = gi, .index_count = 24, .color = {1, 1, 1, 1}};
    sb_scene_add_prim(&s, &d);
    const bool closed[6] = {true, false, false, false, true, false};
    for (int i = 0; i < 6; i++) assert_int_equal(s.draws[i].closed, closed[i]);
    assert_true(sb_scene_finish(&s, &err));
    assert_int_equal(s.plane_count, 1);   /* the cubes' faces are far below 10% of the largest face */
    const sb_plane *p = &s.planes[0];
    assert_int_equal(p->tri_count, 8);
    for (uint32_t k = 0; k < 8; k++) assert_int_equal(p->tris[k], 5 * 12 - 1 + k);   /* in triangle order */
    assert_true(fabs(fabs(p->n[1]) - 1) < 1e-9 && fabs(p->area - 1e4) < 1e-6);
    sb_scene_free(&s);
}

static void load_shared(const char *rel, uint64_t expect_tris) {
    const char *p = shared(rel);
    if (access(p, R_OK) != 0) {
        print_message("%s not present; skipped\n", p);
        skip();
    }
    sb_scene s;
    sb_err err = {{0}};
    bool ok = sb_scene_load(&s, p, NULL, &err);
    if (!ok) print_message("%s\n", err.msg);
    assert_true(ok);
    print_message("%s: %llu triangles, %u draws, %u textures decoded, %.0f ms\n", rel,
                  (unsigned long long)sb_scene_triangles(&s), s.draw_count, s.features.textures_decoded, s.load_ms);
    assert_int_equal(sb_scene_triangles(&s), expect_tris);
    for (uint32_t i = 0; i < s.draw_count; i++) assert_true(s.draws[i].index_count / 3 <= 4096);
    sb_scene_free(&s);
}

/* triangle counts from each folder's SOURCE.txt (scene-graph traversal) */
static void test_truck_town(void **st) { (void)st; load_shared("truck_town/town_model.gltf", 30477); }
static void test_zdm2(void **st) { (void)st; load_shared("sauerbraten_zdm2/zdm2.glb", 58772); }
static void test_hallway(void **st) { (void)st; load_shared("space_ship_hallway/space_ship_hallway.glb", 53400); }

typedef struct {
    char *hit;
} mark;
static void visit(uint32_t d, void *u) { ((mark *)u)->hit[d]++; }

static void test_bvh_cull_exact(void **st) {
    (void)st;
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, "towers", NULL, &err));
    srand(7);
    char *hit = calloc(s.draw_count, 1);
    for (int trial = 0; trial < 200; trial++) {
        double planes[4][4];
        for (int k = 0; k < 4; k++) {
            sb_v3 n = sb_v3_norm(sb_v3_make(rand() / (double)RAND_MAX - 0.5, rand() / (double)RAND_MAX - 0.5,
                                            rand() / (double)RAND_MAX - 0.5));
            planes[k][0] = n.x;
            planes[k][1] = n.y;
            planes[k][2] = n.z;
            planes[k][3] = (rand() / (double)RAND_MAX) * 120;
        }
        memset(hit, 0, s.draw_count);
        mark m = {hit};
        sb_bvh_cull(&s, (const double(*)[4])planes, 4, visit, &m);
        for (uint32_t d = 0; d < s.draw_count; d++) {
            bool out = false;
            for (int k = 0; k < 4; k++) out |= sb_aabb_outside_plane(&s.draws[d].box, planes[k]);
            assert_int_equal(hit[d], out ? 0 : 1);
        }
    }
    free(hit);
    sb_scene_free(&s);
}

static void expect_load_error(const char *file, const char *needle) {
    sb_scene s;
    sb_err err = {{0}};
    assert_false(sb_scene_load(&s, file, NULL, &err));
    print_message("%s\n", err.msg);
    assert_non_null(strstr(err.msg, needle));
}

static void test_missing_file(void **st) {
    (void)st;
    expect_load_error("/nonexistent/x.glb", "/nonexistent/x.glb: cannot open");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane_box), cmocka_unit_test(test_desert_size), cmocka_unit_test(test_truck_town),
        cmocka_unit_test(test_zdm2),      cmocka_unit_test(test_hallway),     cmocka_unit_test(test_bvh_cull_exact),
        cmocka_unit_test(test_missing_file),       cmocka_unit_test(test_closed_and_planes),
    };
    return cmocka_run_group_tests_name("scene", tests, NULL, NULL);
}
