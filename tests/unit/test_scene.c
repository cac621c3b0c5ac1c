/* Scene loading (real glTF through tinygltf), chunking, BVH culling. */
#define _DEFAULT_SOURCE /* setenv, truncate, popen */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "json.h"
#include "motion.h"
#include "scene_load.h"
#include "scene.h"
#include "support.h"

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
    assert_false(s.planes_found);   /* a load leaves the search to the first need */
    sb_scene_find_planes(&s);
    assert_true(s.planes_found);
    assert_int_equal(s.plane_count, 1);   /* the cubes' faces are far below 10% of the largest face */
    const sb_plane *p = &s.planes[0];
    assert_int_equal(p->tri_count, 8);
    for (uint32_t k = 0; k < 8; k++) assert_int_equal(p->tris[k], 5 * 12 - 1 + k);   /* in triangle order */
    assert_true(fabs(fabs(p->n[1]) - 1) < 1e-9 && fabs(p->area - 1e4) < 1e-6);
    sb_scene_free(&s);
}

/* ---- the scene cache ---- */

static char g_cache[64];

static void load_expect(const char *path, bool from_cache, sb_scene *s) {
    sb_err err = {{0}};
    bool ok = sb_scene_load(s, path, NULL, &err);
    if (!ok) print_message("%s\n", err.msg);
    assert_true(ok);
    print_message("%s: %s, %.1f ms\n", path, s->from_cache ? "from the cache" : "read", s->load_ms);
    assert_int_equal(s->from_cache, from_cache);
}

static void same_scene(const sb_scene *a, const sb_scene *b) {
    assert_int_equal(a->vertex_count, b->vertex_count);
    assert_int_equal(a->index_count, b->index_count);
    assert_int_equal(a->draw_count, b->draw_count);
    assert_memory_equal(a->vertices, b->vertices, (size_t)a->vertex_count * SB_VERTEX_BYTES);
    assert_memory_equal(a->indices, b->indices, (size_t)a->index_count * 4);
    for (uint32_t i = 0; i < a->draw_count; i++) {
        const sb_draw *x = &a->draws[i], *y = &b->draws[i];
        assert_true(x->first_index == y->first_index && x->index_count == y->index_count && x->closed == y->closed &&
                    x->double_sided == y->double_sided && x->material == y->material && x->node == y->node);
        assert_memory_equal(&x->box, &y->box, sizeof x->box);
    }
    assert_true(a->content_hash == b->content_hash && a->has_sun == b->has_sun && a->light_count == b->light_count);
    assert_memory_equal(&a->origin, &b->origin, sizeof a->origin);
    assert_memory_equal(&a->bounds, &b->bounds, sizeof a->bounds);
    assert_true(a->planes_found && b->planes_found);   /* an entry is written and read with its planes */
    assert_int_equal(a->plane_count, b->plane_count);
    for (uint32_t i = 0; i < a->plane_count; i++) {
        assert_int_equal(a->planes[i].tri_count, b->planes[i].tri_count);
        assert_memory_equal(a->planes[i].tris, b->planes[i].tris, a->planes[i].tri_count * 4);
    }
    assert_int_equal(a->bvh.node_count, b->bvh.node_count);
    assert_int_equal(a->features.prims, b->features.prims);
}

static void copy_file(const char *from, const char *to) {
    size_t n = 0;
    sb_err err;
    char *d = sb_read_file(from, &n, &err);
    assert_non_null(d);
    assert_true(sb_write_file_atomic(to, d, n, &err));
    free(d);
}

/* The one entry file in the cache folder. */
static void entry_file(char *out, size_t len) {
    char cmd[256];
    snprintf(cmd, sizeof cmd, "ls %s/*.sbscene", g_cache);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    assert_non_null(fgets(out, (int)len, p));
    out[strcspn(out, "\n")] = 0;
    assert_null(fgets(cmd, sizeof cmd, p));   /* only one */
    pclose(p);
}

/* A scene read before comes from the cache, equal in every array; a changed
 * file, a changed buffer it refers to, a damaged entry are read afresh; the
 * load's messages are said again; SB_SCENE_CACHE=off reads every time. */
static void test_scene_cache(void **st) {
    (void)st;
    assert_int_equal(tmp_folder(g_cache, sizeof g_cache, "sbcache"), 0);
    setenv("SB_SCENE_CACHE", g_cache, 1);
    char glb[128], bundled[4096], entry[512];
    snprintf(glb, sizeof glb, "%s/scene.glb", g_cache);
    assert_true(sb_resolve_bundled("towers", ".glb", bundled, sizeof bundled));
    copy_file(bundled, glb);
    sb_scene a, b;
    load_expect(glb, false, &a);
    load_expect(glb, true, &b);
    same_scene(&a, &b);
    assert_true(b.load_ms < a.load_ms);
    sb_scene_free(&a);
    sb_scene_free(&b);
    /* damaged entries: cut short, one byte changed */
    entry_file(entry, sizeof entry);
    assert_int_equal(truncate(entry, 1000), 0);
    load_expect(glb, false, &a);
    sb_scene_free(&a);
    FILE *f = fopen(entry, "r+b");
    assert_non_null(f);
    fseek(f, 5000, SEEK_SET);
    int c = fgetc(f);
    fseek(f, 5000, SEEK_SET);
    fputc(c ^ 1, f);
    fclose(f);
    load_expect(glb, false, &a);
    load_expect(glb, true, &b);
    sb_scene_free(&a);
    sb_scene_free(&b);
    /* another file at the same name */
    assert_true(sb_resolve_bundled("plane-box", ".glb", bundled, sizeof bundled));
    copy_file(bundled, glb);
    load_expect(glb, false, &a);
    assert_int_equal(sb_scene_triangles(&a), 24);
    sb_scene_free(&a);
    /* an external buffer changed under the same .gltf; the load's notice said again */
    char gltf[128], bin[128];
    snprintf(gltf, sizeof gltf, "%s/tri.gltf", g_cache);
    snprintf(bin, sizeof bin, "%s/tri.bin", g_cache);
    gltf_tri t = {.uri = "tri.bin", .node0 = "\"mesh\":0,\"rotation\":[0,0,0,2]"};
    assert_true(gltf_tri_write(gltf, &t));
    float pos[11] = {0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0};
    uint16_t *idx = (uint16_t *)&pos[9];
    idx[0] = 0, idx[1] = 1, idx[2] = 2;
    sb_err err;
    assert_true(sb_write_file_atomic(bin, pos, 44, &err));
    load_expect(gltf, false, &a);
    sb_log_capture(true);
    load_expect(gltf, true, &b);
    sb_log_capture(false);
    print_message("said again: %s", sb_log_captured());
    assert_non_null(strstr(sb_log_captured(), "not unit quaternions and are normalised"));
    same_scene(&a, &b);
    sb_scene_free(&b);
    pos[3] = 2;
    assert_true(sb_write_file_atomic(bin, pos, 44, &err));
    load_expect(gltf, false, &b);
    assert_true(a.content_hash != b.content_hash);
    assert_memory_not_equal(a.vertices, b.vertices, (size_t)a.vertex_count * SB_VERTEX_BYTES);
    sb_scene_free(&a);
    /* the same .gltf copied into another folder: never the first folder's entry, whatever lies beside it. Beside
       a different .bin: that .bin's geometry; beside none, or a cut one: refused as a load without the cache is */
    char other[160], ogltf[200], obin[200];
    snprintf(other, sizeof other, "%s/other", g_cache);
    assert_int_equal(mkdir(other, 0755), 0);
    snprintf(ogltf, sizeof ogltf, "%s/tri.gltf", other);
    snprintf(obin, sizeof obin, "%s/tri.bin", other);
    copy_file(gltf, ogltf);
    pos[3] = 5;   /* another vertex than the first folder's */
    assert_true(sb_write_file_atomic(obin, pos, 44, &err));
    load_expect(ogltf, false, &a);
    assert_memory_not_equal(a.vertices, b.vertices, (size_t)a.vertex_count * SB_VERTEX_BYTES);
    assert_true(a.content_hash != b.content_hash);
    sb_scene_free(&a);
    load_expect(ogltf, true, &a);   /* its own entry, found again */
    sb_scene_free(&a);
    load_expect(gltf, true, &a);    /* and the first folder's, still its own */
    same_scene(&a, &b);
    sb_scene_free(&a);
    sb_scene_free(&b);
    assert_true(sb_write_file_atomic(obin, pos, 22, &err));   /* cut in half */
    expect_scene_refused(ogltf, "tri.bin");
    assert_int_equal(unlink(obin), 0);                         /* missing */
    expect_scene_refused(ogltf, "tri.bin");
    setenv("SB_SCENE_CACHE", "off", 1);
    load_expect(glb, false, &a);
    sb_scene_free(&a);
    load_expect(glb, false, &a);
    /* without the cache nothing searches for planes until asked; asked, it finds plane-box's ground */
    assert_false(a.planes_found);
    sb_scene_find_planes(&a);
    assert_true(a.plane_count >= 1);
    assert_true(fabs(a.planes[0].area - 40 * 40) < 1e-6 && a.planes[0].tri_count == 2);   /* the 40 x 40 ground */
    sb_scene_free(&a);
    unsetenv("SB_SCENE_CACHE");
    assert_int_equal(tmp_remove(g_cache), 0);
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

/* A real level tiled 3x3 by node instancing (scripts/tile-gltf): every mesh
 * decoded once and placed nine times. The copies must be the original moved:
 * nine times its triangles, draws, single-sided and closed draws, and its
 * large planes; the tiles' boxes one grid step apart. */
static void test_tiled_level(void **st) {
    (void)st;
    const char *src = shared("sauerbraten_zdm2/zdm2.glb");
    if (access(src, R_OK) != 0) {
        print_message("%s not present; skipped\n", src);
        skip();
    }
    char tiled[64] = "/tmp/sbtileXXXXXX", cmd[8192];
    assert_non_null(mkdtemp(tiled));
    strcat(tiled, "/zdm2x3.glb");
    snprintf(cmd, sizeof cmd, "%s/scripts/tile-gltf %s %s 3 3 > /dev/null", getenv("SB_SOURCE_ROOT"), src, tiled);
    assert_int_equal(system(cmd), 0);
    sb_scene one, nine;
    sb_err err;
    assert_true(sb_scene_load(&one, src, NULL, &err));
    assert_true(sb_scene_load(&nine, tiled, NULL, &err));
    print_message("zdm2: %llu triangles, %u draws; 3x3: %llu, %u draws, %.0f ms\n",
                  (unsigned long long)sb_scene_triangles(&one), one.draw_count,
                  (unsigned long long)sb_scene_triangles(&nine), nine.draw_count, nine.load_ms);
    assert_int_equal(sb_scene_triangles(&nine), 9 * sb_scene_triangles(&one));
    assert_int_equal(nine.vertex_count, one.vertex_count);   /* the tiles' triangles held once */
    assert_int_equal(nine.index_count, one.index_count);
    assert_int_equal(nine.draw_count, 9 * one.draw_count);
    assert_int_equal(nine.single_sided_draws, 9 * one.single_sided_draws);
    uint32_t closed1 = 0, closed9 = 0;
    for (uint32_t i = 0; i < one.draw_count; i++) closed1 += one.draws[i].closed;
    for (uint32_t i = 0; i < nine.draw_count; i++) closed9 += nine.draws[i].closed;
    assert_int_equal(closed9, 9 * closed1);
    /* the extent: the level, then two more tiles 1.1 level widths apart in X and Z (3.2 widths), the height
     * unchanged: the tiles do not overlap */
    sb_v3 e1 = sb_v3_sub(one.bounds.hi, one.bounds.lo), e9 = sb_v3_sub(nine.bounds.hi, nine.bounds.lo);
    print_message("extent %g x %g x %g -> %g x %g x %g\n", e1.x, e1.y, e1.z, e9.x, e9.y, e9.z);
    assert_true(fabs(e9.y - e1.y) < 1e-3 * e1.y);
    assert_true(fabs(e9.x - 3.2 * e1.x) < 1e-3 * e1.x && fabs(e9.z - 3.2 * e1.z) < 1e-3 * e1.z);
    /* every vertex of the first tile's first draw is the original's, moved by the same offset */
    sb_v3 off = sb_v3_sub(one.origin, nine.origin);
    double worst = 0;
    for (uint32_t i = 0; i < one.vertex_count; i++) {
        const float *a = sb_vertex(&one, i), *b = sb_vertex(&nine, i);
        worst = fmax(worst, fabs(a[0] + off.x - b[0]) + fabs(a[1] + off.y - b[1]) + fabs(a[2] + off.z - b[2]));
    }
    print_message("tile (0, 0) against the level: largest vertex difference %.3g\n", worst);
    assert_true(worst < 1e-3);
    /* the eight other tiles repeat tile (0, 0): every draw of theirs names its draw there and the transform that
     * places it; chunk for chunk the same triangles (its proto's run and vertices), placed where the file puts
     * them (the box made from the file's positions). Again with the tiles turned by quarter turns (--turn). */
    assert_int_equal(one.instance_draws, 0);
    assert_int_equal(nine.instance_draws, 8 * one.draw_count);
    for (uint32_t d = 0; d < nine.draw_count; d++)
        if (nine.draws[d].proto != d) assert_true(sb_xform_translation_only(nine.draws[d].xform));
    sb_scene_free(&nine);
    snprintf(cmd, sizeof cmd, "%s/scripts/tile-gltf %s %s 3 3 --turn --force > /dev/null", getenv("SB_SOURCE_ROOT"), src,
             tiled);
    assert_int_equal(system(cmd), 0);
    assert_true(sb_scene_load(&nine, tiled, NULL, &err));
    assert_int_equal(nine.instance_draws, 8 * one.draw_count);
    double ext = sb_v3_len(e9), off_most = 0;
    uint32_t turned = 0;
    for (uint32_t d = 0; d < nine.draw_count; d++) {
        const sb_draw *dr = &nine.draws[d], *p = &nine.draws[dr->proto];
        if (dr->proto == d) continue;
        assert_int_equal(p->proto, dr->proto);
        assert_int_equal(p->index_count, dr->index_count);
        assert_int_equal(p->vertex_count, dr->vertex_count);
        assert_int_equal(p->first_index, dr->first_index);
        assert_int_equal(p->first_vertex, dr->first_vertex);
        turned += !sb_xform_translation_only(dr->xform);
        sb_aabb placed = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
        for (uint32_t i = 0; i < dr->index_count; i++) {
            float w[3];
            sb_draw_point(&nine, dr, nine.indices[dr->first_index + i], w);
            placed.lo = sb_v3_min(placed.lo, sb_v3_make(w[0], w[1], w[2]));
            placed.hi = sb_v3_max(placed.hi, sb_v3_make(w[0], w[1], w[2]));
        }
        off_most = fmax(off_most, fmax(sb_v3_len(sb_v3_sub(placed.lo, dr->box.lo)), sb_v3_len(sb_v3_sub(placed.hi, dr->box.hi))));
    }
    print_message("%u shared draws (%u turned): placed boxes against the file's, at most %.3g apart (extent %.0f)\n",
                  nine.instance_draws, turned, off_most, ext);
    assert_true(turned >= 6 * one.draw_count);   /* tiles 1, 2, 3, 5, 6, 7 of 0..8 turn */
    assert_true(off_most < 1e-5 * ext);
    /* a scale that is not uniform (conf-instanced's instances) is not shared: each is a copy */
    sb_scene ci;
    char conf[4096];
    snprintf(conf, sizeof conf, "%s/conf-instanced.glb", getenv("SB_DATA_DIR"));
    assert_true(sb_scene_load(&ci, conf, NULL, &err));
    assert_true(ci.features.instances >= 3);
    assert_int_equal(ci.instance_draws, 0);
    sb_scene_free(&ci);
    sb_scene_free(&one);
    sb_scene_free(&nine);
    remove(tiled);
    *strrchr(tiled, '/') = 0;
    rmdir(tiled);
}

/* A glTF file is parsed once a load: by the project's reader, its checks and tinygltf's model built from that one
 * document (tinygltf's own parsers are not even linked: the features test's ldd and nm see to the library). */
static void test_one_parse_a_load(void **st) {
    (void)st;
    const char *files[] = {"desert", SB_HAVE_DRACO ? "towers-draco" : "towers", "conf-skin",
                           shared("sauerbraten_zdm2/zdm2.glb")};
    setenv("SB_SCENE_CACHE", "off", 1);
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        if (i == 3 && access(files[i], R_OK) != 0) continue;
        uint64_t before = sb_json_parses();
        sb_scene s;
        sb_err err;
        assert_true(sb_scene_load(&s, files[i], NULL, &err));
        print_message("%s: %llu parse(s)\n", files[i], (unsigned long long)(sb_json_parses() - before));
        assert_int_equal(sb_json_parses() - before, 1);
        sb_scene_free(&s);
    }
    unsetenv("SB_SCENE_CACHE");
}

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
    for (int trial = 0; trial < 400; trial++) {
        if (trial == 200) {   /* draws moved (as a pose moves them) and the tree refit, not rebuilt: still exact */
            for (uint32_t d = 0; d < s.draw_count; d += 3) {
                sb_v3 dv = sb_v3_make(rand() % 41 - 20, rand() % 11 - 5, rand() % 41 - 20);
                s.draws[d].box.lo = sb_v3_add(s.draws[d].box.lo, dv);
                s.draws[d].box.hi = sb_v3_add(s.draws[d].box.hi, dv);
            }
            sb_scene_refit_bvh(&s);
        }
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
        sb_scene_cull(&s, (const double(*)[4])planes, 4, visit, &m);
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

/* An animated scene comes from the cache with its clips: the hit is a cached load, and posed at any time it holds
 * the vertices, boxes and bounds of the file read afresh and posed alike (the skinned humanoid, the bundled movers'
 * rigid clips); another --anim-speed is another entry (its run ids differ). */
static void test_animated_scene_cache(void **st) {
    (void)st;
    char dir[64];
    assert_int_equal(tmp_folder(dir, sizeof dir, "sbanimcache"), 0);
    setenv("SB_SCENE_CACHE", dir, 1);
    char movers[4096], human[4096];
    assert_true(sb_resolve_bundled("movers", ".glb", movers, sizeof movers));
    snprintf(human, sizeof human, "%s/godot_mannequiny/mannequiny.glb", getenv("SB_SHARED_SCENES"));
    const char *files[2] = {movers, human};
    for (int f = 0; f < 2; f++) {
        if (access(files[f], R_OK) != 0) {
            print_message("%s not present: left out\n", files[f]);
            continue;
        }
        sb_scene a, b;
        load_expect(files[f], false, &a);
        load_expect(files[f], true, &b);
        assert_true(sb_scene_moves(&a) && sb_scene_moves(&b));
        assert_int_equal(a.moving_draws, b.moving_draws);
        assert_true(a.content_hash == b.content_hash);
        assert_string_equal(a.anim, b.anim);
        for (int k = 0; k < 3; k++) {
            double t = 0.37 + 1.9 * k;
            assert_true(sb_scene_pose(&a, t));
            assert_true(sb_scene_pose(&b, t));
            sb_scene_sync_vertices(&a);   /* the CPU's vertices, as a reader asks for them */
            sb_scene_sync_vertices(&b);
            assert_memory_equal(a.vertices, b.vertices, (size_t)a.vertex_count * SB_VERTEX_BYTES);
            for (uint32_t i = 0; i < a.draw_count; i++) assert_memory_equal(&a.draws[i].box, &b.draws[i].box, sizeof(sb_aabb));
            assert_memory_equal(&a.bounds, &b.bounds, sizeof a.bounds);
        }
        sb_scene_free(&a);
        sb_scene_free(&b);
    }
    /* another speed is another entry: read, with its own content hash */
    sb_scene_opts fast = {.anim_speed = 3};
    sb_scene a, c;
    sb_err err;
    load_expect(movers, true, &a);
    assert_true(sb_scene_load(&c, movers, &fast, &err));
    assert_false(c.from_cache);
    assert_true(a.content_hash != c.content_hash);
    sb_scene_free(&a);
    sb_scene_free(&c);
    unsetenv("SB_SCENE_CACHE");
    assert_int_equal(tmp_remove(dir), 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane_box), cmocka_unit_test(test_desert_size), cmocka_unit_test(test_truck_town),
        cmocka_unit_test(test_zdm2),      cmocka_unit_test(test_hallway),     cmocka_unit_test(test_bvh_cull_exact),
        cmocka_unit_test(test_missing_file),       cmocka_unit_test(test_closed_and_planes),
        cmocka_unit_test(test_scene_cache),        cmocka_unit_test(test_tiled_level),
        cmocka_unit_test(test_animated_scene_cache),
        cmocka_unit_test(test_one_parse_a_load),
    };
    return cmocka_run_group_tests_name("scene", tests, NULL, NULL);
}
