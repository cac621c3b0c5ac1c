/* Light-space fitting: every receiver the camera can see maps inside the shadow
 * map, and every caster that can shadow it lies in front of the far plane and
 * behind the near plane (nothing clipped toward the light). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "scene_load.h"
#include "lightfit.h"

static double urand(void) { return rand() / (double)RAND_MAX; }

static void check_scene(const char *name) {
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, name, NULL, &err));
    srand(11);
    sb_v3 ext = sb_v3_sub(s.bounds.hi, s.bounds.lo);
    int checked = 0;
    for (int trial = 0; trial < 50; trial++) {
        sb_v3 pos = sb_v3_add(s.origin, sb_v3_make((urand() - 0.5) * ext.x, s.bounds.lo.y + urand() * ext.y * 1.5,
                                                    (urand() - 0.5) * ext.z));
        sb_v3 dir = sb_v3_make(urand() - 0.5, -urand() * 0.5, urand() - 0.5);
        sb_camera cam = sb_camera_look(pos, dir, 60, 16.0 / 9, 0.1, sb_v3_len(ext));
        sb_v3 sun = sb_sun_dir(urand() * 360, 5 + urand() * 85);
        sb_v3 corners[8];
        sb_frustum_corners(&cam, s.origin, cam.znear, cam.zfar, corners);
        sb_light_fit fit;
        sb_light_fit_points(&s, sun, corners, 8, 2048, &fit);
        assert_true(sb_m4_finite(fit.shadow_mat));
        /* random receivers: points inside the frustum and the scene bounds */
        for (int k = 0; k < 200; k++) {
            double z = cam.znear + urand() * (cam.zfar - cam.znear);
            double ty = tan(cam.fov_deg * SB_PI / 360), tx = ty * cam.aspect;
            sb_v3 p = sb_v3_sub(cam.pos, s.origin);
            p = sb_v3_add(p, sb_v3_scale(cam.forward, z));
            p = sb_v3_add(p, sb_v3_scale(cam.right, (urand() * 2 - 1) * tx * z));
            p = sb_v3_add(p, sb_v3_scale(cam.up, (urand() * 2 - 1) * ty * z));
            if (p.x < s.bounds.lo.x || p.y < s.bounds.lo.y || p.z < s.bounds.lo.z || p.x > s.bounds.hi.x ||
                p.y > s.bounds.hi.y || p.z > s.bounds.hi.z)
                continue;
            sb_v3 c = sb_m4_point(fit.shadow_mat, p);
            assert_true(c.x >= 0 && c.x <= 1 && c.y >= 0 && c.y <= 1 && c.z >= 0 && c.z <= 1);
            checked++;
            /* any caster point between p and the light, inside the scene, is in front of the near plane */
            for (double t = 0; t < 1e4; t += sb_v3_len(ext) * 0.05) {
                sb_v3 q = sb_v3_add(p, sb_v3_scale(sun, t));
                if (q.x < s.bounds.lo.x || q.y < s.bounds.lo.y || q.z < s.bounds.lo.z || q.x > s.bounds.hi.x ||
                    q.y > s.bounds.hi.y || q.z > s.bounds.hi.z)
                    break;
                /* only caster geometry matters: test against draw boxes containing q */
                for (uint32_t d = 0; d < s.draw_count; d++) {
                    const sb_aabb *b = &s.draws[d].box;
                    if (q.x < b->lo.x || q.y < b->lo.y || q.z < b->lo.z || q.x > b->hi.x || q.y > b->hi.y ||
                        q.z > b->hi.z)
                        continue;
                    sb_v3 cq = sb_m4_point(fit.shadow_mat, q);
                    assert_true(cq.z >= -1e-9);
                }
            }
        }
    }
    print_message("%s: %d receiver samples inside their light frustum\n", name, checked);
    assert_true(checked > 500);
    sb_scene_free(&s);
}

static void test_fit_towers(void **st) { (void)st; check_scene("towers"); }
static void test_fit_overhangs(void **st) { (void)st; check_scene("overhangs"); }

static void test_light_view_orthonormal(void **st) {
    (void)st;
    const double els[] = {90, 89.999, 45, 0.5, -30};
    for (size_t i = 0; i < SB_COUNT(els); i++) {
        sb_m4 v = sb_light_view(sb_sun_dir(17, els[i]));
        assert_true(sb_m4_finite(v));
        /* the sun direction maps to +z in light space */
        sb_v3 z = sb_m4_dir(v, sb_sun_dir(17, els[i]));
        assert_true(fabs(z.z - 1) < 1e-12);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_fit_towers), cmocka_unit_test(test_fit_overhangs),
                                       cmocka_unit_test(test_light_view_orthonormal)};
    return cmocka_run_group_tests_name("lightfit", tests, NULL, NULL);
}
