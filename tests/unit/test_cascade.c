/* Cascade machinery without GL: split schemes, SDSM partitions, coverage of
 * every visible sample by the cascade that shades it, and caster culling
 * that is conservative (brute force over every triangle) and reasonably tight. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "cascade.h"

void sdsm_partition(int m, int histogram, double zmin, double zmax, double near, double far, const uint32_t *hist,
                    double *s);

static double urand(void) { return rand() / (double)RAND_MAX; }

static void test_split_schemes(void **st) {
    (void)st;
    const double n = 0.5, f = 800;
    for (int m = 1; m <= 8; m++) {
        double uni[9], lg[9], pr[9];
        sb_split_distances(0.0, m, n, f, uni);
        sb_split_distances(1.0, m, n, f, lg);
        sb_split_distances(0.5, m, n, f, pr);
        assert_true(uni[0] == n && uni[m] == f && lg[0] == n && lg[m] == f && pr[0] == n && pr[m] == f);
        for (int i = 0; i <= m; i++) {
            assert_true(fabs(uni[i] - (n + (f - n) * i / m)) < 1e-9);
            assert_true(fabs(lg[i] - n * pow(f / n, (double)i / m)) < 1e-9 * lg[i]);
            assert_true(fabs(pr[i] - 0.5 * (uni[i] + lg[i])) < 1e-9 * pr[i]);
            if (i) assert_true(uni[i] > uni[i - 1] && lg[i] > lg[i - 1] && pr[i] > pr[i - 1]);
        }
    }
}

static void test_sdsm_partitions(void **st) {
    (void)st;
    /* samples only in two depth ranges: [1, 2] and [400, 800]; nothing between */
    const double near = 0.5, far = 1000;
    uint32_t hist[64] = {0};
    double l0 = log(near), w = (log(far) - l0) / 64;
    for (int b = 0; b < 64; b++) {
        double lo = exp(l0 + b * w), hi = exp(l0 + (b + 1) * w);
        if ((hi > 1 && lo < 2) || (hi > 400 && lo < 800)) hist[b] = 100;
    }
    double s[9];
    sdsm_partition(4, 1, 1.0, 800, near, far, hist, s);
    assert_true(s[0] == 1.0 && s[4] == 800);
    for (int i = 1; i < 4; i++) {
        assert_true(s[i] > s[i - 1]);
        int b = (int)floor((log(s[i]) - l0) / w);
        print_message("histogram split %d at %.3f (bin %d, %u samples)\n", i, s[i], b, hist[b]);
        assert_true(hist[b] > 0 || hist[b - 1] > 0);   /* never inside an empty depth range */
    }
    /* the log scheme puts splits into the empty range */
    sdsm_partition(4, 0, 1.0, 800, near, far, hist, s);
    int empty = 0;
    for (int i = 1; i < 4; i++) empty += s[i] > 2.5 && s[i] < 350;
    assert_true(empty > 0);
}

typedef struct {
    sb_scene scene;
    sb_gpu gpu;
    sb_frame frame;
    sb_csm csm;
} rig;

static void rig_camera(rig *r, double far_scale) {
    const sb_scene *s = &r->scene;
    sb_v3 ext = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    sb_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.pos = sb_v3_add(s->origin, sb_v3_make((urand() - 0.5) * ext.x, s->bounds.lo.y + (0.05 + urand()) * ext.y,
                                              (urand() - 0.5) * ext.z));
    cam.rot = sb_quat_look(sb_v3_make(urand() - 0.5, -urand() * 0.6, urand() - 0.5), sb_v3_make(0, 1, 0));
    cam.right = sb_quat_rotate(cam.rot, sb_v3_make(1, 0, 0));
    cam.up = sb_quat_rotate(cam.rot, sb_v3_make(0, 1, 0));
    cam.forward = sb_quat_rotate(cam.rot, sb_v3_make(0, 0, -1));
    cam.fov_deg = 60;
    cam.aspect = 16.0 / 9;
    cam.znear = 0.1;
    cam.zfar = sb_v3_len(ext) * far_scale;
    r->gpu.sun = sb_sun_dir(urand() * 360, 3 + urand() * 87);
    sb_frame_setup(&r->frame, &r->gpu, &cam);
}

static void rig_open(rig *r, const char *scene, int stable) {
    memset(r, 0, sizeof *r);
    sb_err err;
    assert_true(sb_scene_load(&r->scene, scene, &err));
    r->gpu.scene = &r->scene;
    r->gpu.scratch = malloc((r->scene.draw_count + 1) * sizeof(uint32_t));
    r->csm.count = 4;
    r->csm.res = 1024;
    r->csm.stable = stable;
    r->csm.mask = calloc(r->scene.draw_count, 1);
}

static void rig_close(rig *r) {
    free(r->gpu.scratch);
    free(r->csm.mask);
    sb_scene_free(&r->scene);
}

static bool in_box(sb_v3 p, const sb_aabb *b) {
    return p.x >= b->lo.x && p.y >= b->lo.y && p.z >= b->lo.z && p.x <= b->hi.x && p.y <= b->hi.y && p.z <= b->hi.z;
}

static void coverage(const char *scene, int stable, int warp) {
    rig r;
    rig_open(&r, scene, stable);
    r.csm.warp = warp;
    r.csm.min_angle = 5;
    r.csm.focus = 0.3;
    int warped = 0;
    srand(5);
    long samples = 0;
    for (int trial = 0; trial < 40; trial++) {
        rig_camera(&r, 1.0);
        const sb_camera *cam = &r.frame.cam;
        double splits[9];
        sb_split_distances(0.5, 4, cam->znear, cam->zfar, splits);
        for (int k = 0; k < 4; k++) {
            sb_csm_fit_slice(&r.csm, &r.frame, splits[k], splits[k + 1], &r.csm.fit[k]);
            assert_true(sb_m4_finite(r.csm.fit[k].shadow_mat));
            warped += r.csm.fit[k].warped;
        }
        double ty = tan(cam->fov_deg * SB_PI / 360), tx = ty * cam->aspect;
        sb_v3 eye = sb_v3_sub(cam->pos, r.scene.origin);
        for (int i = 0; i < 3000; i++) {
            double z = cam->znear + pow(urand(), 2) * (cam->zfar - cam->znear);
            sb_v3 p = sb_v3_add(eye, sb_v3_scale(cam->forward, z));
            p = sb_v3_add(p, sb_v3_scale(cam->right, (urand() * 2 - 1) * tx * z));
            p = sb_v3_add(p, sb_v3_scale(cam->up, (urand() * 2 - 1) * ty * z));
            /* a sample on (or in the box of) some geometry */
            bool on = false;
            for (uint32_t d = 0; d < r.scene.draw_count && !on; d++) on = in_box(p, &r.scene.draws[d].box);
            if (!on) continue;
            int k = 0;
            while (k < 3 && z > splits[k + 1]) k++;
            sb_v3 c = sb_m4_point(r.csm.fit[k].shadow_mat, p);
            if (!(c.x >= 0 && c.x <= 1 && c.y >= 0 && c.y <= 1 && c.z >= 0 && c.z <= 1))
                fail_msg("%s stable=%d warp=%d: sample at view depth %g outside cascade %d: (%g, %g, %g)", scene, stable,
                         warp, z, k, c.x, c.y, c.z);
            samples++;
        }
    }
    print_message("%s stable=%d warp=%d: %ld visible samples inside the light frustum of their cascade (%d warped fits)\n",
                  scene, stable, warp, samples, warped);
    assert_true(samples > 1000);
    if (warp) assert_true(warped > 0);
    rig_close(&r);
}

static void test_coverage(void **st) {
    (void)st;
    const char *scenes[] = {"desert", "towers", "overhangs"};
    for (int i = 0; i < 3; i++) {
        coverage(scenes[i], 0, 0);
        coverage(scenes[i], 1, 0);
        coverage(scenes[i], 0, 1);   /* LiSPSM: the warped (projective) maps cover their slices too */
        coverage(scenes[i], 0, 2);   /* TSM */
    }
}

/* Does the triangle reach into the cascade's light volume (x/y window, not beyond the far plane)? */
static bool triangle_casts(const sb_light_fit *fit, const float *v0, const float *v1, const float *v2) {
    sb_v3 c[3] = {sb_m4_point(fit->view_proj, sb_v3_make(v0[0], v0[1], v0[2])),
                  sb_m4_point(fit->view_proj, sb_v3_make(v1[0], v1[1], v1[2])),
                  sb_m4_point(fit->view_proj, sb_v3_make(v2[0], v2[1], v2[2]))};
    for (int a = 0; a < 2; a++) {
        double lo = 1e300, hi = -1e300;
        for (int i = 0; i < 3; i++) {
            double x = a ? c[i].y : c[i].x;
            lo = fmin(lo, x);
            hi = fmax(hi, x);
        }
        if (lo > 1 || hi < -1) return false;
    }
    return fmin(fmin(c[0].z, c[1].z), c[2].z) <= 1;
}

static void culling(const char *scene) {
    rig r;
    rig_open(&r, scene, 0);
    srand(9);
    uint64_t submitted = 0, necessary = 0;
    for (int trial = 0; trial < 25; trial++) {
        rig_camera(&r, 0.6);
        double splits[9];
        sb_split_distances(0.5, 4, r.frame.cam.znear, r.frame.cam.zfar, splits);
        for (int k = 0; k < 4; k++) {
            sb_csm_fit_slice(&r.csm, &r.frame, splits[k], splits[k + 1], &r.csm.fit[k]);
            r.csm.active[k] = true;
        }
        sb_csm_cull(&r.csm, &r.frame, NULL);
        for (int k = 0; k < 4; k++) {
            for (uint32_t d = 0; d < r.scene.draw_count; d++) {
                const sb_draw *dr = &r.scene.draws[d];
                bool culled = !(r.csm.mask[d] & (1u << k));
                if (!culled) submitted += dr->index_count / 3;
                for (uint32_t t = dr->first_index; t < dr->first_index + dr->index_count; t += 3) {
                    const float *v = r.scene.vertices;
                    const uint32_t *ix = r.scene.indices + t;
                    if (!triangle_casts(&r.csm.fit[k], v + 6 * ix[0], v + 6 * ix[1], v + 6 * ix[2])) continue;
                    necessary++;
                    if (culled) fail_msg("%s: draw %u culled from cascade %d but triangle %u casts into it", scene, d, k, t / 3);
                }
            }
        }
    }
    print_message("%s: submitted %llu / necessary %llu triangles = %.2f\n", scene, (unsigned long long)submitted,
                  (unsigned long long)necessary, (double)submitted / (double)necessary);
    assert_true(submitted >= necessary);
    rig_close(&r);
}

static void test_culling_conservative_and_tight(void **st) {
    (void)st;
    culling("towers");
    culling("overhangs");
    culling("desert");
}

static void test_lispsm_fallback(void **st) {
    (void)st;
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, "towers", &err));
    sb_v3 sun = sb_sun_dir(200, 55);
    const double angles[] = {0, 0.5, 4.9, 5.1, 30, 90, 150, 179.9, 180};
    for (size_t i = 0; i < SB_COUNT(angles); i++) {
        /* a view direction at `angle` from the direction toward the sun */
        sb_v3 right, up;
        sb_basis(sun, &right, &up);
        double a = angles[i] * SB_PI / 180;
        sb_v3 fwd = sb_v3_add(sb_v3_scale(sun, cos(a)), sb_v3_scale(up, sin(a)));
        sb_v3 pts[8];
        for (int k = 0; k < 8; k++)
            pts[k] = sb_v3_make(k & 1 ? 20 : -20, k & 2 ? 10 : -5, k & 4 ? 30 : -30);
        sb_light_fit fit;
        sb_light_fit_lispsm(&s, sun, sb_v3_make(0, 5, 0), fwd, 0.5, 200, pts, 8, 1024, 5, &fit);
        double gamma = angles[i] > 90 ? 180 - angles[i] : angles[i];
        print_message("view at %5.1f deg from the light: %s (n_opt %.3g)\n", angles[i], fit.warped ? "warped" : "uniform",
                      fit.n_opt);
        assert_true(sb_m4_finite(fit.shadow_mat) && sb_m4_finite(fit.view_proj));
        assert_int_equal(fit.warped, gamma > 5);   /* the fallback engages below 5 degrees, in both directions */
        for (int e = 0; e < 16; e++) assert_false(isnan(fit.shadow_mat.m[e]));
    }
    sb_scene_free(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_split_schemes),
        cmocka_unit_test(test_sdsm_partitions),
        cmocka_unit_test(test_coverage),
        cmocka_unit_test(test_culling_conservative_and_tight),
        cmocka_unit_test(test_lispsm_fallback),
    };
    return cmocka_run_group_tests_name("cascade", tests, NULL, NULL);
}
