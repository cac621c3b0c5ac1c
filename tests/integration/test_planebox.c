/* Integration: real rendering on llvmpipe, checked against geometry.
 * plane-box is a 2x2x2 box on a plane under a known sun; the analytic shadow
 * is a ray/box test for every plane pixel the camera sees. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

static void check_backend(sb_backend b) {
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, b, 640, 360, &err));
    /* the sun comes from the file's KHR_lights_punctual light (azimuth 30, elevation 50) */
    sb_v3 expect = sb_sun_dir(30, 50);
    assert_true(s.scene.has_sun);
    assert_true(sb_v3_len(sb_v3_sub(s.scene.sun, expect)) < 1e-6);
    pb_result r;
    assert_true(pb_render(&s, "sm:res=2048", &r, NULL, &err));
    print_message("%s: plane %ld px, shadow exact %ld, sm %ld, mismatch %ld (%.3f%% of image)\n",
                  sb_backend_name(b), r.plane, r.shadow_exact, r.shadow_tech, r.mismatch,
                  100.0 * r.mismatch / r.pixels);
    assert_true(r.plane > r.pixels / 4);              /* the camera sees the plane */
    assert_true(r.shadow_exact > r.pixels / 100);     /* and a real shadow on it */
    assert_true(r.mismatch < r.pixels / 100);         /* within 1% of the image */
    long diff = labs(r.shadow_tech - r.shadow_exact);
    assert_true(diff < r.pixels / 100);
    /* none shadows nothing */
    assert_true(pb_render(&s, "none", &r, NULL, &err));
    assert_int_equal(r.shadow_tech, 0);
    sb_session_close(&s);
}

static void test_sm_matches_analytic_egl(void **st) {
    (void)st;
    check_backend(SB_BACKEND_EGL);
}

static void test_sm_matches_analytic_osmesa(void **st) {
    (void)st;
    check_backend(SB_BACKEND_OSMESA);
}

static void test_low_resolution_is_worse(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    pb_result lo, hi;
    assert_true(pb_render(&s, "sm:res=64:filter=none", &lo, NULL, &err));
    assert_true(pb_render(&s, "sm:res=2048:filter=none", &hi, NULL, &err));
    print_message("mismatch res=64 %ld, res=2048 %ld\n", lo.mismatch, hi.mismatch);
    assert_true(lo.mismatch > 2 * hi.mismatch);
    sb_session_close(&s);
}

static void test_cascaded_match_analytic(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    const char *specs[] = {"pssm:res=1024", "pssm:res=1024:layered=gs:stable=on", "sdsm:res=1024",
                           "sdsm:res=1024:splits=cpu:latency=0", "sdsm:res=1024:tight=on:partition=histogram",
                           "pssm:res=1024:select=map:blend=0.2:filter=pcf3", "lispsm:res=1024",
                           "pssm:res=1024:warp=lispsm", "sdsm:res=1024:splits=cpu:warp=lispsm", "tsm:res=1024",
                           "pssm:res=1024:warp=tsm:layered=gs", "psm:res=1024", "psm:res=1024:cube=on",
                           "psm:res=1024:cube=on:layered=gs", "psm:res=1024:behind=shift"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        pb_result r;
        bool ok = pb_render(&s, specs[i], &r, NULL, &err);
        if (!ok) print_error("%s\n", err.msg);
        assert_true(ok);
        print_message("%s: shadow exact %ld, technique %ld, mismatch %ld (%.3f%% of image)\n", specs[i], r.shadow_exact,
                      r.shadow_tech, r.mismatch, 100.0 * r.mismatch / r.pixels);
        assert_true(r.shadow_exact > r.pixels / 100);
        assert_true(r.mismatch < r.pixels / 100);
    }
    sb_session_close(&s);
}

static void test_pcss_converges_to_hard(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    sb_error_metrics hard, zero, soft, wide;
    assert_true(eval_frame(&s, "sm:filter=none", 0, 1, &hard, NULL, NULL, &err));
    assert_true(eval_frame(&s, "sm:filter=pcss:sun_size=0", 0, 1, &zero, NULL, NULL, &err));
    assert_true(eval_frame(&s, "sm:filter=pcss:sun_size=1", 0, 1, &soft, NULL, NULL, &err));
    assert_true(eval_frame(&s, "sm:filter=pcss:sun_size=4", 0, 1, &wide, NULL, NULL, &err));
    print_message("pcss vis_mae: hard %.5f, sun 0 %.5f, 1 deg %.5f, 4 deg %.5f; err_rate %.5f %.5f %.5f %.5f\n",
                  hard.vis_mae, zero.vis_mae, soft.vis_mae, wide.vis_mae, hard.err_rate, zero.err_rate, soft.err_rate,
                  wide.err_rate);
    /* a point-sized sun gives the hard shadow; a wider one widens the penumbra */
    assert_true(fabs(zero.vis_mae - hard.vis_mae) < 0.002);
    assert_true(zero.err_rate < 0.005);
    assert_true(soft.vis_mae > zero.vis_mae);
    assert_true(wide.vis_mae > soft.vis_mae);
    assert_true(wide.err_rate < 0.05);   /* the binary state stays mostly right */
    sb_session_close(&s);
}

static void test_filtered_formats_converge(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    sb_error_metrics hard;
    assert_true(eval_frame(&s, "sm:res=1024:filter=none", 0, 1, &hard, NULL, NULL, &err));
    const char *formats[] = {"vsm", "esm", "msm"};
    for (int i = 0; i < 3; i++) {
        sb_error_metrics m[3];
        const int blur[3] = {0, 2, 6};
        for (int b = 0; b < 3; b++) {
            char spec[96];
            snprintf(spec, sizeof spec, "sm:res=1024:format=%s:blur=%d:bleed=0", formats[i], blur[b]);
            bool ok = eval_frame(&s, spec, 0, 1, &m[b], NULL, NULL, &err);
            if (!ok) print_error("%s\n", err.msg);
            assert_true(ok);
        }
        print_message("%s: vis_mae blur 0 %.5f, 2 %.5f, 6 %.5f (hard %.5f); err_rate %.5f %.5f %.5f (hard %.5f)\n",
                      formats[i], m[0].vis_mae, m[1].vis_mae, m[2].vis_mae, hard.vis_mae, m[0].err_rate, m[1].err_rate,
                      m[2].err_rate, hard.err_rate);
        /* no filter width: the hard result; wider filters: softer edges */
        assert_true(m[0].err_rate < hard.err_rate + 0.003);
        assert_true(fabs(m[0].vis_mae - hard.vis_mae) < 0.004);
        assert_true(m[2].vis_mae > m[0].vis_mae);
    }
    sb_session_close(&s);
}

/* The sun low behind a low camera whose plane the box is behind: the box's
 * shadow falls forward over most of the view (tests/data/planebox-behind.path).
 * In the camera's post-projective space the sun is an inverted point light and
 * the box lies beyond the plane at infinity. PSM's inverse projection orders
 * it in front of every receiver; the naive ordering (an ordinary near plane)
 * clips it and loses the shadow; the virtual camera shift keeps it at a cost in
 * resolution. Checked against the analytic shadow and the ray-cast reference. */
static void test_psm_sun_behind_camera(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open_view(&s, SB_BACKEND_EGL, 480, 270, "planebox-behind.path", 30, 20, &err));
    /* the setup is what it claims: every box corner behind the camera, the sun behind too */
    sb_camera cam = sb_path_camera(&s.path, 0, 1, 480.0 / 270, &s.scene);
    for (int k = 0; k < 8; k++) {
        sb_v3 c = sb_v3_make(k & 1 ? 1 : -1, k & 2 ? 2 : 0, k & 4 ? 1 : -1);
        assert_true(sb_v3_dot(sb_v3_sub(c, cam.pos), cam.forward) < 0);
    }
    assert_true(sb_v3_dot(s.gpu.sun, cam.forward) < 0);
    const char *specs[] = {"psm", "psm:behind=shift", "psm:cube=on", "psm:behind=naive"};
    pb_result r[4];
    sb_error_metrics m[4];
    for (int i = 0; i < 4; i++) {
        bool ok = pb_render(&s, specs[i], &r[i], NULL, &err) && eval_frame(&s, specs[i], 0, 1, &m[i], NULL, NULL, &err);
        if (!ok) print_error("%s\n", err.msg);
        assert_true(ok);
        print_message("%-18s analytic: shadow %ld, technique %ld, mismatch %ld (%.3f%%); reference: err_rate %.5f, "
                      "res_err_mean %.3f\n", specs[i], r[i].shadow_exact, r[i].shadow_tech, r[i].mismatch,
                      100.0 * r[i].mismatch / r[i].pixels, m[i].err_rate, m[i].res_err_mean);
    }
    assert_true(r[0].shadow_exact > r[0].pixels / 4);   /* the shadow fills much of the view */
    for (int i = 0; i < 3; i++) {
        assert_true(r[i].mismatch < r[i].pixels / 200);
        assert_true(m[i].err_rate < 0.002);
    }
    /* the shift costs resolution: coarser texels than the inverse projection */
    assert_true(m[1].res_err_mean > m[0].res_err_mean + 0.1);
    /* the naive ordering loses (nearly) the whole shadow */
    assert_true(r[3].mismatch > r[3].shadow_exact / 2);
    assert_true(m[3].err_rate > 0.3);
    sb_session_close(&s);
}

static void test_backends_agree(void **st) {
    (void)st;
    const int w = 320, h = 180;
    unsigned char *va = malloc((size_t)w * h), *vb = malloc((size_t)w * h);
    sb_session a, b;
    sb_err err;
    pb_result ra, rb;
    assert_true(pb_open(&a, SB_BACKEND_EGL, w, h, &err));
    assert_true(pb_render(&a, "sm:res=1024:filter=pcf3", &ra, va, &err));
    sb_session_close(&a);
    assert_true(pb_open(&b, SB_BACKEND_OSMESA, w, h, &err));
    assert_true(pb_render(&b, "sm:res=1024:filter=pcf3", &rb, vb, &err));
    sb_session_close(&b);
    long differ = 0;
    for (int i = 0; i < w * h; i++) differ += abs((int)va[i] - (int)vb[i]) > 8;
    print_message("egl vs osmesa: %ld of %d visibility pixels differ\n", differ, w * h);
    assert_true(differ <= w * h / 1000);
    assert_int_equal(ra.plane, rb.plane);
    free(va);
    free(vb);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sm_matches_analytic_egl),
        cmocka_unit_test(test_sm_matches_analytic_osmesa),
        cmocka_unit_test(test_low_resolution_is_worse),
        cmocka_unit_test(test_backends_agree),
        cmocka_unit_test(test_cascaded_match_analytic),
        cmocka_unit_test(test_psm_sun_behind_camera),
        cmocka_unit_test(test_pcss_converges_to_hard),
        cmocka_unit_test(test_filtered_formats_converge),
    };
    return cmocka_run_group_tests_name("planebox", tests, NULL, NULL);
}
