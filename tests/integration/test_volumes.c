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
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    o.width = 480;
    o.height = 270;
    sb_session s;
    memset(&s, 0, sizeof s);
    sb_err err;
    assert_true(sb_session_open(&s, &o, "plane-box", path, &err));
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
    assert_true(s.scene.plane_count >= 1);
    pb_result r;
    assert_true(pb_render(&s, "planar", &r, NULL, &err));
    print_message("planar: shadow exact %ld, planar %ld, mismatch %ld (%.3f%% of image)\n", r.shadow_exact,
                  r.shadow_tech, r.mismatch, 100.0 * r.mismatch / r.pixels);
    assert_true(r.shadow_exact > r.pixels / 100);
    assert_true(r.mismatch * 1000 < r.pixels * 2);
    sb_session_close(&s);
    /* the terrain of desert has no large plane: the technique is skipped with the reason */
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    o.width = 64;
    o.height = 36;
    memset(&s, 0, sizeof s);
    assert_true(sb_session_open(&s, &o, "desert", "desert", &err));
    const char *why = sb_skip_reason(&s, sb_technique_find("planar"));
    assert_non_null(why);
    assert_string_equal(why, "the scene has no large planar receiver");
    assert_null(sb_skip_reason(&s, sb_technique_find("volumes")));
    sb_session_close(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_volumes_match_analytic),
                                       cmocka_unit_test(test_camera_inside_volume), cmocka_unit_test(test_planar)};
    return cmocka_run_group_tests_name("volumes", tests, NULL, NULL);
}
