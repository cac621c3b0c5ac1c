/* lightfit.c - orthographic light frustum fitting. */
#include "lightfit.h"

#include <string.h>

sb_m4 sb_light_view(sb_v3 sun) {
    sb_v3 fwd = sb_v3_scale(sb_v3_norm(sun), -1), right, up;
    sb_basis(fwd, &right, &up);
    return sb_m4_view(sb_v3_make(0, 0, 0), right, up, fwd);
}

void sb_frustum_corners(const sb_camera *cam, sb_v3 origin, double zn, double zf, sb_v3 out[8]) {
    double ty = tan(cam->fov_deg * SB_PI / 360), tx = ty * cam->aspect;
    sb_v3 eye = sb_v3_sub(cam->pos, origin);
    for (int i = 0; i < 8; i++) {
        double z = i < 4 ? zn : zf;
        double sx = (i & 1) ? 1 : -1, sy = (i & 2) ? 1 : -1;
        sb_v3 p = sb_v3_add(eye, sb_v3_scale(cam->forward, z));
        p = sb_v3_add(p, sb_v3_scale(cam->right, sx * tx * z));
        out[i] = sb_v3_add(p, sb_v3_scale(cam->up, sy * ty * z));
    }
}

static void box_in_light(sb_m4 view, const sb_aabb *b, sb_v3 *lo, sb_v3 *hi) {
    *lo = sb_v3_make(1e300, 1e300, 1e300);
    *hi = sb_v3_make(-1e300, -1e300, -1e300);
    for (int k = 0; k < 8; k++) {
        sb_v3 q = sb_v3_make(k & 1 ? b->hi.x : b->lo.x, k & 2 ? b->hi.y : b->lo.y, k & 4 ? b->hi.z : b->lo.z);
        sb_v3 l = sb_m4_point(view, q);
        *lo = sb_v3_min(*lo, l);
        *hi = sb_v3_max(*hi, l);
    }
}

typedef struct {
    const sb_scene *s;
    sb_m4 view;
    double zmax;
} caster_scan;

static void scan_caster(uint32_t d, void *user) {
    caster_scan *c = user;
    sb_v3 lo, hi;
    box_in_light(c->view, &c->s->draws[d].box, &lo, &hi);
    if (hi.z > c->zmax) c->zmax = hi.z;
}

/* Completes a fit from a light-space x/y window and the receivers' z range:
 * extends toward the light to the farthest caster over the window (BVH). */
static void finish_fit(const sb_scene *s, sb_v3 lo, sb_v3 hi, double shi_z, int res, sb_light_fit *out) {
    double side[5][4], all[6][4];
    sb_m4 probe = sb_m4_mul(sb_m4_ortho(lo.x, hi.x, lo.y, hi.y, -shi_z, -lo.z), out->view);
    sb_frustum_planes(probe, all);
    memcpy(side, all, 4 * sizeof all[0]);      /* x and y planes */
    memcpy(side[4], all[5], sizeof all[0]);    /* far plane: not beyond the receivers */
    caster_scan sc = {s, out->view, hi.z};
    sb_bvh_cull(s, (const double(*)[4])side, 5, scan_caster, &sc);
    double znear_l = sc.zmax, zfar_l = lo.z;   /* light space z: toward the light is +z */
    double pad = 1e-4 * (znear_l - zfar_l) + 1e-9;
    out->l = lo.x;
    out->r = hi.x;
    out->b = lo.y;
    out->t = hi.y;
    out->zn = -znear_l - pad;
    out->zf = -zfar_l + pad;
    out->proj = sb_m4_ortho(out->l, out->r, out->b, out->t, out->zn, out->zf);
    out->view_proj = sb_m4_mul(out->proj, out->view);
    sb_frustum_planes(out->view_proj, out->planes);
    sb_m4 bias = sb_m4_identity();
    bias.m[0] = bias.m[5] = bias.m[10] = 0.5;
    bias.m[12] = bias.m[13] = bias.m[14] = 0.5;
    out->shadow_mat = sb_m4_mul(bias, out->view_proj);
    out->texel_world = fmax(out->r - out->l, out->t - out->b) / res;
}

void sb_light_fit_points(const sb_scene *s, sb_v3 sun, const sb_v3 *pts, int n, int res, sb_light_fit *out) {
    memset(out, 0, sizeof *out);
    out->view = sb_light_view(sun);
    sb_v3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    for (int i = 0; i < n; i++) {
        sb_v3 l = sb_m4_point(out->view, pts[i]);
        lo = sb_v3_min(lo, l);
        hi = sb_v3_max(hi, l);
    }
    sb_v3 slo, shi;
    box_in_light(out->view, &s->bounds, &slo, &shi);
    /* receivers are only where the scene is */
    lo = sb_v3_max(lo, slo);
    hi = sb_v3_min(hi, shi);
    if (lo.x >= hi.x || lo.y >= hi.y || lo.z >= hi.z) {
        out->empty = true;
        lo = slo;
        hi = shi;
    }
    /* a guard band of one texel on each side keeps filter taps inside */
    double gx = (hi.x - lo.x) / res, gy = (hi.y - lo.y) / res;
    lo.x -= gx; hi.x += gx;
    lo.y -= gy; hi.y += gy;
    finish_fit(s, lo, hi, shi.z, res, out);
}

void sb_light_fit_stable(const sb_scene *s, sb_v3 sun, const sb_v3 *pts, int n, int res, sb_light_fit *out) {
    memset(out, 0, sizeof *out);
    out->view = sb_light_view(sun);
    /* a bounding sphere of the slice: its size does not change when the camera rotates */
    sb_v3 c = {0, 0, 0};
    for (int i = 0; i < n; i++) c = sb_v3_add(c, pts[i]);
    c = sb_v3_scale(c, 1.0 / n);
    double r = 0;
    for (int i = 0; i < n; i++) r = fmax(r, sb_v3_len(sb_v3_sub(pts[i], c)));
    /* quantise the radius so rounding noise cannot change the texel size */
    double q = pow(2.0, floor(log2(r)) - 8);
    r = ceil(r / q) * q;
    double texel = 2 * r / res;
    sb_v3 cl = sb_m4_point(out->view, c);
    /* snap the window origin to whole texels: a translating camera moves it by whole texels only */
    cl.x = floor(cl.x / texel) * texel;
    cl.y = floor(cl.y / texel) * texel;
    sb_v3 slo, shi;
    box_in_light(out->view, &s->bounds, &slo, &shi);
    /* depth spans the scene: a range that followed the camera would move every depth value */
    sb_v3 lo = {cl.x - r, cl.y - r, slo.z}, hi = {cl.x + r, cl.y + r, shi.z};
    finish_fit(s, lo, hi, shi.z, res, out);
}

void sb_light_fit_lispsm(const sb_scene *s, sb_v3 sun, sb_v3 eye, sb_v3 forward, double zn, double zf,
                         const sb_v3 *pts, int n, int res, double min_gamma_deg, sb_light_fit *out) {
    sun = sb_v3_norm(sun);
    double cos_g = sb_v3_dot(sb_v3_norm(forward), sun), sin_g = sqrt(fmax(0, 1 - cos_g * cos_g));
    if (sin_g < sin(min_gamma_deg * SB_PI / 180) || zn <= 0) { /* view along the light: no useful warp */
        sb_light_fit_points(s, sun, pts, n, res, out);
        return;
    }
    /* the uniform fit first: its caster extension and receiver window bound the body */
    sb_light_fit_points(s, sun, pts, n, res, out);
    if (out->empty) return;
    /* light view whose up axis is the view direction projected perpendicular to the light */
    sb_v3 fwd = sb_v3_scale(sun, -1);
    sb_v3 up = sb_v3_norm(sb_v3_sub(forward, sb_v3_scale(fwd, sb_v3_dot(forward, fwd))));
    sb_v3 right = sb_v3_norm(sb_v3_cross(fwd, up));
    up = sb_v3_cross(right, fwd);
    sb_m4 lv = sb_m4_view(sb_v3_make(0, 0, 0), right, up, fwd);
    /* body: the slice corners inside the scene, and the same points pushed toward the light to the
       farthest caster (so every caster over the receivers is inside the warped frustum) */
    sb_v3 blo = {1e300, 1e300, 1e300}, bhi = {-1e300, -1e300, -1e300};
    for (int i = 0; i < n; i++) {
        sb_v3 q = sb_m4_point(lv, pts[i]);
        blo = sb_v3_min(blo, q);
        bhi = sb_v3_max(bhi, q);
    }
    sb_v3 slo = {1e300, 1e300, 1e300}, shi = {-1e300, -1e300, -1e300};
    for (int k = 0; k < 8; k++) {
        sb_v3 q = sb_m4_point(lv, sb_v3_make(k & 1 ? s->bounds.hi.x : s->bounds.lo.x, k & 2 ? s->bounds.hi.y : s->bounds.lo.y,
                                             k & 4 ? s->bounds.hi.z : s->bounds.lo.z));
        slo = sb_v3_min(slo, q);
        shi = sb_v3_max(shi, q);
    }
    blo = sb_v3_max(blo, slo);
    bhi = sb_v3_min(bhi, shi);
    if (blo.x >= bhi.x || blo.y >= bhi.y) return; /* keep the uniform fit */
    double zmax = shi.z + 1e-4 * (shi.z - slo.z), zmin = blo.z;
    double d = bhi.y - blo.y;
    double nopt = (zn + sqrt(zn * zf)) / sin_g;
    nopt = fmax(nopt, 1e-4 * d);
    /* the warp's centre: below the body along y, at the camera's x */
    sb_v3 eye_l = sb_m4_point(lv, eye);
    double cx = fmin(fmax(eye_l.x, blo.x), bhi.x), cy = blo.y - nopt;
    double nn = nopt, ff = nopt + d;
    sb_m4 t = sb_m4_translate(sb_v3_make(-cx, -cy, 0));
    sb_m4 p = {{0}};
    /* x' = x, y' = (f+n)/(f-n) y - 2fn/(f-n), z' = z, w = y: a perspective along +y */
    p.m[0] = 1;
    p.m[5] = (ff + nn) / (ff - nn);
    p.m[13] = -2 * ff * nn / (ff - nn);
    p.m[10] = 1;
    p.m[7] = 1;
    sb_m4 warp = sb_m4_mul(p, sb_m4_mul(t, lv));
    sb_v3 wlo = {1e300, 1e300, 1e300}, whi = {-1e300, -1e300, -1e300};
    for (int k = 0; k < 8; k++) {
        sb_v3 q = sb_v3_make(k & 1 ? bhi.x : blo.x, k & 2 ? bhi.y : blo.y, k & 4 ? zmax : zmin);
        /* back to world to warp: invert lv (orthonormal) */
        sb_m4 inv;
        sb_m4_invert(lv, &inv);
        sb_v3 w = sb_m4_point(warp, sb_m4_point(inv, q));
        wlo = sb_v3_min(wlo, w);
        whi = sb_v3_max(whi, w);
    }
    if (!(whi.x > wlo.x && whi.y > wlo.y && whi.z > wlo.z)) return;
    /* ortho fit of the warped body: z toward the light is +z, so near = -zmax */
    sb_m4 o = sb_m4_ortho(wlo.x, whi.x, wlo.y, whi.y, -whi.z, -wlo.z);
    sb_m4 vp = sb_m4_mul(o, warp);
    if (!sb_m4_finite(vp)) return;
    out->view = lv;
    out->proj = sb_m4_mul(o, sb_m4_mul(p, t));
    out->view_proj = vp;
    sb_frustum_planes(vp, out->planes);
    sb_m4 bias = sb_m4_identity();
    bias.m[0] = bias.m[5] = bias.m[10] = 0.5;
    bias.m[12] = bias.m[13] = bias.m[14] = 0.5;
    out->shadow_mat = sb_m4_mul(bias, vp);
    /* texel and depth scales for bias: the body's extent spread over the map (an average) */
    out->texel_world = fmax(bhi.x - blo.x, d) / res;
    out->zn = -zmax;
    out->zf = -zmin;
    out->warped = true;
    out->n_opt = nopt;
}

/* Solves the 3x3 homography H (row-major) with H src[i] ~ dst[i], i < 4. */
static bool homography(const double src[4][2], const double dst[4][2], double H[9]) {
    double A[8][9];
    for (int i = 0; i < 4; i++) {
        double x = src[i][0], y = src[i][1], u = dst[i][0], v = dst[i][1];
        double r1[9] = {x, y, 1, 0, 0, 0, -u * x, -u * y, u};
        double r2[9] = {0, 0, 0, x, y, 1, -v * x, -v * y, v};
        memcpy(A[2 * i], r1, sizeof r1);
        memcpy(A[2 * i + 1], r2, sizeof r2);
    }
    for (int c = 0; c < 8; c++) { /* Gaussian elimination with partial pivoting; h8 = 1 */
        int piv = c;
        for (int r = c + 1; r < 8; r++)
            if (fabs(A[r][c]) > fabs(A[piv][c])) piv = r;
        if (fabs(A[piv][c]) < 1e-14) return false;
        for (int k = 0; k < 9; k++) {
            double t = A[c][k];
            A[c][k] = A[piv][k];
            A[piv][k] = t;
        }
        for (int r = 0; r < 8; r++) {
            if (r == c) continue;
            double f = A[r][c] / A[c][c];
            for (int k = c; k < 9; k++) A[r][k] -= f * A[c][k];
        }
    }
    for (int i = 0; i < 8; i++) H[i] = A[i][8] / A[i][i];
    H[8] = 1;
    return true;
}

void sb_light_fit_tsm(const sb_scene *s, sb_v3 sun, const sb_v3 *pts, int res, double focus, sb_light_fit *out) {
    sb_light_fit_points(s, sun, pts, 8, res, out);
    if (out->empty) return;
    /* the footprint in the uniform map's [-1,1]^2 */
    double q[8][2];
    for (int i = 0; i < 8; i++) {
        sb_v3 c = sb_m4_point(out->view_proj, pts[i]);
        q[i][0] = c.x;
        q[i][1] = c.y;
    }
    double nc[2] = {0, 0}, fc[2] = {0, 0};
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 2; k++) {
            nc[k] += q[i][k] / 4;
            fc[k] += q[4 + i][k] / 4;
        }
    double ax[2] = {fc[0] - nc[0], fc[1] - nc[1]}, len = hypot(ax[0], ax[1]);
    if (len < 1e-6) return; /* looking along the light: no trapezoid, keep the uniform map */
    ax[0] /= len;
    ax[1] /= len;
    double px[2] = {-ax[1], ax[0]};
    /* footprint in the centre-line frame: t along the line from the near centre, u across */
    double tmin = 1e300, tmax = -1e300;
    for (int i = 0; i < 8; i++) {
        double t = (q[i][0] - nc[0]) * ax[0] + (q[i][1] - nc[1]) * ax[1];
        tmin = fmin(tmin, t);
        tmax = fmax(tmax, t);
    }
    double lambda = tmax - tmin;
    /* the 80% rule: the focus point (focus of the way from top to base) lands on the 80% line */
    double delta = focus * lambda, xi = -0.6;
    double eta = (lambda * delta + lambda * delta * xi) / (lambda - 2 * delta - lambda * xi);
    if (!(eta > 0) || !isfinite(eta)) return;
    double vt = tmin - eta; /* the vanishing point on the centre line */
    /* side lines from the vanishing point through the widest footprint points */
    double slope = 0;
    for (int i = 0; i < 8; i++) {
        double t = (q[i][0] - nc[0]) * ax[0] + (q[i][1] - nc[1]) * ax[1];
        double u = (q[i][0] - nc[0]) * px[0] + (q[i][1] - nc[1]) * px[1];
        slope = fmax(slope, fabs(u) / fmax(t - vt, 1e-12));
    }
    /* trapezoid corners (t, u): top (near) then base (far), back to the map's x,y */
    double tc[4][2] = {{tmin, -slope * (tmin - vt)}, {tmin, slope * (tmin - vt)}, {tmax, slope * (tmax - vt)},
                       {tmax, -slope * (tmax - vt)}};
    double src[4][2], dst[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int i = 0; i < 4; i++) {
        src[i][0] = nc[0] + ax[0] * tc[i][0] + px[0] * tc[i][1];
        src[i][1] = nc[1] + ax[1] * tc[i][0] + px[1] * tc[i][1];
    }
    double H[9];
    if (!homography(src, dst, H)) return;
    /* embed: (x, y, w) by H, z passes through (depth stays monotonic along each light ray) */
    sb_m4 T = {{0}};
    T.m[0] = H[0]; T.m[4] = H[1]; T.m[12] = H[2];
    T.m[1] = H[3]; T.m[5] = H[4]; T.m[13] = H[5];
    T.m[3] = H[6]; T.m[7] = H[7]; T.m[15] = H[8];
    T.m[10] = 1;
    sb_m4 warp = sb_m4_mul(T, out->view_proj);
    /* the depth of the extended light box after the warp: refit z to [-1, 1] */
    double zlo = 1e300, zhi = -1e300;
    for (int i = 0; i < 8; i++) {
        for (int e = 0; e < 2; e++) {
            /* the uniform light box's corners over this footprint point: near and far depth */
            sb_v3 c = sb_m4_point(out->view_proj, pts[i]);
            sb_m4 inv;
            if (!sb_m4_invert(out->view_proj, &inv)) return;
            sb_v3 w = sb_m4_point(inv, sb_v3_make(c.x, c.y, e ? 1 : -1));
            sb_v3 z = sb_m4_point(warp, w);
            zlo = fmin(zlo, z.z);
            zhi = fmax(zhi, z.z);
        }
    }
    if (!(zhi > zlo)) return;
    sb_m4 fitz = sb_m4_identity();
    fitz.m[10] = 2 / (zhi - zlo);
    fitz.m[14] = -(zhi + zlo) / (zhi - zlo);
    sb_m4 vp = sb_m4_mul(fitz, warp);
    if (!sb_m4_finite(vp)) return;
    out->view_proj = vp;
    sb_frustum_planes(vp, out->planes);
    sb_m4 bias = sb_m4_identity();
    bias.m[0] = bias.m[5] = bias.m[10] = 0.5;
    bias.m[12] = bias.m[13] = bias.m[14] = 0.5;
    out->shadow_mat = sb_m4_mul(bias, vp);
    out->warped = true;
}
