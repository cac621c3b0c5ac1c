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

#include "scene_load.h"
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
    uint32_t *scratch;
} rig;

static void rig_camera(rig *r, double far_scale) {
    const sb_scene *s = &r->scene;
    sb_v3 ext = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    sb_v3 pos = sb_v3_add(s->origin, sb_v3_make((urand() - 0.5) * ext.x, s->bounds.lo.y + (0.05 + urand()) * ext.y,
                                                (urand() - 0.5) * ext.z));
    sb_v3 dir = sb_v3_make(urand() - 0.5, -urand() * 0.6, urand() - 0.5);
    sb_camera cam = sb_camera_look(pos, dir, 60, 16.0 / 9, 0.1, sb_v3_len(ext) * far_scale);
    r->gpu.sun = sb_sun_dir(urand() * 360, 3 + urand() * 87);
    sb_frame_setup(&r->frame, &r->gpu, &cam);
    r->frame.scratch = r->scratch;
}

static void rig_open(rig *r, const char *scene, int stable) {
    memset(r, 0, sizeof *r);
    sb_err err;
    assert_true(sb_scene_load(&r->scene, scene, NULL, &err));
    r->gpu.scene = &r->scene;
    r->scratch = malloc((r->scene.draw_count + 1) * sizeof(uint32_t));
    r->csm.count = r->csm.d.cascades = 4;
    r->csm.d.res = 1024;
    r->csm.d.stable = stable;
    r->csm.mask = calloc(r->scene.draw_count, 1);
}

static void rig_close(rig *r) {
    free(r->scratch);
    free(r->csm.mask);
    sb_scene_free(&r->scene);
}

static bool in_box(sb_v3 p, const sb_aabb *b) {
    return p.x >= b->lo.x && p.y >= b->lo.y && p.z >= b->lo.z && p.x <= b->hi.x && p.y <= b->hi.y && p.z <= b->hi.z;
}

static void coverage(const char *scene, int stable, int warp) {
    rig r;
    rig_open(&r, scene, stable);
    r.csm.d.warp = warp;
    r.csm.d.min_angle = 5;
    r.csm.d.focus = 0.3;
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
                    const uint32_t *ix = r.scene.indices + t;
                    float a[3], b[3], c[3];
                    sb_draw_point(&r.scene, dr, ix[0], a), sb_draw_point(&r.scene, dr, ix[1], b);
                    sb_draw_point(&r.scene, dr, ix[2], c);
                    if (!triangle_casts(&r.csm.fit[k], a, b, c))
                        continue;
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
    assert_true(sb_scene_load(&s, "towers", NULL, &err));
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
        sb_light_fit_lispsm(&s, sun, sb_v3_make(0, 5, 0), fwd, 0.5, 200, pts, 8, 1024, 5, false, &fit);
        double gamma = angles[i] > 90 ? 180 - angles[i] : angles[i];
        print_message("view at %5.1f deg from the light: %s (n_opt %.3g)\n", angles[i], fit.warped ? "warped" : "uniform",
                      fit.n_opt);
        assert_true(sb_m4_finite(fit.shadow_mat) && sb_m4_finite(fit.view_proj));
        assert_int_equal(fit.warped, gamma > 5);   /* the fallback engages below 5 degrees, in both directions */
        for (int e = 0; e < 16; e++) assert_false(isnan(fit.shadow_mat.m[e]));
    }
    sb_scene_free(&s);
}

static sb_camera look_camera(sb_v3 pos, sb_v3 target) {
    return sb_camera_look(pos, sb_v3_sub(target, pos), 60, 16.0 / 9, 0.05, 60);
}

/* Shadow-map coordinates of an origin-relative point: xyz / w, and w. */
static double shadow_coord(const sb_light_fit *f, sb_v3 p, sb_v3 *out) {
    const double *m = f->shadow_mat.m;
    double h[4];
    for (int r = 0; r < 4; r++) h[r] = m[r] * p.x + m[4 + r] * p.y + m[8 + r] * p.z + m[12 + r];
    *out = sb_v3_make(h[0] / h[3], h[1] / h[3], h[2] / h[3]);
    return h[3];
}

/* Does the origin-relative point pass the fit's caster-culling planes? */
static bool inside_planes(const sb_light_fit *f, sb_v3 p) {
    for (int i = 0; i < 6; i++)
        if (f->planes[i][0] * p.x + f->planes[i][1] * p.y + f->planes[i][2] * p.z + f->planes[i][3] < 0) return false;
    return true;
}

/* Is the world point on plane-box's ground inside the camera frustum? */
static bool in_view(const sb_camera *c, sb_v3 p) {
    sb_v3 d = sb_v3_sub(p, c->pos);
    double z = sb_v3_dot(d, c->forward), ty = tan(c->fov_deg * SB_PI / 360);
    return z > 0.3 && z < c->zfar && fabs(sb_v3_dot(d, c->right)) < z * ty * c->aspect &&
           fabs(sb_v3_dot(d, c->up)) < z * ty;
}

/* Entry distance of the ray p + t d into plane-box's box [-1,1]x[0,2]x[-1,1], or -1. */
static double box_entry(sb_v3 p, sb_v3 d) {
    const double lo[3] = {-1, 0, -1}, hi[3] = {1, 2, 1}, o[3] = {p.x, p.y, p.z}, v[3] = {d.x, d.y, d.z};
    double t0 = 1e-9, t1 = 1e300;
    for (int a = 0; a < 3; a++) {
        if (fabs(v[a]) < 1e-15) {
            if (o[a] < lo[a] || o[a] > hi[a]) return -1;
            continue;
        }
        double ta = (lo[a] - o[a]) / v[a], tb = (hi[a] - o[a]) / v[a];
        t0 = fmax(t0, fmin(ta, tb));
        t1 = fmin(t1, fmax(ta, tb));
    }
    return t0 <= t1 ? t0 : -1;
}

/* PSM with the sun behind the camera (the camera of tests/data/planebox-behind.path):
 * for every shadowed ground point in view, the box point that shadows it lies
 * behind the camera, on the same map texel; the inverse projection gives it a
 * smaller depth than the receiver and keeps it among the casters, the naive
 * ordering gives it a depth below 0 and culls it (clipped at the near plane, so
 * the shadow is lost). */
static void test_psm_behind_camera_order(void **st) {
    (void)st;
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, "plane-box", NULL, &err));
    sb_camera cam = look_camera(sb_v3_make(-2, 0.3, -3.75), sb_v3_make(-2.97, 0.126, -3.579));
    sb_v3 sun = sb_sun_dir(30, 20);
    sb_light_fit inv[6], naive[6];
    sb_psm_info ii, ni;
    assert_int_equal(sb_light_fit_psm(&s, sun, &cam, &(sb_psm_desc){.behind = SB_PSM_INVERSE, .res = 2048}, inv, &ii), 1);
    assert_int_equal(sb_light_fit_psm(&s, sun, &cam, &(sb_psm_desc){.behind = SB_PSM_NAIVE, .res = 2048}, naive, &ni), 1);
    assert_true(ii.inverted && !ii.fallback && !ii.ortho && !inv[0].empty && inv[0].warped);
    assert_true(sb_m4_finite(inv[0].shadow_mat) && sb_m4_finite(naive[0].shadow_mat));
    int checked = 0, clipped = 0;
    for (double x = -12; x <= 12; x += 0.05)
        for (double z = -12; z <= 12; z += 0.05) {
            sb_v3 p = sb_v3_make(x, 0, z);
            double t = box_entry(p, sun);
            if (!in_view(&cam, p) || t < 0 || (fabs(x) <= 1 && fabs(z) <= 1)) continue;
            sb_v3 q = sb_v3_add(p, sb_v3_scale(sun, t + 1e-3));   /* inside the caster */
            assert_true(sb_v3_dot(sb_v3_sub(q, cam.pos), cam.forward) < 0);
            sb_v3 pr = sb_v3_sub(p, s.origin), qr = sb_v3_sub(q, s.origin), cp = {0, 0, 0}, cq = {0, 0, 0};
            assert_true(shadow_coord(&inv[0], pr, &cp) > 0 && shadow_coord(&inv[0], qr, &cq) > 0);
            assert_true(cp.x >= 0 && cp.x <= 1 && cp.y >= 0 && cp.y <= 1 && cp.z >= 0 && cp.z <= 1);
            assert_true(fabs(cp.x - cq.x) < 1e-6 && fabs(cp.y - cq.y) < 1e-6);
            assert_true(cq.z < cp.z);                            /* the caster is nearer the light */
            assert_true(inside_planes(&inv[0], qr));             /* and culled in (depth clamp keeps it) */
            assert_true(shadow_coord(&naive[0], pr, &cp) > 0 && shadow_coord(&naive[0], qr, &cq) > 0);
            assert_true(cp.z >= 0 && cp.z <= 1);
            clipped += cq.z < 0 && !inside_planes(&naive[0], qr);   /* clipped at the near plane, culled out */
            checked++;
        }
    print_message("%d shadowed receivers in view, casters behind the camera; naive ordering clips %d of them\n", checked,
                  clipped);
    assert_true(checked > 100);
    assert_int_equal(clipped, checked);
    sb_scene_free(&s);
}

/* Every ground point in view maps into an active map (a cube face when cube=on). */
static void check_coverage(const sb_scene *s, const sb_camera *cam, const sb_light_fit *fits, int n) {
    int covered = 0, total = 0;
    for (double x = -20; x <= 20; x += 0.5)
        for (double z = -20; z <= 20; z += 0.5) {
            sb_v3 p = sb_v3_make(x, 0, z);
            if (!in_view(cam, p) || (fabs(x) <= 1 && fabs(z) <= 1)) continue;
            total++;
            for (int k = 0; k < n; k++) {
                sb_v3 c;
                if (fits[k].empty || shadow_coord(&fits[k], sb_v3_sub(p, s->origin), &c) <= 0) continue;
                if (c.x >= 0 && c.x <= 1 && c.y >= 0 && c.y <= 1 && c.z >= 0 && c.z <= 1) {
                    covered++;
                    break;
                }
            }
        }
    assert_true(total > 50);
    assert_int_equal(covered, total);
}

/* The sun right behind the camera: the light sits in the middle of the view in
 * PPS, so one frustum from it needs a wide angle (past max_fov the single map
 * falls back to the uniform map), the cube's faces share it; the sun across the
 * view: a directional light in PPS (orthographic map). */
static void test_psm_cube_and_limits(void **st) {
    (void)st;
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, "plane-box", NULL, &err));
    for (int back = 0; back < 2; back++) {
        sb_v3 sun = sb_sun_dir(30, 50);
        sb_v3 target = sb_v3_make(0, 1, 0);
        sb_v3 along = sb_v3_norm(sb_v3_cross(sun, sb_v3_make(0, 1, 0)));  /* horizontal, across the sun */
        sb_camera cam = look_camera(sb_v3_add(target, sb_v3_scale(back ? sun : along, 8)), target);
        sb_light_fit single[6], cube[6];
        sb_psm_info si, ci;
        assert_int_equal(sb_light_fit_psm(&s, sun, &cam, &(sb_psm_desc){.res = 2048}, single, &si), 1);
        assert_int_equal(sb_light_fit_psm(&s, sun, &cam, &(sb_psm_desc){.res = 2048, .cube = true}, cube, &ci), 6);
        int faces = 0;
        for (int k = 0; k < 6; k++) faces += !cube[k].empty;
        print_message("sun %s: single map %s; cube: %d faces\n", back ? "behind the camera" : "across the view",
                      si.fallback ? "fell back to uniform" : si.ortho ? "orthographic in PPS" : "perspective", faces);
        if (back) {
            assert_true(si.inverted && !si.ortho);
            assert_true(faces >= 2);
            sb_light_fit narrow[6];
            sb_psm_info ni;
            sb_light_fit_psm(&s, sun, &cam, &(sb_psm_desc){.res = 2048, .max_half_fov_deg = 30}, narrow, &ni);
            assert_true(ni.fallback && !narrow[0].warped);
            check_coverage(&s, &cam, narrow, 1);
        } else {
            assert_true(si.ortho && !si.fallback);
        }
        check_coverage(&s, &cam, single, 1);
        check_coverage(&s, &cam, cube, 6);
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
        cmocka_unit_test(test_psm_behind_camera_order),
        cmocka_unit_test(test_psm_cube_and_limits),
    };
    return cmocka_run_group_tests_name("cascade", tests, NULL, NULL);
}
