/* `cameras SCENE PATH`: every frame's camera as a run renders it, for another renderer to draw the same frames.
 *
 * - The conventions hold by geometry: projection x view takes each camera's target to the screen's centre, the
 *   point at `near` along the view to depth -1 and at `far` to +1, and the top of the vertical field of view to
 *   y = 1; the view matrix is the rotation's inverse with the position.
 * - Re-rendered: the exported cameras written back as a key path (position, rotation, field of view at each
 *   frame's time) sample to the same cameras, and a run along them gives the run along the original path's
 *   figures, digit for digit (without flicker twins: a twin is another camera, between the keys).
 * - The lights: plane-box's sun (azimuth 30, elevation 50), plane-box-lamp's lamp at (2.5, 3.5, 1.5); twins a
 *   display frame (--flicker-dt) later.
 * - As glTF (--format gltf): the tool's own glTF camera path (FILE#camera=0) samples the file back to the same
 *   cameras (float precision), the sun's node shines along -sun, the lamp's node stands at the lamp; a twin
 *   camera node with --twins.
 * - A path that is not there: one line, exit 2. */
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

#include "json.h"
#include "sbmath.h"
#include "support.h"
#include "table.h"

SB_TEST_SCRATCH("sbengines")

static char g_out[1 << 20];

static double num(const sb_json *o, const char *key) {
    const sb_json *v = sb_json_get(o, key);
    assert_non_null(v);
    assert_int_equal(v->type, SB_JSON_NUMBER);
    return v->num;
}

static void vec(const sb_json *o, const char *key, double *out, int n) {
    const sb_json *v = sb_json_get(o, key);
    assert_non_null(v);
    assert_int_equal(v->count, n);
    for (int k = 0; k < n; k++) out[k] = v->items[k].num;
}

/* clip = P * V * (p, 1), column-major; returns NDC */
static void project(const double *P, const double *V, const double p[3], double ndc[3]) {
    double v[4], c[4];
    for (int r = 0; r < 4; r++) v[r] = V[r] * p[0] + V[4 + r] * p[1] + V[8 + r] * p[2] + V[12 + r];
    for (int r = 0; r < 4; r++) c[r] = P[r] * v[0] + P[4 + r] * v[1] + P[8 + r] * v[2] + P[12 + r] * v[3];
    for (int k = 0; k < 3; k++) ndc[k] = c[k] / c[3];
}

static void export_cameras(const char *args, sb_json_doc *doc) {
    int rc = run_capture(args, g_out, sizeof g_out);
    assert_int_equal(rc, 0);
    sb_err err;
    assert_true(sb_json_parse(doc, "cameras", g_out, strlen(g_out), &err));
}

static void test_conventions(void **st) {
    (void)st;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "%s cameras plane-box plane-box --frames 5 --size 160x90 --twins 2>&1", test_binary());
    sb_json_doc doc;
    export_cameras(cmd, &doc);
    const sb_json *cams = sb_json_get(doc.root, "cameras");
    assert_int_equal(cams->count, 5);
    assert_non_null(strstr(sb_json_get(doc.root, "conventions")->text, "column-major"));
    double sun[3];
    vec(sb_json_get(doc.root, "sun"), "direction", sun, 3);
    sb_v3 want = sb_sun_dir(30, 50);   /* scenegen's plane-box sun */
    print_message("sun %g %g %g\n", sun[0], sun[1], sun[2]);
    assert_true(fabs(sun[0] - want.x) < 1e-12 && fabs(sun[1] - want.y) < 1e-12 && fabs(sun[2] - want.z) < 1e-12);
    assert_true(fabs(sun[1] - sin(50 * 3.14159265358979 / 180)) < 1e-12);   /* 50 degrees up */
    for (uint32_t i = 0; i < cams->count; i++) {
        const sb_json *c = &cams->items[i];
        double P[16], V[16], pos[3], target[3], up[3], ndc[3];
        vec(c, "projection", P, 16);
        vec(c, "view", V, 16);
        vec(c, "position", pos, 3);
        vec(c, "target", target, 3);
        vec(c, "up", up, 3);
        project(P, V, target, ndc);
        assert_true(fabs(ndc[0]) < 1e-9 && fabs(ndc[1]) < 1e-9);
        double f[3], dist = 0;
        for (int k = 0; k < 3; k++) f[k] = target[k] - pos[k], dist += f[k] * f[k];
        dist = sqrt(dist);
        double n = num(c, "near"), fa = num(c, "far"), half = tan(num(c, "yfov") / 2), p[3];
        for (int k = 0; k < 3; k++) p[k] = pos[k] + f[k] / dist * n;
        project(P, V, p, ndc);
        assert_true(fabs(ndc[2] + 1) < 1e-6);
        for (int k = 0; k < 3; k++) p[k] = pos[k] + f[k] / dist * fa;
        project(P, V, p, ndc);
        assert_true(fabs(ndc[2] - 1) < 1e-6);
        for (int k = 0; k < 3; k++) p[k] = pos[k] + (f[k] / dist + up[k] * half) * 10;
        project(P, V, p, ndc);
        assert_true(fabs(ndc[1] - 1) < 1e-9 && fabs(ndc[0]) < 1e-9);
        assert_true(fabs(num(c, "aspect") - 160.0 / 90) < 1e-12);
        const sb_json *tw = sb_json_get(c, "twin");
        assert_non_null(tw);
        assert_true(fabs(num(tw, "t") - num(c, "t") - 1 / 60.0) < 1e-6);
    }
    sb_json_free(&doc);
    /* a lamp, in world units */
    snprintf(cmd, sizeof cmd, "%s cameras plane-box-lamp plane-box-lamp --frames 2 2>&1", test_binary());
    export_cameras(cmd, &doc);
    const sb_json *lamps = sb_json_get(doc.root, "lamps");
    assert_int_equal(lamps->count, 1);
    double lp[3];
    vec(&lamps->items[0], "position", lp, 3);
    assert_true(fabs(lp[0] - 2.5) < 1e-9 && fabs(lp[1] - 3.5) < 1e-9 && fabs(lp[2] - 1.5) < 1e-9);
    sb_json_free(&doc);
}

/* The exported cameras as a key path: frame i's position, rotation and field of view at its time. */
static void write_key_path(const sb_json *cams, const char *path) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (uint32_t i = 0; i < cams->count; i++) {
        const sb_json *c = &cams->items[i];
        double pos[3], q[4];
        vec(c, "position", pos, 3);
        vec(c, "rotation", q, 4);
        fprintf(f, "key %.17g  %.17g %.17g %.17g  %.17g %.17g %.17g %.17g  %.17g\n", num(c, "t"), pos[0], pos[1], pos[2],
                q[0], q[1], q[2], q[3], num(c, "fov_deg"));
    }
    fclose(f);
}

static void test_rerendered(void **st) {
    (void)st;
    char cmd[1024], keys[512];
    snprintf(cmd, sizeof cmd, "%s cameras towers towers --frames 4 --size 160x90 2>&1", test_binary());
    sb_json_doc doc;
    export_cameras(cmd, &doc);
    snprintf(keys, sizeof keys, "%s/exported.path", g_tmp);
    write_key_path(sb_json_get(doc.root, "cameras"), keys);
    sb_json_free(&doc);
    /* the same cameras, sampled */
    char a[8192], b[8192];
    snprintf(cmd, sizeof cmd, "%s path towers towers --frames 4 --size 160x90", test_binary());
    assert_int_equal(run_capture(cmd, a, sizeof a), 0);
    snprintf(cmd, sizeof cmd, "%s path %s towers --frames 4 --size 160x90", test_binary(), keys);
    assert_int_equal(run_capture(cmd, b, sizeof b), 0);
    char *sa, *sb, *la = strtok_r(a, "\n", &sa), *lb = strtok_r(b, "\n", &sb);
    for (int row = 0; la && lb; row++, la = strtok_r(NULL, "\n", &sa), lb = strtok_r(NULL, "\n", &sb)) {
        if (row == 0) continue;   /* the header */
        double va[16], vb[16];
        int na = 0, nb = 0;
        for (char *t = la, *s; na < 16 && (t = strtok_r(na ? NULL : t, ",", &s)); ) va[na++] = atof(t);
        for (char *t = lb, *s; nb < 16 && (t = strtok_r(nb ? NULL : t, ",", &s)); ) vb[nb++] = atof(t);
        assert_true(na >= 13 && nb >= 13);
        for (int k = 3; k < 13; k++)   /* px .. qw, fov, near, far */
            if (fabs(va[k] - vb[k]) > 1e-6 * (1 + fabs(va[k]))) fail_msg("frame %d column %d: %g against %g", row - 1, k, va[k], vb[k]);
    }
    /* rendered along both: the same figures */
    snprintf(cmd, sizeof cmd, "%s run towers towers sm:res=512 --frames 4 --warmup 0 --size 160x90 --error-every 1 --flicker-dt 0 --quiet --out %s/orig",
             test_binary(), g_tmp);
    assert_int_equal(run_capture(cmd, a, sizeof a), 0);
    char dir_a[512], dir_b[512];
    snprintf(dir_a, sizeof dir_a, "%s", last_line_of(a));
    snprintf(cmd, sizeof cmd, "%s run towers %s sm:res=512 --frames 4 --warmup 0 --size 160x90 --error-every 1 --flicker-dt 0 --quiet --out %s/keys",
             test_binary(), keys, g_tmp);
    assert_int_equal(run_capture(cmd, b, sizeof b), 0);
    snprintf(dir_b, sizeof dir_b, "%s", last_line_of(b));
    sb_table ta, tb;
    summary_table(dir_a, &ta);
    summary_table(dir_b, &tb);
    /* (the flicker twins are another camera each, between the keys: cameras --twins exports them) */
    const char *same[] = {"err_rate_mean", "err_rate_p95", "vis_mae_mean", "res_err_mean_mean", "shadow_triangles_mean"};
    for (size_t k = 0; k < sizeof same / sizeof *same; k++) {
        print_message("%s: %s along the path, %s along the exported cameras\n", same[k], sb_table_get(&ta, 0, same[k]),
                      sb_table_get(&tb, 0, same[k]));
        assert_string_equal(sb_table_get(&ta, 0, same[k]), sb_table_get(&tb, 0, same[k]));
    }
    sb_table_free(&ta);
    sb_table_free(&tb);
}

/* The columns of `path` CSV rows: px..qw (3..9), fov (10). */
static int csv_rows(char *text, double rows[][16], int max) {
    int n = 0;
    char *s1, *line = strtok_r(text, "\n", &s1);
    for (int row = 0; line && n < max; row++, line = strtok_r(NULL, "\n", &s1)) {
        if (row == 0) continue;
        int k = 0;
        for (char *s2, *t = strtok_r(line, ",", &s2); t && k < 16; t = strtok_r(NULL, ",", &s2)) rows[n][k++] = atof(t);
        n++;
    }
    return n;
}

static void test_gltf(void **st) {
    (void)st;
    char cmd[1024], file[512], a[8192], b[8192];
    snprintf(file, sizeof file, "%s/cameras.gltf", g_tmp);
    snprintf(cmd, sizeof cmd, "%s cameras plane-box-lamp plane-box-lamp --frames 4 --size 160x90 --twins --format gltf > %s",
             test_binary(), file);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "%s path plane-box-lamp plane-box-lamp --frames 4 --size 160x90", test_binary());
    assert_int_equal(run_capture(cmd, a, sizeof a), 0);
    snprintf(cmd, sizeof cmd, "%s path '%s#camera=0' plane-box-lamp --frames 4 --size 160x90", test_binary(), file);
    assert_int_equal(run_capture(cmd, b, sizeof b), 0);
    double ra[8][16], rb[8][16];
    int na = csv_rows(a, ra, 8), nb = csv_rows(b, rb, 8);
    assert_int_equal(na, 4);
    assert_int_equal(nb, 4);
    for (int i = 0; i < 4; i++) {
        double dot = 0;
        for (int k = 3; k < 6; k++) assert_true(fabs(ra[i][k] - rb[i][k]) < 1e-5 * (1 + fabs(ra[i][k])));
        for (int k = 6; k < 10; k++) dot += ra[i][k] * rb[i][k];
        assert_true(fabs(fabs(dot) - 1) < 1e-6);   /* q and -q are one rotation */
        assert_true(ra[i][10] == rb[i][10]);   /* field of view */
    }
    /* its nodes: the two cameras, the sun shining along -sun, the lamp */
    FILE *f = fopen(file, "rb");
    assert_non_null(f);
    size_t len = fread(b, 1, sizeof b - 1, f);
    fclose(f);
    b[len] = 0;
    sb_json_doc doc;
    sb_err err;
    assert_true(sb_json_parse(&doc, file, b, len, &err));
    const sb_json *nodes = sb_json_get(doc.root, "nodes");
    assert_int_equal(nodes->count, 4);
    assert_string_equal(sb_json_get(&nodes->items[1], "name")->text, "camera twin");
    double q[4], t[3];
    vec(&nodes->items[2], "rotation", q, 4);
    sb_v3 along = sb_quat_rotate((sb_quat){q[0], q[1], q[2], q[3]}, sb_v3_make(0, 0, -1)), sun = sb_sun_dir(30, 50);
    print_message("sun node shines along %g %g %g (-sun: %g %g %g)\n", along.x, along.y, along.z, -sun.x, -sun.y, -sun.z);
    assert_true(sb_v3_len(sb_v3_add(along, sun)) < 1e-6);
    vec(&nodes->items[3], "translation", t, 3);
    assert_true(fabs(t[0] - 2.5) < 1e-6 && fabs(t[1] - 3.5) < 1e-6 && fabs(t[2] - 1.5) < 1e-6);
    sb_json_free(&doc);
}

/* What the export must not get wrong in silence: a path of one key (every frame at time 0) keyed once, so its times
 * increase strictly and the tool's own loader reads it back to the same camera (it wrote 0,0,0 and the loader
 * dropped them); every count and length written with all its digits (past about 31k frames a byteLength came out
 * as 6 significant digits); a lamp's intensity written even where it is 0 (an engine reads a missing one as 1). */
static void test_gltf_exact(void **st) {
    (void)st;
    char cmd[12288], file[512], path[512], a[8192], b[8192];
    snprintf(path, sizeof path, "%s/one.path", g_tmp);
    FILE *pf = fopen(path, "w");
    assert_non_null(pf);
    fputs("fov 60\nlook 0   -5 4.5 -4   -0.8 0 -0.8\n", pf);
    fclose(pf);
    snprintf(file, sizeof file, "%s/one.gltf", g_tmp);
    snprintf(cmd, sizeof cmd, "%s cameras plane-box %s --frames 3 --size 160x90 --format gltf > %s", test_binary(),
             path, file);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "%s path %s plane-box --frames 3 --size 160x90", test_binary(), path);
    assert_int_equal(run_capture(cmd, a, sizeof a), 0);
    snprintf(cmd, sizeof cmd, "%s path '%s#camera=0' plane-box --frames 3 --size 160x90", test_binary(), file);
    if (run_capture(cmd, b, sizeof b) != 0) fail_msg("the export of a one-key path does not load back: %s", b);
    double ra[8][16], rb[8][16];
    assert_int_equal(csv_rows(a, ra, 8), 3);
    assert_int_equal(csv_rows(b, rb, 8), 3);
    for (int i = 0; i < 3; i++)
        for (int k = 3; k < 6; k++) assert_true(fabs(ra[i][k] - rb[i][k]) < 1e-5 * (1 + fabs(ra[i][k])));
    /* 31,251 frames: the buffer of 1,000,032 bytes has that byteLength (6 digits wrote 1000030, and the tool refused
       its own export) */
    snprintf(file, sizeof file, "%s/long.gltf", g_tmp);
    snprintf(cmd, sizeof cmd, "%s cameras plane-box plane-box --frames 31251 --size 160x90 --format gltf > %s && "
             "%s path '%s#camera=0' plane-box --frames 3 --size 160x90 > /dev/null", test_binary(), file, test_binary(),
             file);
    assert_int_equal(system(cmd), 0);
    /* a lamp of intensity 0 (plane-box-lamp's, its glb's JSON changed): written as 0, not left to the default 1 */
    char bin_dir[4096], glb[4200], dark[4200];
    snprintf(bin_dir, sizeof bin_dir, "%s", test_binary());
    snprintf(glb, sizeof glb, "%s/plane-box-lamp.glb", dirname(bin_dir));
    snprintf(dark, sizeof dark, "%s/dark.glb", g_tmp);
    snprintf(cmd, sizeof cmd, "python3 -c 'import json, struct, sys; b = open(sys.argv[1], \"rb\").read(); "
             "n = struct.unpack_from(\"<I\", b, 12)[0]; d = json.loads(b[20:20 + n]); "
             "[l.__setitem__(\"intensity\", 0) for l in d[\"extensions\"][\"KHR_lights_punctual\"][\"lights\"]]; "
             "j = json.dumps(d).encode(); j += b\" \" * (-len(j) %% 4); rest = b[20 + n:]; "
             "open(sys.argv[2], \"wb\").write(struct.pack(\"<III\", 0x46546C67, 2, 12 + 8 + len(j) + len(rest)) + "
             "struct.pack(\"<II\", len(j), 0x4E4F534A) + j + rest)' %s %s", glb, dark);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "%s cameras %s plane-box-lamp --frames 2 --size 160x90 --format gltf", test_binary(), dark);
    assert_int_equal(run_capture(cmd, b, sizeof b), 0);
    if (!strstr(b, "\"intensity\":0")) fail_msg("no intensity 0 in:\n%s", b);
    /* the document that cannot be written whole: exit 4, said; twins that would be dropped: refused */
    expect_cli_exit(4, "could not be written", "(%s cameras plane-box plane-box --frames 2 --size 160x90 > /dev/full)",
                    test_binary());
    expect_cli_fail("--twins needs --flicker-dt above 0",
                    "%s cameras plane-box plane-box --frames 2 --size 160x90 --twins --flicker-dt 0", test_binary());
}

static void test_bad_input(void **st) {
    (void)st;
    expect_cli_fail("no-such.path", "%s cameras plane-box %s/no-such.path", test_binary(), g_tmp);
    expect_cli_fail("usage: shadowbench cameras", "%s cameras plane-box", test_binary());
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_conventions), cmocka_unit_test(test_rerendered),
                                       cmocka_unit_test(test_gltf), cmocka_unit_test(test_gltf_exact),
                                       cmocka_unit_test(test_bad_input)};
    return cmocka_run_group_tests_name("engines", tests, setup, teardown);
}
