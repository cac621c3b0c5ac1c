/* Scenes that move (issue 49): glTF clips played on the path's clock, in the
 * rasterizer and in the exact reference alike, and the caches that must
 * invalidate for them.
 *
 *   - the bundled `movers` scene: a box slides along x by a node translation
 *     clip; at every evaluated frame its shadow's centroid, in the reference and
 *     in a shadow map, lies where the box's position at that frame's time puts
 *     it (worked out here by casting toward the sun against the box alone);
 *   - a still camera over it: cache=on cascades are drawn again only for the
 *     cascades a moved caster's box reaches, virtual pages likewise (fewer than
 *     cache=off, more than none), and stale_px is 0 on every evaluated frame;
 *     raycast's error and flicker stay exactly 0 while ref_flicker sees the
 *     shadows move;
 *   - real animated files (a skinned humanoid, a morph-target model): what the
 *     GPU holds is what the CPU posed, and raster and rays agree;
 *   - --anim none on an animated file gives the figures of the same file with its
 *     animations removed, bit for bit; bad input. */
#define _DEFAULT_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "eval.h"
#include "motion.h"
#include "pose.h"
#include "reference.h"
#include "scene_load.h"
#include "support.h"
#include "table.h"

static char g_tmp[64], g_out[65536];

#define sh(...) run_logged(g_out, sizeof g_out, __VA_ARGS__)

static int setup(void **st) {
    (void)st;
    return tmp_folder(g_tmp, sizeof g_tmp, "sbmotion");
}

static int teardown(void **st) {
    (void)st;
    return tmp_remove(g_tmp);
}

static bool open_scene(sb_session *s, const char *scene, const char *path, int w, int h, int frames, const char *anim,
                       sb_err *err) {
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    o.width = w, o.height = h, o.frames = frames, o.warmup = 0, o.anim = anim;
    memset(s, 0, sizeof *s);
    return sb_session_open(s, &o, scene, path, err);
}

/* The slider of `movers` (scenegen.c): its centre's x at clip time t (LINEAR keys -8 at 0 s, 8 at 4 s, -8 at 8 s). */
static double slider_x(double t) {
    t = fmod(t, 8);
    return t <= 4 ? -8 + 4 * t : 8 - 4 * (t - 4);
}

typedef struct centroid {
    double x, z;
    long n;
} centroid;

static void add_point(centroid *c, sb_v3 p) { c->x += p.x, c->z += p.z, c->n++; }
static void finish(centroid *c) {
    if (c->n) c->x /= c->n, c->z /= c->n;
}

/* A spec's run spec (the grammar's). */
static sb_run_spec spec_of(const char *text) {
    sb_run_spec *runs = NULL;
    int n = 0;
    sb_err err;
    assert_true(sb_spec_expand(text, NULL, &runs, &n, &err));
    assert_int_equal(n, 1);
    sb_run_spec r = runs[0];
    free(runs);
    return r;
}

static void test_box_shadow_follows_the_clip(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    const int n = 9, w = 480, h = 270;
    assert_true(open_scene(&s, "movers", "movers", w, h, n, NULL, &err));
    assert_true(sb_scene_moves(&s.scene));
    const char *specs[] = {"raycast", "sm:res=2048:filter=none"};
    for (int k = 0; k < 2; k++) {
        sb_run_spec spec = spec_of(specs[k]);
        sb_instance in;
        assert_true(sb_instance_create(&in, &s, &spec, n, &err));
        sb_eval_buf b;
        sb_eval_buf_init(&b, &s.gpu, false);
        int seq = 0;
        for (int pf = 0; pf < n; pf += 2) {
            sb_frame f;
            sb_error_metrics m;
            assert_true(sb_eval_frame(&s, &in, pf, n, 0, &seq, &b, &f, &m, &err));
            double t = sb_session_frame_time(&s, pf, n), x = slider_x(t);
            const double lo[3] = {x - 1, 0, -5}, hi[3] = {x + 1, 2, -3};
            sb_v3 sun = s.gpu.sun;
            centroid want = {0}, ref = {0}, got = {0};
            double foot = 0;   /* a pixel's footprint on the plane: the largest step between neighbours */
            for (int y = 0; y < h; y++)
                for (int xx = 0; xx < w; xx++) {
                    size_t i = (size_t)y * w + xx;
                    if (b.ref[i] == 128) continue;
                    const float *q = b.pos + 4 * i;
                    sb_v3 p = sb_v3_add(sb_v3_make(q[0], q[1], q[2]), s.scene.origin);
                    if (fabs(p.y) > 1e-3 || p.z < -9 || p.z > 0 || fabs(p.x) > 14) continue;   /* the track's strip */
                    const float *r = b.pos + 4 * (i + 1);
                    if (xx + 1 < w && b.ref[i + 1] != 128 && fabs(r[1] + s.scene.origin.y) <= 1e-3)   /* on the plane */
                        foot = fmax(foot, hypot(r[0] - q[0], r[2] - q[2]));
                    if (box_blocks(p, sun, 1e300, lo, hi)) add_point(&want, p);
                    if (b.ref[i] < 128) add_point(&ref, p);
                    if (b.vis[i] < 128) add_point(&got, p);
                }
            finish(&want), finish(&ref), finish(&got);
            double texel = 40.0 / 2048;   /* sm's map over the slab at least: a texel is no smaller */
            printf("%s t=%.2f slider x=%.2f: shadow centroid want (%.3f, %.3f) over %ld px, reference (%.3f, %.3f) "
                   "%ld, raster (%.3f, %.3f) %ld; pixel %.3f m; err %.5g geom_mismatch %.5g\n",
                   specs[k], t, x, want.x, want.z, want.n, ref.x, ref.z, ref.n, got.x, got.z, got.n, foot, m.err_rate,
                   m.geom_mismatch);
            assert_true(want.n > 100);
            /* the reference answers the box where the clip puts it: the same pixels, within a pixel's footprint */
            assert_true(hypot(ref.x - want.x, ref.z - want.z) <= foot);
            /* the shadow map's, within the footprint of a texel (or a pixel, the larger) */
            assert_true(hypot(got.x - want.x, got.z - want.z) <= fmax(foot, 4 * texel));
            assert_true(m.geom_mismatch == 0);
            if (k == 0) assert_true(m.err_rate == 0);   /* raycast: exactly the reference */
        }
        sb_eval_buf_free(&b);
        sb_instance_destroy(&in);
    }
    sb_session_close(&s);
}

/* The per-frame rows of a run of a results set, by technique and a text its params hold. */
static bool frames_of(const char *dir, const char *tech, const char *has, sb_table *t) {
    sb_table sum;
    summary_table(dir, &sum);
    bool found = false;
    for (int r = 0; r < sum.nrows && !found; r++) {
        if (strcmp(sb_table_get(&sum, r, "technique"), tech) || !strstr(sb_table_get(&sum, r, "params"), has)) continue;
        char path[4300];
        snprintf(path, sizeof path, "%s/%s.csv", dir, sb_table_get(&sum, r, "run_id"));
        sb_err err;
        found = sb_table_load(t, path, &err);
    }
    sb_table_free(&sum);
    return found;
}

static long cell(const sb_table *t, int r, const char *col) { return atol(sb_table_get(t, r, col)); }

static void test_caches_invalidate_what_moved(void **st) {
    (void)st;
    /* one mover (the slider), a still camera low over the street: the nearest cascade does not reach it */
    char path[4200];
    snprintf(path, sizeof path, "%s/still.path", g_tmp);
    FILE *pf = fopen(path, "w");
    assert_non_null(pf);
    fprintf(pf, "fov 60\nlook 0  0 6 -22  0 1 0\nlook 8  0 6 -22  0 1 0\n");
    fclose(pf);
    assert_int_equal(sh("%s run movers %s pssm:stable=on:cache=on pssm:stable=on virtual:cache=on virtual:cache=off "
                        "virtual:cache=on:split=on raycast --anim slide "
                        "--frames 9 --size 320x180 --error-every 2 --quiet --out %s/caches", test_binary(), path, g_tmp), 0);
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", last_line_of(g_out));
    sb_table p, von, voff, vsplit, sum;
    assert_true(frames_of(dir, "pssm", "cache=on", &p));
    assert_true(frames_of(dir, "virtual", "filter=hw:cache=on", &von));   /* its canonical text ends there */
    assert_true(frames_of(dir, "virtual", "cache=off", &voff));
    assert_true(frames_of(dir, "virtual", "split=on", &vsplit));
    int partial = 0;
    for (int r = 1; r < p.nrows; r++) {   /* frame 0 draws everything: nothing was kept yet */
        long moved = cell(&p, r, "casters_moved"), inval = cell(&p, r, "cascades_invalidated"),
             drawn = cell(&p, r, "cascades_rendered"), kept = cell(&p, r, "cascades_cached");
        long active = drawn + kept;
        printf("pssm frame %d: casters_moved %ld, cascades drawn %ld (invalidated %ld), kept %ld\n", r, moved, drawn,
               inval, kept);
        /* every frame is drawn at a pose of its own: the GPU's posing pass is timed in it, as a stage */
        assert_true(*sb_table_get(&p, r, "pose_ms") && atof(sb_table_get(&p, r, "pose_ms")) >= 0);
        /* a still camera: a cascade is drawn again only for a caster that moved into its volume */
        assert_int_equal(drawn, inval);
        if (moved) assert_true(inval > 0);
        partial += inval > 0 && inval < active;
        long pon = cell(&von, r, "pages_rendered"), poff = cell(&voff, r, "pages_rendered"),
             pinv = cell(&von, r, "pages_invalidated");
        printf("virtual frame %d: pages drawn cache=on %ld (invalidated %ld), cache=off %ld\n", r, pon, pinv, poff);
        assert_true(pon < poff);
        if (moved) assert_true(pon > 0 && pinv > 0);
        /* split=on: no still page is given up for the mover (only pages newly needed are drawn: the mover's own
           top moves under other pages), the mover drawn over copies of the pages it overlaps */
        long sdrawn = cell(&vsplit, r, "pages_rendered"), sdyn = cell(&vsplit, r, "pages_dynamic");
        printf("virtual split=on frame %d: pages drawn %ld, invalidated %s, the mover drawn over %ld\n", r, sdrawn,
               sb_table_get(&vsplit, r, "pages_invalidated"), sdyn);
        assert_true(sdrawn <= pon - pinv);
        assert_int_equal(cell(&vsplit, r, "pages_invalidated"), 0);
        if (moved) assert_true(sdyn > 0);
    }
    sb_table_free(&vsplit);
    assert_true(partial > 0);   /* some frames keep the cascades the mover does not reach */
    sb_table_free(&p);
    sb_table_free(&von);
    sb_table_free(&voff);
    summary_table(dir, &sum);
    for (int r = 0; r < sum.nrows; r++) {
        const char *tech = sb_table_get(&sum, r, "technique"), *stale = sb_table_get(&sum, r, "stale_px_max");
        bool cached = strstr(sb_table_get(&sum, r, "params"), "cache=on") != NULL;
        printf("%s %s: stale_px_max '%s', flicker_rate %s, ref_flicker %s\n", tech, cached ? "cache=on" : "",
               stale, sb_table_get(&sum, r, "flicker_rate_mean"), sb_table_get(&sum, r, "ref_flicker_mean"));
        if (cached) assert_true(*stale && atof(stale) == 0);   /* measured, and nothing stale */
        else assert_string_equal(stale, "");
        if (!strcmp(tech, "raycast")) {
            assert_true(atof(sb_table_get(&sum, r, "err_rate_max")) == 0);
            assert_true(atof(sb_table_get(&sum, r, "flicker_rate_max")) == 0);
            assert_true(atof(sb_table_get(&sum, r, "ref_flicker_mean")) > 0);   /* the shadows do move */
        }
    }
    sb_table_free(&sum);
    /* cached against drawn every frame, as the report pairs them: pssm's cache is a late parameter (left out of
       its text at off), virtual's is not; both pair */
    assert_int_equal(sh("%s compare %s --pair cache=off,on --format csv", test_binary(), dir), 0);
    assert_non_null(strstr(g_out, ",pssm,"));
    assert_non_null(strstr(g_out, ",virtual,"));
}

/* The GPU's posing pass against the CPU's pose, at a few clip times: every moving vertex's position within float
 * rounding (16 float epsilons of the scene's size) and its normal within 1e-5; each moving draw's box (the bounds that follow the joints)
 * holds its vertices as posed, and is no more than twice the exact box across; the pose alone poses nothing on
 * the CPU (its copy waits for a reader), a reader poses it once; and the vertices moved. by_gpu false: a file
 * whose moving placements the GPU leaves to the CPU (no normals): no pass, the CPU's vertices sent at each pose
 * (bit for bit), their boxes exact. block (bytes, 0: the GL's): storage blocks that small (SB_POSE_BLOCK_BYTES), so
 * that the pass poses in several runs of placements, each in several dispatches, as a GPU with small blocks would. */
static void gpu_equals_cpu(const char *file, const char *anim, bool by_gpu, long block, uint32_t groups) {
    sb_session s;
    sb_err err;
    char cap[32];
    snprintf(cap, sizeof cap, "%ld", block);
    if (block) setenv("SB_POSE_BLOCK_BYTES", cap, 1);
    bool opened = open_scene(&s, file, "orbit", 64, 36, 4, anim, &err);
    unsetenv("SB_POSE_BLOCK_BYTES");
    if (!opened) fail_msg("%s", err.msg);
    assert_true(sb_scene_moves(&s.scene));
    assert_int_equal(s.scene.instance_draws, 0);   /* the vertex buffer is the scene's array, in order */
    assert_true((s.gpu.pose != NULL) == by_gpu);   /* the GPU poses, or leaves every placement to the CPU */
    const sb_scene *sc = &s.scene;
    float *before = sb_xmalloc((size_t)sc->vertex_count * SB_VERTEX_BYTES);
    float *gpu = sb_xmalloc((size_t)sc->vertex_count * SB_VERTEX_BYTES);
    memcpy(before, sc->vertices, (size_t)sc->vertex_count * SB_VERTEX_BYTES);
    const double times[] = {0.1, 0.37, 1.3};
    for (int k = 0; k < 3; k++) {
        uint64_t cpu0 = sb_scene_cpu_poses(sc);
        sb_session_pose(&s, times[k]);
        sb_motion_stats ms = sb_motion_statistics(sc->motion);
        if (groups) assert_int_equal(ms.pose_groups, groups);   /* the pose's work in that many threads' shares */
        if (groups) assert_int_equal(ms.lone_places, 0);
        assert_true(sb_pose_run(s.gpu.pose, s.gpu.scene, s.gpu.vbo) == by_gpu);   /* as the next frame drawn would */
        uint32_t chunks, dispatches;
        sb_pose_dispatches(s.gpu.pose, &chunks, &dispatches);
        if (block) assert_true(chunks >= 2 && dispatches > chunks);   /* split as small blocks ask */
        else assert_true(chunks == by_gpu && dispatches == by_gpu);
        assert_int_equal(sb_scene_cpu_poses(sc), cpu0);   /* the pose alone: the GPU's (or the CPU-only ones') */
        glBindBuffer(GL_ARRAY_BUFFER, s.gpu.vbo);
        glGetBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)sc->vertex_count * SB_VERTEX_BYTES, gpu);
        sb_scene_sync_vertices(sc);
        sb_scene_sync_vertices(sc);
        assert_int_equal(sb_scene_cpu_poses(sc), cpu0 + by_gpu);   /* a reader's: once a pose, if the GPU posed */
        double size = sb_v3_len(sb_v3_sub(sc->bounds.hi, sc->bounds.lo)), dpos = 0, dnrm = 0, loose = 0;
        long compared = 0, moved = 0, outside = 0;
        for (uint32_t d = 0; d < sc->draw_count; d++) {
            const sb_draw *dr = &sc->draws[d];
            if (dr->motion == SB_DRAW_STILL) continue;
            for (uint32_t v = dr->first_vertex; v < dr->first_vertex + dr->vertex_count; v++) {
                const float *g = gpu + (size_t)v * SB_VERTEX_FLOATS, *c = sb_vertex(sc, v);
                for (int e = 0; e < 3; e++) dpos = fmax(dpos, fabs(g[e] - c[e])), dnrm = fmax(dnrm, fabs(g[3 + e] - c[3 + e]));
                moved += memcmp(before + (size_t)v * SB_VERTEX_FLOATS, c, 12) != 0;
                compared++;
            }
            sb_aabb exact = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
            for (uint32_t i = 0; i < dr->index_count; i++) {
                const float *c = sb_vertex(sc, sc->indices[dr->first_index + i]);
                sb_v3 p = sb_v3_make(c[0], c[1], c[2]);
                outside += p.x < dr->box.lo.x || p.y < dr->box.lo.y || p.z < dr->box.lo.z || p.x > dr->box.hi.x ||
                           p.y > dr->box.hi.y || p.z > dr->box.hi.z;
                exact.lo = sb_v3_min(exact.lo, p), exact.hi = sb_v3_max(exact.hi, p);
            }
            loose = fmax(loose, sb_v3_len(sb_v3_sub(dr->box.hi, dr->box.lo)) / sb_v3_len(sb_v3_sub(exact.hi, exact.lo)));
        }
        printf("(%u run(s) of placements, %u dispatch(es)) ", chunks, dispatches);
        printf("%s at %.2f s: %ld moving vertices, %ld of them away from the load's pose; the GPU's within %.3g of the "
               "CPU's (%.3g of the scene's %.3g), normals within %.3g; %ld outside their draw's box, the loosest box "
               "%.2fx the exact one across\n", file, times[k], compared, moved, dpos, dpos / size, size, dnrm, outside, loose);
        assert_true(compared > 0 && moved > 0);
        assert_true(dpos <= (by_gpu ? 2e-6 * size : 0));   /* 16 float epsilons; the CPU's own: equal */
        assert_true(dnrm <= (by_gpu ? 1e-5 : 0));
        assert_int_equal(outside, 0);
        assert_true(by_gpu ? loose >= 1 && loose <= 2 : loose == 1);
    }
    /* a reference built after the GPU posed the scene is built from the pose (the CPU's copy posed first) */
    sb_session_pose(&s, 2.1);
    uint64_t cpu0 = sb_scene_cpu_poses(sc);
    sb_reference r;
    assert_true(sb_reference_build(&r, sc, &err));
    assert_int_equal(sb_scene_cpu_poses(sc), cpu0 + by_gpu);
    sb_reference_free(&r);
    free(before);
    free(gpu);
    sb_session_close(&s);
}

static void test_real_animated_files(void **st) {
    (void)st;
    const char *files[][2] = {{"godot_mannequiny/mannequiny.glb", "run_root.001"},
                              {"playcanvas_morph_stress/morph-stress-test.glb", "all"}};
    for (int i = 0; i < 2; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", getenv("SB_SHARED_SCENES"), files[i][0]);
        if (access(path, R_OK) != 0) {
            print_message("%s: not here, left out\n", path);
            continue;
        }
        gpu_equals_cpu(path, files[i][1], true, 0, 0);
        if (i == 0) gpu_equals_cpu(path, files[i][1], true, 400000, 0);   /* its 3 placements: 2 runs, 4 dispatches */
        if (i == 0) {   /* three walkers (scripts/place-movers): a group each, posed and boxed on threads of their own */
            char three[4096];
            snprintf(three, sizeof three, "%s/movers-3.glb", g_tmp);
            assert_int_equal(sh("python3 %s/scripts/place-movers %s/plane-box.glb %s 3 %s --clip %s --force",
                                getenv("SB_SOURCE_ROOT"), getenv("SB_DATA_DIR"), path, three, files[i][1]), 0);
            gpu_equals_cpu(three, "all", true, 0, 3);
        }
        /* raster and rays agree on every evaluated frame, and raycast is the reference */
        assert_int_equal(sh("%s run %s orbit sm raycast --anim %s --frames 5 --size 256x144 --error-every 1 --quiet "
                            "--out %s/real", test_binary(), path, files[i][1], g_tmp), 0);
        char dir[4096];
        snprintf(dir, sizeof dir, "%s", last_line_of(g_out));
        const char *techs[] = {"sm", "raycast"};
        for (int k = 0; k < 2; k++) {
            sb_table t;
            assert_true(frames_of(dir, techs[k], "", &t));
            for (int r = 0; r < t.nrows; r++) {
                assert_true(atof(sb_table_get(&t, r, "geom_mismatch")) == 0);
                if (k == 1) assert_true(atof(sb_table_get(&t, r, "err_rate")) == 0);
            }
            long moved = 0;
            for (int r = 0; r < t.nrows; r++) moved = cell(&t, r, "casters_moved") > moved ? cell(&t, r, "casters_moved") : moved;
            printf("%s %s: %d frames, geom_mismatch 0 on each; at most %ld casters moved between frames\n", files[i][0],
                   techs[k], t.nrows, moved);
            assert_true(moved > 0);
            sb_table_free(&t);
        }
    }
}

/* Copies a .glb with its "animations" member taken out of the JSON chunk (padded back to 4 bytes). */
static void strip_animations(const char *from, const char *to) {
    size_t len;
    sb_err err;
    char *b = sb_read_file(from, &len, &err);
    assert_non_null(b);
    uint32_t jlen;
    memcpy(&jlen, b + 12, 4);
    char *json = sb_xmalloc(jlen + 1);
    memcpy(json, b + 20, jlen);
    json[jlen] = 0;
    char *a = strstr(json, "\"animations\":");
    assert_non_null(a);
    char *p = strchr(a, '[');
    int depth = 0;
    for (; *p; p++) {
        depth += *p == '[' || *p == '{';
        depth -= *p == ']' || *p == '}';
        if (depth == 0) break;
    }
    char *end = p + 1;
    if (*end == ',') end++;
    else if (a > json && a[-1] == ',') a--;
    memmove(a, end, strlen(end) + 1);
    size_t nj = strlen(json), padded = (nj + 3) & ~(size_t)3;
    uint32_t rest = (uint32_t)(len - 20 - jlen), total = (uint32_t)(12 + 8 + padded + rest), nj32 = (uint32_t)padded;
    FILE *f = fopen(to, "wb");
    assert_non_null(f);
    fwrite(b, 1, 8, f);
    fwrite(&total, 4, 1, f);
    fwrite(&nj32, 4, 1, f);
    fwrite(b + 16, 1, 4, f);
    fwrite(json, 1, nj, f);
    for (size_t i = nj; i < padded; i++) fputc(' ', f);
    fwrite(b + 20 + jlen, 1, rest, f);
    fclose(f);
    free(json);
    free(b);
}

/* A moving primitive without normals (its face normals are the CPU's) stays with the CPU: conf-skin with its
 * NORMAL attributes renamed to an application-specific one (glTF's leading underscore: ignored). */
static void test_placements_the_gpu_leaves(void **st) {
    (void)st;
    char src[4096], to[4200];
    assert_true(sb_resolve_bundled("conf-skin", ".glb", src, sizeof src));
    snprintf(to, sizeof to, "%s/conf-skin-no-normals.glb", g_tmp);
    size_t len;
    sb_err err;
    char *b = sb_read_file(src, &len, &err);
    assert_non_null(b);
    int renamed = 0;
    for (size_t i = 0; i + 8 <= len; i++)
        if (!memcmp(b + i, "\"NORMAL\"", 8)) memcpy(b + i, "\"_ORMAL\"", 8), renamed++;
    assert_true(renamed > 0);
    FILE *f = fopen(to, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, len, f), len);
    fclose(f);
    free(b);
    gpu_equals_cpu(to, NULL, false, 0, 0);
    gpu_equals_cpu(src, NULL, true, 0, 0);   /* the same file with its normals: the GPU's */
}

static void test_anim_none_is_the_still_file(void **st) {
    (void)st;
    char src[4096], still[4200];
    assert_true(sb_resolve_bundled("conf-skin", ".glb", src, sizeof src));
    snprintf(still, sizeof still, "%s/conf-skin-still.glb", g_tmp);
    strip_animations(src, still);
    char dirs[2][4096];
    const char *what[2] = {"conf-skin --anim none", still};
    for (int k = 0; k < 2; k++) {
        assert_int_equal(sh("%s run %s conf-skin sm pssm raycast --frames 5 --size 256x144 --error-every 2 --quiet "
                            "--out %s/none%d", test_binary(), k ? still : "conf-skin --anim none", g_tmp, k), 0);
        snprintf(dirs[k], sizeof dirs[k], "%s", last_line_of(g_out));
    }
    sb_table a, b;
    summary_table(dirs[0], &a);
    summary_table(dirs[1], &b);
    assert_int_equal(a.nrows, b.nrows);
    const char *cols[] = {"err_rate_mean", "err_false_lit_mean", "err_false_shadow_mean", "shadow_draw_calls_mean",
                          "triangles_mean", "geom_mismatch", "flicker_rate_mean", "scene_triangles"};
    for (int r = 0; r < a.nrows; r++)
        for (size_t c = 0; c < sizeof cols / sizeof *cols; c++) {
            printf("%s %s: %s | %s\n", what[0], cols[c], sb_table_get(&a, r, cols[c]), sb_table_get(&b, r, cols[c]));
            assert_string_equal(sb_table_get(&a, r, cols[c]), sb_table_get(&b, r, cols[c]));
        }
    for (int r = 0; r < a.nrows; r++) assert_string_equal(sb_table_get(&a, r, "casters_moved_mean"), "");
    sb_table_free(&a);
    sb_table_free(&b);
}

static void test_bad_input(void **st) {
    (void)st;
    const char *bin = test_binary();
    const char *out = expect_cli_fail("--anim walk: no clip of that name (its clips: slide, turn)",
                                      "%s run movers movers sm --anim walk --frames 2", bin);
    assert_null(strchr(out, '\n') ? strchr(strchr(out, '\n') + 1, '\n') : NULL);   /* one line */
    expect_cli_fail("--anim-speed 0: expected a number in (0", "%s run movers movers sm --anim-speed 0", bin);
    expect_cli_fail("--anim-speed -1: expected a number in (0", "%s run movers movers sm --anim-speed -1", bin);
    expect_cli_fail("--anim-speed inf: expected a number", "%s run movers movers sm --anim-speed inf", bin);
    expect_cli_fail("--anim-speed nan: expected a number", "%s run movers movers sm --anim-speed nan", bin);
    expect_cli_fail("--anim slide,,turn: expected all, none, or clip names", "%s run movers movers sm --anim slide,,turn",
                    bin);
    /* a channel that cannot be played as written is left out, said, never a refusal */
    char file[4200];
    snprintf(file, sizeof file, "%s/backwards.gltf", g_tmp);
    FILE *f = fopen(file, "w");
    assert_non_null(f);
    /* a triangle on node 0, moved by a translation whose key times go 0, 2, 1 */
    fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
               "\"buffers\":[{\"byteLength\":84,\"uri\":\"data:application/octet-stream;base64,"
               "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAEAAAIA/AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"
               "\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":12},"
               "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":36}],"
               "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],"
               "\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"SCALAR\"},"
               "{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
               "\"animations\":[{\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}],"
               "\"samplers\":[{\"input\":1,\"output\":2}]}]}");
    fclose(f);
    assert_int_equal(sh("%s info %s", bin, file), 0);
    assert_non_null(strstr(g_out, "key times do not increase (key 2): left out"));
    assert_non_null(strstr(g_out, "animation: nothing moves"));
    /* the same triangle, its key times -1, 0, 1 (before 0: glTF's start at 0), then at 0, 1, 2 with its three
       translations read as a CUBICSPLINE's (one value a key where it has three), then as morph weights of a mesh
       that has none (dropped with no word: "nothing moves"): each left out with its own cause */
    const char *cases[][3] = {{"", "key 0 is at -1 s, before 0 (glTF's key times start at 0 or later): left out",
                               "translation"},
                              {",\"interpolation\":\"CUBICSPLINE\"",
                               "a CUBICSPLINE sampler has three values a key (in-tangent, value, out-tangent), this one one",
                               "translation"},
                              {"", "a weights channel on node 0, whose mesh has no morph weights: nothing for it to move",
                               "weights"}};
    for (int i = 0; i < 3; i++) {
        float buf[21] = {0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0};
        if (i >= 1) buf[9] = 0, buf[10] = 1, buf[11] = 2;
        char b64[200];
        test_base64((const unsigned char *)buf, sizeof buf, b64);
        f = fopen(file, "w");
        assert_non_null(f);
        fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
                   "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                   "\"buffers\":[{\"byteLength\":84,\"uri\":\"data:application/octet-stream;base64,%s\"}],"
                   "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":12},"
                   "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":36}],"
                   "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],"
                   "\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"SCALAR\"},"
                   "{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                   "\"animations\":[{\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"%s\"}}],"
                   "\"samplers\":[{\"input\":1,\"output\":2%s}]}]}",
                b64, cases[i][2], cases[i][0]);
        fclose(f);
        assert_int_equal(sh("%s info %s", bin, file), 0);
        if (!strstr(g_out, cases[i][1])) fail_msg("expected \"%s\" in:\n%s", cases[i][1], g_out);
    }
}

/* The nightly's runs of still scenes keep their id and parameters: a scene that moves only adds runs, and the runs a
 * scene only skipped left the matrix (their places with them: an index is a run's place, not its name). */
static void test_nightly_ids_hold(void **st) {
    (void)st;
    assert_int_equal(sh("%s batch %s --dry-run", test_binary(), test_data("../../scripts/nightly.bench")), 0);
    size_t len;
    sb_err err;
    char *golden = sb_read_file(test_data("nightly-ids.csv"), &len, &err);
    assert_non_null(golden);
    int rows = 0, found = 0;
    for (char *line = strtok(golden, "\n"); line; line = strtok(NULL, "\n")) {
        if (line[0] == '#') continue;
        rows++;
        /* the dry run's line: index,run_id,scene,path,technique,params,cost; the golden one leaves path and cost out */
        char idx[16], id[32], scene[64], rest[1024];
        assert_int_equal(sscanf(line, "%15[^,],%31[^,],%63[^,],%1023[^\n]", idx, id, scene, rest), 4);
        char want[1200];
        snprintf(want, sizeof want, ",%s,%s,", id, scene);
        char *at = strstr(g_out, want);
        if (!at) print_error("the nightly lost run %s (%s)\n", id, line);
        assert_non_null(at);
        char *tech = strchr(at + strlen(want), ',');   /* past the path */
        assert_non_null(tech);
        tech++;
        assert_memory_equal(tech, rest, strlen(rest));   /* the same technique and parameters */
        found++;
    }
    printf("the nightly's %d runs of still scenes: all there, the same id and parameters\n", found);
    assert_true(rows >= 120);
    assert_int_equal(found, rows);
    free(golden);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_box_shadow_follows_the_clip),
        cmocka_unit_test(test_caches_invalidate_what_moved),
        cmocka_unit_test(test_real_animated_files),
        cmocka_unit_test(test_placements_the_gpu_leaves), cmocka_unit_test(test_anim_none_is_the_still_file),
        cmocka_unit_test(test_nightly_ids_hold),
    };
    return cmocka_run_group_tests_name("motion", tests, setup, teardown);
}
