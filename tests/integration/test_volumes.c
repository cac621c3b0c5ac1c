/* Shadow volumes against the exact answer: on plane-box every mode matches
 * the analytic shadow; with the camera inside the box's shadow volume z-pass
 * counts wrong and z-fail (and auto) right. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "support.h"

static void test_volumes_match_analytic(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    const char *specs[] = {"volumes:mode=zpass", "volumes:mode=zfail", "volumes"};
    for (int i = 0; i < 3; i++) {
        pb_result r;
        bool ok = pb_render(&s, specs[i], &r, NULL, &err);
        if (!ok) print_error("%s\n", err.msg);
        assert_true(ok);
        print_message("%s: shadow exact %ld, volumes %ld, mismatch %ld (%.3f%% of image)\n", specs[i], r.shadow_exact,
                      r.shadow_tech, r.mismatch, 100.0 * r.mismatch / r.pixels);
        assert_true(r.shadow_exact > r.pixels / 100);
        assert_true(r.mismatch * 1000 < r.pixels * 2);   /* exact up to rasterization: 0.2% of the image */
    }
    sb_session_close(&s);
}

static void test_camera_inside_volume(void **st) {
    (void)st;
    /* a camera in the box's shadow (a ray from it toward the sun enters the box) */
    sb_v3 sun = sb_sun_dir(30, 50);
    sb_v3 eye = sb_v3_sub(sb_v3_make(0, 1, 0), sb_v3_scale(sun, 0.9));
    char path[128];
    snprintf(path, sizeof path, "/tmp/sb-vol-%d.path", (int)getpid());
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "look 0  %.17g %.17g %.17g  -4 0 -4.5\n", eye.x, eye.y, eye.z);
    fclose(f);
    sb_session s;
    sb_err err;
    assert_true(test_open(&s, "plane-box", path, 480, 270, &err));
    sb_error_metrics zpass, zfail, autom;
    assert_true(eval_frame(&s, "volumes:mode=zpass", 0, 1, &zpass, NULL, NULL, &err));
    assert_true(eval_frame(&s, "volumes:mode=zfail", 0, 1, &zfail, NULL, NULL, &err));
    assert_true(eval_frame(&s, "volumes:mode=auto", 0, 1, &autom, NULL, NULL, &err));
    print_message("camera inside a volume: err_rate z-pass %.4f, z-fail %.4f, auto %.4f (%ld px)\n", zpass.err_rate,
                  zfail.err_rate, autom.err_rate, zfail.pixels);
    assert_true(zfail.pixels > 1000);
    assert_true(zpass.err_rate > 0.2);        /* the count starts one too low: inverted shadows */
    assert_true(zfail.err_rate < 0.01);
    assert_true(autom.err_rate < 0.01);
    sb_session_close(&s);
    unlink(path);
}

static void test_planar(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    pb_result r;
    assert_true(pb_render(&s, "planar", &r, NULL, &err));
    assert_true(s.scene.plane_count >= 1);   /* searched when planar first needed them */
    print_message("planar: shadow exact %ld, planar %ld, mismatch %ld (%.3f%% of image)\n", r.shadow_exact,
                  r.shadow_tech, r.mismatch, 100.0 * r.mismatch / r.pixels);
    assert_true(r.shadow_exact > r.pixels / 100);
    assert_true(r.mismatch * 1000 < r.pixels * 2);
    sb_session_close(&s);
    /* the terrain of desert has no large plane: the technique is skipped with the reason */
    assert_true(test_open(&s, "desert", "desert", 64, 36, &err));
    const char *why = sb_skip_reason(&s, sb_technique_find("planar"), NULL);
    assert_non_null(why);
    assert_string_equal(why, "the scene has no large planar receiver");
    assert_null(sb_skip_reason(&s, sb_technique_find("volumes"), NULL));
    sb_session_close(&s);
}

/* Does the segment from p to the lamp cross the box? */
static bool box_blocks_lamp(sb_v3 p, sb_v3 lamp) { return pb_box_blocks(p, sb_v3_sub(lamp, p), 1 - 1e-9); }

static void test_point_light_cube(void **st) {
    (void)st;
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    o.width = 640;
    o.height = 360;
    sb_session s;
    memset(&s, 0, sizeof s);
    sb_err err;
    assert_true(sb_session_open(&s, &o, "plane-box-lamp", test_data("planebox-fixed.path"), &err));
    assert_true(s.scene.light_count == 2 && s.scene.lights[1].type == SB_LIGHT_POINT);
    sb_v3 lamp = sb_v3_add(s.scene.lights[1].position, s.scene.origin);
    assert_true(sb_v3_len(sb_v3_sub(lamp, sb_v3_make(2.5, 3.5, 1.5))) < 1e-6);
    /* per-technique tolerance, in % of the image: dual paraboloids bend the box's large faces
       (the paraboloid projection is not linear), so they get more room; raycast toward the lamp is exact */
    const char *specs[] = {"cube", "cube:layered=gs", "cube:layered=vs", "cube:filter=pcf:res=2048", "dpsm",
                           "raycast:light=0"};
    const double tolerance_pct[] = {1, 1, 1, 1, 3, 0.1};
    const int w = 640, h = 360;
    float *depth = malloc(sizeof(float) * w * h);
    unsigned char *vis = malloc((size_t)w * h);
    for (int k = 0; k < 6; k++) {
        sb_run_spec *runs = NULL;
        int n = 0;
        assert_true(sb_spec_expand(specs[k], NULL, &runs, &n, &err));
        sb_instance in;
        assert_true(sb_instance_create(&in, &s, &runs[0], 1, &err));
        sb_timer t;
        sb_timer_init(&t, SB_TIMING_SYNC, 1, 1);
        sb_timer_frame_begin(&t, 0);
        sb_frame f;
        memset(&f, 0, sizeof f);
        render_frame_eval(&s, &in, &f, 0, 1, 0, &t);
        sb_gpu_readback(&s.gpu, depth, vis, NULL);
        long plane = 0, exact = 0, tech = 0, mismatch = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                float d = depth[y * w + x];
                if (d >= 1.0f) continue;
                sb_v3 p = sb_frame_unproject(&f, x, y, d);
                if (fabs(p.y) > 0.02 || fabs(p.x) > 19.9 || fabs(p.z) > 19.9 || (fabs(p.x) <= 1 && fabs(p.z) <= 1)) continue;
                plane++;
                bool a = box_blocks_lamp(p, lamp), b = vis[y * w + x] < 128;
                exact += a;
                tech += b;
                mismatch += a != b;
            }
        print_message("%s: plane %ld px, analytic point-light shadow %ld, cube %ld, mismatch %ld (%.3f%% of image), "
                      "shadow draws %u\n", specs[k], plane, exact, tech, mismatch, 100.0 * mismatch / (w * h),
                      f.counters.shadow_draw_calls);
        assert_true(exact > w * h / 50);
        assert_true(mismatch * 100 < tolerance_pct[k] * w * h);
        sb_timer_free(&t);
        sb_instance_destroy(&in);
        free(runs);
    }
    free(depth);
    free(vis);
    /* the sun techniques still shade the sun here; without a point light, cube is skipped */
    assert_null(sb_skip_reason(&s, sb_technique_find("sm"), NULL));
    sb_session_close(&s);
    memset(&s, 0, sizeof s);
    assert_true(sb_session_open(&s, &o, "plane-box", "plane-box", &err));
    assert_string_equal(sb_skip_reason(&s, sb_technique_find("cube"), NULL), "the scene has no point or spot light");
    sb_session_close(&s);
    /* a night scene (lamps, no sun): sun techniques are skipped with the reason */
    memset(&s, 0, sizeof s);
    o.width = 64;
    o.height = 36;
    assert_true(sb_session_open(&s, &o, "towers-night", "towers-night", &err));
    assert_non_null(strstr(sb_skip_reason(&s, sb_technique_find("pssm"), NULL), "lit only by 6 point light(s), no sun"));
    assert_null(sb_skip_reason(&s, sb_technique_find("cube"), NULL));
    assert_null(sb_skip_reason(&s, sb_technique_find("raycast"), NULL));   /* toward the first lamp */
    sb_session_close(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_volumes_match_analytic),
                                       cmocka_unit_test(test_camera_inside_volume), cmocka_unit_test(test_planar),
                                       cmocka_unit_test(test_point_light_cube)};
    return cmocka_run_group_tests_name("volumes", tests, NULL, NULL);
}
