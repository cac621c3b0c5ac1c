/* Paths: parsing, errors with file:line, centripetal Catmull-Rom through the
 * keys with a continuous first derivative, slerp of unit length. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>

#include "path.h"

static const char *text =
    "# test path\n"
    "fov 50\n"
    "key 0   0 0 0    0 0 0 1\n"
    "look 1  4 1 0    4 1 -10   70\n"
    "key 3   6 5 -2   0 0.7071068 0 0.7071068\n"
    "look 4  10 5 -8  0 0 0\n";

static void test_parse_and_pass_through_keys(void **st) {
    (void)st;
    sb_path p;
    sb_err err;
    assert_true(sb_path_parse(&p, "t.path", text, &err));
    assert_int_equal(p.key_count, 4);
    assert_true(fabs(p.fov_deg - 50) < 1e-12);
    for (int i = 0; i < p.key_count; i++) {
        sb_v3 pos;
        sb_quat q;
        double fov;
        sb_path_eval(&p, p.keys[i].t, &pos, &q, &fov);
        assert_true(sb_v3_len(sb_v3_sub(pos, p.keys[i].pos)) < 1e-9);
        double dot = fabs(q.x * p.keys[i].rot.x + q.y * p.keys[i].rot.y + q.z * p.keys[i].rot.z + q.w * p.keys[i].rot.w);
        assert_true(fabs(dot - 1) < 1e-9);
    }
    sb_v3 pos;
    sb_quat q;
    double fov;
    sb_path_eval(&p, 1.0, &pos, &q, &fov);
    assert_true(fabs(fov - 70) < 1e-9);
    sb_path_free(&p);
}

static void test_c1_at_keys(void **st) {
    (void)st;
    sb_path p;
    sb_err err;
    assert_true(sb_path_parse(&p, "t.path", text, &err));
    for (int i = 1; i + 1 < p.key_count; i++) {
        double t = p.keys[i].t, h = 1e-5;
        sb_v3 a, b, c;
        sb_quat q;
        double fov;
        sb_path_eval(&p, t - h, &a, &q, &fov);
        sb_path_eval(&p, t, &b, &q, &fov);
        sb_path_eval(&p, t + h, &c, &q, &fov);
        sb_v3 left = sb_v3_scale(sb_v3_sub(b, a), 1 / h), right = sb_v3_scale(sb_v3_sub(c, b), 1 / h);
        /* centripetal Catmull-Rom in non-uniform time is C1 in its own parameter;
           with key times that differ per segment the velocity scales by the segment's
           duration, so compare directions, which must agree */
        double cosang = sb_v3_dot(sb_v3_norm(left), sb_v3_norm(right));
        print_message("key %d: velocity direction cos %.9f\n", i, cosang);
        assert_true(cosang > 0.999);
    }
    sb_path_free(&p);
}

static void test_slerp_unit_length(void **st) {
    (void)st;
    sb_quat a = sb_quat_norm((sb_quat){0.1, 0.7, -0.2, 0.6}), b = sb_quat_norm((sb_quat){-0.5, 0.1, 0.8, -0.1});
    for (int i = 0; i <= 100; i++) {
        sb_quat q = sb_quat_slerp(a, b, i / 100.0);
        double l = sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
        assert_true(fabs(l - 1) < 1e-12);
    }
    /* shortest arc: slerp toward -b equals slerp toward b */
    sb_quat nb = {-b.x, -b.y, -b.z, -b.w};
    sb_quat x = sb_quat_slerp(a, b, 0.3), y = sb_quat_slerp(a, nb, 0.3);
    assert_true(fabs(fabs(x.x * y.x + x.y * y.y + x.z * y.z + x.w * y.w) - 1) < 1e-12);
}

static void test_sampling_is_frame_based(void **st) {
    (void)st;
    sb_path p;
    sb_err err;
    assert_true(sb_path_parse(&p, "t.path", text, &err));
    sb_camera c0 = sb_path_camera(&p, 0, 5, 1.5, NULL), c4 = sb_path_camera(&p, 4, 5, 1.5, NULL);
    assert_true(sb_v3_len(sb_v3_sub(c0.pos, p.keys[0].pos)) < 1e-12);
    assert_true(sb_v3_len(sb_v3_sub(c4.pos, p.keys[3].pos)) < 1e-12);
    assert_true(fabs(sb_path_progress(2, 5) - 0.5) < 1e-15);
    /* look keys really look at their target */
    sb_camera c = sb_path_camera(&p, 0, 1, 1.5, NULL);
    assert_true(fabs(sb_v3_dot(c.forward, sb_v3_make(0, 0, -1)) - 1) < 1e-9);
    sb_path_free(&p);
}

static void expect_error(const char *txt, const char *needle) {
    sb_path p;
    sb_err err = {{0}};
    assert_false(sb_path_parse(&p, "bad.path", txt, &err));
    print_message("error: %s\n", err.msg);
    assert_non_null(strstr(err.msg, needle));
}

static void test_malformed_lines(void **st) {
    (void)st;
    expect_error("key 0 0 0 0 0 0 0 1\nkey 1 0 0 x 0 0 0 1\n", "bad.path:2:");
    expect_error("key 0 0 0 0 0 0 0 1\nkye 1 0 0 0 0 0 0 1\n", "bad.path:2: unknown directive 'kye'");
    expect_error("key 0 0 0 0 0 0 0\n", "bad.path:1:");
    expect_error("key 1 0 0 0 0 0 0 1\nkey 1 1 0 0 0 0 0 1\n", "bad.path:2: time 1 does not increase");
    expect_error("key 0 0 0 0 0 0 0 0\n", "bad.path:1: orientation quaternion has zero length");
    expect_error("# nothing\n", "no keyframes");
    expect_error("key 0 nan 0 0 0 0 0 1\n", "bad.path:1:");
    /* found by fuzzing (tests/fuzz/regressions/path): a coordinate whose interpolation overflowed */
    expect_error("look 0 0 6e39 12 0 0.5 0\nlook 4 10 6 6 0 0.5 0\n", "bad.path:1: '6e39' is out of range");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_and_pass_through_keys), cmocka_unit_test(test_c1_at_keys),
        cmocka_unit_test(test_slerp_unit_length), cmocka_unit_test(test_sampling_is_frame_based),
        cmocka_unit_test(test_malformed_lines),
    };
    return cmocka_run_group_tests_name("path", tests, NULL, NULL);
}
