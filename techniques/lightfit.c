/* lightfit.c - orthographic light frustum fitting. */
#include "lightfit.h"
#include "motion.h"

#include <stdlib.h>
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

/* Light clip space [-1,1]^3 -> shadow-map texture space [0,1]^3. */
static sb_m4 shadow_from_clip(sb_m4 view_proj) {
    sb_m4 bias = sb_m4_identity();
    bias.m[0] = bias.m[5] = bias.m[10] = 0.5;
    bias.m[12] = bias.m[13] = bias.m[14] = 0.5;
    return sb_m4_mul(bias, view_proj);
}

static void box_in_light(sb_m4 view, const sb_aabb *b, sb_v3 *lo, sb_v3 *hi) {
    *lo = sb_v3_make(1e300, 1e300, 1e300);
    *hi = sb_v3_make(-1e300, -1e300, -1e300);
    for (int k = 0; k < 8; k++) {
        sb_v3 q = sb_aabb_corner(b, k);
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
    sb_scene_cull(s, (const double(*)[4])side, 5, scan_caster, &sc);
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
    out->shadow_mat = shadow_from_clip(out->view_proj);
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

/* ---- convex clipping: what receivers a frustum can see ------------------ */

static void m4_v4(sb_m4 m, const double in[4], double out[4]) {
    for (int r = 0; r < 4; r++) out[r] = m.m[r] * in[0] + m.m[4 + r] * in[1] + m.m[8 + r] * in[2] + m.m[12 + r] * in[3];
}

static double v3_at(sb_v3 v, int i) { return i == 0 ? v.x : i == 1 ? v.y : v.z; }
static void v3_set(sb_v3 *v, int i, double x) {
    if (i == 0) v->x = x;
    else if (i == 1) v->y = x;
    else v->z = x;
}
static double plane_eval(const double p[4], sb_v3 v) { return p[0] * v.x + p[1] * v.y + p[2] * v.z + p[3]; }

typedef struct {
    sb_v3 *p;
    int n, cap;
} point_list;

static void points_push(point_list *l, sb_v3 p) {
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 256;
        sb_v3 *np = sb_xrealloc(l->p, sizeof *np * (size_t)cap);
        if (!np) return;   /* out of memory: the fit uses the points it has */
        l->p = np;
        l->cap = cap;
    }
    l->p[l->n++] = p;
}

/* Sutherland-Hodgman: the part of the convex polygon in[n] inside the plane. */
static int clip_polygon(const sb_v3 *in, int n, const double pl[4], sb_v3 *out) {
    int m = 0;
    for (int i = 0; i < n; i++) {
        sb_v3 a = in[i], b = in[(i + 1) % n];
        double da = plane_eval(pl, a), db = plane_eval(pl, b);
        if (da >= 0) out[m++] = a;
        if ((da >= 0) != (db >= 0)) out[m++] = sb_v3_lerp(a, b, da / (da - db));
    }
    return m;
}

/* The vertices of (box ∩ convex frustum): every box face clipped by the six
 * planes (Sutherland-Hodgman), and the frustum's corners inside the box. */
static void box_clip_vertices(const sb_aabb *b, const double (*planes)[4], const sb_v3 corners[8], point_list *out) {
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            sb_v3 poly[2][16];
            for (int k = 0; k < 4; k++) {
                sb_v3 q = b->lo;
                v3_set(&q, axis, v3_at(side ? b->hi : b->lo, axis));
                v3_set(&q, u, v3_at(k == 1 || k == 2 ? b->hi : b->lo, u));
                v3_set(&q, v, v3_at(k >= 2 ? b->hi : b->lo, v));
                poly[0][k] = q;
            }
            int n = 4, cur = 0;
            for (int p = 0; p < 6 && n > 0; p++) {
                n = clip_polygon(poly[cur], n, planes[p], poly[1 - cur]);
                cur = 1 - cur;
            }
            for (int k = 0; k < n; k++) points_push(out, poly[cur][k]);
        }
    double eps = 1e-9 * (1 + sb_v3_len(sb_v3_sub(b->hi, b->lo)));
    for (int k = 0; k < 8; k++) {
        sb_v3 c = corners[k];
        if (c.x >= b->lo.x - eps && c.y >= b->lo.y - eps && c.z >= b->lo.z - eps && c.x <= b->hi.x + eps &&
            c.y <= b->hi.y + eps && c.z <= b->hi.z + eps)
            points_push(out, c);
    }
}

/* Inward planes of the frustum slice with corners[8] (near four, then far four,
 * bit 0: right, bit 1: up, as sb_frustum_corners orders them). */
static void slice_planes(const sb_v3 c[8], double planes[6][4]) {
    static const int quads[6][3] = {{0, 2, 4}, {1, 5, 3}, {0, 4, 1}, {2, 3, 6}, {0, 1, 2}, {4, 6, 5}};
    sb_v3 centre = {0, 0, 0};
    for (int k = 0; k < 8; k++) centre = sb_v3_add(centre, sb_v3_scale(c[k], 0.125));
    for (int i = 0; i < 6; i++) {
        sb_v3 a = c[quads[i][0]], b = c[quads[i][1]], d = c[quads[i][2]];
        sb_v3 n = sb_v3_norm(sb_v3_cross(sb_v3_sub(b, a), sb_v3_sub(d, a)));
        if (sb_v3_dot(n, sb_v3_sub(centre, a)) < 0) n = sb_v3_scale(n, -1);
        planes[i][0] = n.x;
        planes[i][1] = n.y;
        planes[i][2] = n.z;
        planes[i][3] = -sb_v3_dot(n, a);
    }
}

static double slice_receivers(const sb_scene *s, const double (*planes)[4], const sb_v3 corners[8], sb_v3 eye,
                              sb_v3 fwd, bool nearest, point_list *out);

void sb_light_fit_lispsm(const sb_scene *s, sb_v3 sun, sb_v3 eye, sb_v3 forward, double zn, double zf,
                         const sb_v3 *pts, int n, int res, double min_gamma_deg, bool receivers, sb_light_fit *out) {
    sun = sb_v3_norm(sun);
    double cos_g = sb_v3_dot(sb_v3_norm(forward), sun), sin_g = sqrt(fmax(0, 1 - cos_g * cos_g));
    /* no useful warp with the view along the light (or no slice of 8 corners): the uniform fit alone */
    const bool warps = n == 8 && sin_g >= sin(min_gamma_deg * SB_PI / 180) && zn > 0;
    /* one scan of the slice's receivers serves the uniform fit (receivers), the warp's body and its n_opt */
    double planes[6][4], zr = 1e300;
    point_list recv = {0};
    if (n == 8 && (receivers || warps)) {
        slice_planes(pts, planes);
        zr = slice_receivers(s, (const double(*)[4])planes, pts, eye, forward, warps, &recv);
    }
    /* the uniform fit first: its caster extension and receiver window bound the body */
    if (receivers && recv.n) sb_light_fit_points(s, sun, recv.p, recv.n, res, out);
    else sb_light_fit_points(s, sun, pts, n, res, out);
    if (!warps || out->empty) {
        free(recv.p);
        return;
    }
    /* light view whose up axis is the view direction projected perpendicular to the light */
    sb_v3 fwd = sb_v3_scale(sun, -1);
    sb_v3 up = sb_v3_norm(sb_v3_sub(forward, sb_v3_scale(fwd, sb_v3_dot(forward, fwd))));
    sb_v3 right = sb_v3_norm(sb_v3_cross(fwd, up));
    up = sb_v3_cross(right, fwd);
    sb_m4 lv = sb_m4_view(sb_v3_make(0, 0, 0), right, up, fwd);
    /* body: the receivers inside the slice (fit=receivers: what is there), else the slice clipped to the scene's
       box (where the scene can be), and the same points pushed toward the light to the top of the scene (so every
       caster over the receivers is inside the warped frustum). The warp is fitted to these points: the box's
       corners would widen the near end of the map to the whole body and waste the resolution the warp gives it. */
    point_list body = {0};
    if (receivers && recv.n) body = recv;
    else {
        free(recv.p);
        box_clip_vertices(&s->bounds, (const double(*)[4])planes, pts, &body);
    }
    sb_v3 blo = {1e300, 1e300, 1e300}, bhi = {-1e300, -1e300, -1e300};
    for (int i = 0; i < body.n; i++) {
        body.p[i] = sb_m4_point(lv, body.p[i]);
        blo = sb_v3_min(blo, body.p[i]);
        bhi = sb_v3_max(bhi, body.p[i]);
    }
    sb_v3 slo = {1e300, 1e300, 1e300}, shi = {-1e300, -1e300, -1e300};
    for (int k = 0; k < 8; k++) {
        sb_v3 q = sb_m4_point(lv, sb_aabb_corner(&s->bounds, k));
        slo = sb_v3_min(slo, q);
        shi = sb_v3_max(shi, q);
    }
    if (body.n == 0 || !(blo.x < bhi.x && blo.y < bhi.y)) { /* keep the uniform fit */
        free(body.p);
        return;
    }
    double zmax = shi.z + 1e-4 * (shi.z - slo.z), zmin = blo.z;
    double d = bhi.y - blo.y;
    /* n_opt from the nearest receiver the slice shows, not the camera's near plane: a slice whose nearest visible
       surface is metres away (a camera above the ground, the view's first cascade) is warped as that surface
       needs, not for a near plane nothing is at (Wimmer et al.'s z_n is the body's near) */
    if (zr < zf && zr > zn) zn = zr;
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
    sb_m4 pt = sb_m4_mul(p, t);
    sb_v3 wlo = {1e300, 1e300, 1e300}, whi = {-1e300, -1e300, -1e300};
    for (int i = 0; i < body.n; i++)
        for (int e = 0; e < 2; e++) {
            sb_v3 q = body.p[i];
            if (e) q.z = zmax;
            sb_v3 w = sb_m4_point(pt, q);
            wlo = sb_v3_min(wlo, w);
            whi = sb_v3_max(whi, w);
        }
    free(body.p);
    sb_m4 warp = sb_m4_mul(pt, lv);
    if (!(whi.x > wlo.x && whi.y > wlo.y && whi.z > wlo.z)) return;
    /* ortho fit of the warped body: z toward the light is +z, so near = -zmax */
    sb_m4 o = sb_m4_ortho(wlo.x, whi.x, wlo.y, whi.y, -whi.z, -wlo.z);
    sb_m4 vp = sb_m4_mul(o, warp);
    if (!sb_m4_finite(vp)) return;
    out->view = lv;
    out->proj = sb_m4_mul(o, sb_m4_mul(p, t));
    out->view_proj = vp;
    sb_frustum_planes(vp, out->planes);
    out->shadow_mat = shadow_from_clip(vp);
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

/* The footprint of what can be seen, in the uniform map's [-1,1]^2: the slice
 * clipped to the scene's box (the frustum's corners reach far beyond a scene
 * whose far plane is loose, and the trapezoid would spend the map there), or
 * the slice's corners q when the clip is empty. *nb gets the point count. */
static double (*tsm_footprint(const sb_scene *s, const sb_light_fit *out, const sb_v3 *pts, double q[8][2],
                              int *nb))[2] {
    double planes[6][4];
    slice_planes(pts, planes);
    point_list body = {0};
    box_clip_vertices(&s->bounds, (const double(*)[4])planes, pts, &body);
    *nb = body.n ? body.n : 8;
    double (*fp)[2] = sb_xmalloc(sizeof *fp * (size_t)*nb);
    for (int i = 0; i < *nb; i++) {
        if (body.n) {
            sb_v3 c = sb_m4_point(out->view_proj, body.p[i]);
            fp[i][0] = c.x;
            fp[i][1] = c.y;
        } else {
            fp[i][0] = q[i][0];
            fp[i][1] = q[i][1];
        }
    }
    free(body.p);
    return fp;
}

/* Embeds the homography H of the map's x, y (depth passes through: it stays
 * monotonic along each light ray), refits depth to [-1, 1] over the extended
 * light box, and makes it the fit's matrices. The warped depth is z / w' with
 * w' affine in x, y: over the trapezoid (corners tz, which hold everything the
 * map shows) its extremes are at the corners, the box's near and far depth
 * (the slice's own corners alone miss the trapezoid's wide end, and casters
 * there fell outside the depth range: desert's frame 5 of 8 lost 3.5% of its
 * shadow pixels). */
static void tsm_warp(sb_light_fit *out, const double H[9], const double tz[4][2]) {
    sb_m4 T = {{0}};
    T.m[0] = H[0]; T.m[4] = H[1]; T.m[12] = H[2];
    T.m[1] = H[3]; T.m[5] = H[4]; T.m[13] = H[5];
    T.m[3] = H[6]; T.m[7] = H[7]; T.m[15] = H[8];
    T.m[10] = 1;
    sb_m4 warp = sb_m4_mul(T, out->view_proj);
    double zlo = 1e300, zhi = -1e300;
    for (int i = 0; i < 4; i++) {
        double w = H[6] * tz[i][0] + H[7] * tz[i][1] + H[8];
        if (!(w > 0)) return;
        for (int e = -1; e <= 1; e += 2) {
            zlo = fmin(zlo, e / w);
            zhi = fmax(zhi, e / w);
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
    out->shadow_mat = shadow_from_clip(vp);
    out->warped = true;
}

void sb_light_fit_tsm(const sb_scene *s, sb_v3 sun, const sb_v3 *pts, int res, double focus, double zn, double zf,
                      sb_light_fit *out) {
    sb_light_fit_points(s, sun, pts, 8, res, out);
    if (out->empty) return;
    /* the frustum's corners in the uniform map's [-1,1]^2, and the centre line from the near to the far end */
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
    int nb;
    double (*fp)[2] = tsm_footprint(s, out, pts, q, &nb);
    /* footprint in the centre-line frame: t along the line from the near centre, u across */
    double tmin = 1e300, tmax = -1e300;
    for (int i = 0; i < nb; i++) {
        double t = (fp[i][0] - nc[0]) * ax[0] + (fp[i][1] - nc[1]) * ax[1];
        tmin = fmin(tmin, t);
        tmax = fmax(tmax, t);
    }
    double lambda = tmax - tmin;
    /* the 80% rule: the focus point (focus of the way from top to base) lands on the 80% line */
    double delta = focus * lambda, xi = -0.6;
    double eta = (lambda * delta + lambda * delta * xi) / (lambda - 2 * delta - lambda * xi);
    /* never a stronger warp than the slice's perspective asks for: the vanishing point no nearer the top than
       LiSPSM's n_opt = (zn + sqrt(zn zf)) / sin(gamma) is to the body, in the body's share of the line (a cascade
       whose far end is twice its near gains little from a warp, and the 80% rule made for the whole view would
       spend its far end's texels on its near end) */
    sb_v3 axis = {0, 0, 0};
    for (int i = 0; i < 4; i++) axis = sb_v3_add(axis, sb_v3_scale(sb_v3_sub(pts[4 + i], pts[i]), 0.25));
    double along = sb_v3_len(axis), cos_g = along > 0 ? sb_v3_dot(axis, sb_v3_norm(sun)) / along : 1;
    double sin_g = sqrt(fmax(0, 1 - cos_g * cos_g)), body = (zf - zn) * sin_g;
    if (zn > 0 && zf > zn && sin_g > 1e-6 && body > 0) eta = fmax(eta, lambda * (zn + sqrt(zn * zf)) / sin_g / body);
    if (!(eta > 0) || !isfinite(eta) || !(lambda > 0)) {
        free(fp);
        return;
    }
    double vt = tmin - eta; /* the vanishing point on the centre line */
    /* side lines from the vanishing point through the widest footprint points */
    double slope = 0;
    for (int i = 0; i < nb; i++) {
        double t = (fp[i][0] - nc[0]) * ax[0] + (fp[i][1] - nc[1]) * ax[1];
        double u = (fp[i][0] - nc[0]) * px[0] + (fp[i][1] - nc[1]) * px[1];
        slope = fmax(slope, fabs(u) / fmax(t - vt, 1e-12));
    }
    free(fp);
    /* trapezoid corners (t, u): top (near) then base (far), back to the map's x,y */
    double tc[4][2] = {{tmin, -slope * (tmin - vt)}, {tmin, slope * (tmin - vt)}, {tmax, slope * (tmax - vt)},
                       {tmax, -slope * (tmax - vt)}};
    double src[4][2], dst[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int i = 0; i < 4; i++) {
        src[i][0] = nc[0] + ax[0] * tc[i][0] + px[0] * tc[i][1];
        src[i][1] = nc[1] + ax[1] * tc[i][0] + px[1] * tc[i][1];
    }
    double H[9];
    if (homography(src, dst, H)) tsm_warp(out, H, (const double(*)[2])src);
}

/* ---- PSM ---------------------------------------------------------------- */

typedef struct {
    uint32_t draw;
    double depth;           /* nearest view depth of its box inside the frustum */
} draw_depth;

typedef struct {
    const sb_scene *s;
    const double (*planes)[4];
    const sb_v3 *corners;
    point_list *out;
    sb_v3 eye, fwd;
    draw_depth *near;       /* optional: per draw, the box's nearest depth */
    uint32_t near_count;
} receiver_scan;

/* The vertices of (draw box ∩ view frustum). */
static void scan_receiver(uint32_t d, void *user) {
    receiver_scan *r = user;
    int first = r->out->n;
    box_clip_vertices(&r->s->draws[d].box, r->planes, r->corners, r->out);
    if (r->near && r->out->n > first) {
        double dmin = 1e300;
        for (int i = first; i < r->out->n; i++) dmin = fmin(dmin, sb_v3_dot(sb_v3_sub(r->out->p[i], r->eye), r->fwd));
        r->near[r->near_count++] = (draw_depth){d, dmin};
    }
}

static int by_depth(const void *a, const void *b) {
    double x = ((const draw_depth *)a)->depth, y = ((const draw_depth *)b)->depth;
    return x < y ? -1 : x > y;
}

/* The nearest view depth of a front-facing triangle inside the frustum (what
 * the camera pass can show; it culls back faces), refining draws in the order
 * of their boxes' nearest depth until no box can be nearer. Boxes alone put
 * the near plane at the camera whenever it is inside a draw's box. */
static double nearest_receiver(const sb_scene *s, const double (*planes)[4], sb_v3 eye, sb_v3 fwd, draw_depth *near,
                               uint32_t n) {
    qsort(near, n, sizeof *near, by_depth);
    double best = 1e300;
    for (uint32_t k = 0; k < n && near[k].depth < best; k++) {
        const sb_draw *dr = &s->draws[near[k].draw];
        if (dr->motion != SB_DRAW_STILL) sb_scene_sync_vertices(s);   /* its triangles as posed: the CPU's copy */
        for (uint32_t i = 0; i + 2 < dr->index_count; i += 3) {
            sb_v3 poly[2][16];
            for (int v = 0; v < 3; v++) {
                float p[3];
                sb_draw_point(s, dr, s->indices[dr->first_index + i + v], p);
                poly[0][v] = sb_v3_make(p[0], p[1], p[2]);
            }
            sb_v3 nrm = sb_v3_cross(sb_v3_sub(poly[0][1], poly[0][0]), sb_v3_sub(poly[0][2], poly[0][0]));
            if (sb_v3_dot(nrm, sb_v3_sub(eye, poly[0][0])) <= 0) continue; /* back face (or edge-on) */
            int m = 3, cur = 0;
            for (int pl = 0; pl < 6 && m > 0; pl++) {
                m = clip_polygon(poly[cur], m, planes[pl], poly[1 - cur]);
                cur = 1 - cur;
            }
            for (int v = 0; v < m; v++) best = fmin(best, sb_v3_dot(sb_v3_sub(poly[cur][v], eye), fwd));
        }
    }
    return best;
}

/* The receivers a slice shows (planes, corners): the vertices of each draw's box clipped to it into out, and, when
 * nearest, the nearest view depth of a front face inside it (1e300 when it shows none, or not asked). */
static double slice_receivers(const sb_scene *s, const double (*planes)[4], const sb_v3 corners[8], sb_v3 eye,
                              sb_v3 fwd, bool nearest, point_list *out) {
    draw_depth *near = nearest ? sb_xmalloc(sizeof *near * (s->draw_count + 1)) : NULL;
    receiver_scan rs = {s, planes, corners, out, eye, fwd, near, 0};
    sb_scene_cull(s, planes, 6, scan_receiver, &rs);
    double z = near ? nearest_receiver(s, planes, eye, fwd, near, rs.near_count) : 1e300;
    free(near);
    return z;
}

void sb_light_fit_receivers(const sb_scene *s, sb_v3 sun, const sb_v3 corners[8], int res, sb_light_fit *out) {
    double planes[6][4];
    slice_planes(corners, planes);
    point_list pts = {0};
    slice_receivers(s, (const double(*)[4])planes, corners, sb_v3_make(0, 0, 0), sb_v3_make(0, 0, 0), false, &pts);
    if (pts.n) sb_light_fit_points(s, sun, pts.p, pts.n, res, out);
    else sb_light_fit_points(s, sun, corners, 8, res, out);   /* no receiver: the slice (the caller skips it) */
    free(pts.p);
}

/* Light view in PPS as a linear map of homogeneous PPS points: x' = r·(x - l w),
 * y' = u·(x - l w), z' = a·(x - l w), w' = w (z' > 0 in front of the light). */
static sb_m4 pps_light_view(sb_v3 l, sb_v3 r, sb_v3 u, sb_v3 a) {
    sb_m4 m = sb_m4_identity();
    sb_v3 rows[3] = {r, u, a};
    for (int i = 0; i < 3; i++) {
        m.m[0 + i] = rows[i].x;
        m.m[4 + i] = rows[i].y;
        m.m[8 + i] = rows[i].z;
        m.m[12 + i] = -sb_v3_dot(rows[i], l);
    }
    return m;
}

/* Perspective from the light over the window [u0,u1]x[v0,v1] (x'/z', y'/z'),
 * w_clip = z'. Depth, by case (a, n, f distances along the axis):
 *   inverted:       z_ndc = a / z'              (near -a, far a; Novosibirsk)
 *   inverted naive: z_ndc = 2n / z' - 1         (near n, far at infinity, reversed)
 *   ordinary:       z_ndc = (f+n)/(f-n) - 2fn / ((f-n) z') */
enum { DEPTH_INVERSE, DEPTH_NAIVE, DEPTH_ORDINARY };
static sb_m4 pps_light_proj(double u0, double u1, double v0, double v1, int kind, double n, double f) {
    sb_m4 p = {{0}};
    p.m[0] = 2 / (u1 - u0);
    p.m[8] = -(u1 + u0) / (u1 - u0);
    p.m[5] = 2 / (v1 - v0);
    p.m[9] = -(v1 + v0) / (v1 - v0);
    p.m[11] = 1;
    if (kind == DEPTH_INVERSE) {
        p.m[14] = n;
    } else if (kind == DEPTH_NAIVE) {
        p.m[10] = -1;
        p.m[14] = 2 * n;
    } else {
        p.m[10] = (f + n) / (f - n);
        p.m[14] = -2 * f * n / (f - n);
    }
    return p;
}

static void psm_finish(sb_light_fit *out, sb_m4 light_view, sb_m4 light_proj, bool keep_near, double texel) {
    out->view = light_view;
    out->proj = light_proj;
    out->view_proj = sb_m4_mul(light_proj, light_view);
    sb_frustum_planes(out->view_proj, out->planes);
    if (!keep_near) { /* casters toward the light are clamped, not culled */
        out->planes[4][0] = out->planes[4][1] = out->planes[4][2] = 0;
        out->planes[4][3] = 1;
    }
    out->shadow_mat = shadow_from_clip(out->view_proj);
    out->texel_world = texel;
    out->zn = 0;
    out->zf = 1;
    out->warped = true;
    out->empty = !sb_m4_finite(out->shadow_mat);
}

/* The PSM's receivers: the visible draw boxes clipped to the view frustum, cut
 * at the nearest visible receiver when it lies beyond the near plane. Returns
 * false when the camera sees nothing. */
static bool psm_receivers(const sb_scene *s, const sb_camera *cam, point_list *pts) {
    sb_v3 eye = sb_v3_sub(cam->pos, s->origin), fwd = cam->forward;
    double fovy = cam->fov_deg * SB_PI / 180;
    sb_m4 cam_vp = sb_m4_mul(sb_m4_perspective(fovy, cam->aspect, cam->znear, cam->zfar),
                             sb_m4_view(eye, cam->right, cam->up, fwd));
    double planes[6][4];
    sb_frustum_planes(cam_vp, planes);
    sb_v3 corners[8];
    sb_frustum_corners(cam, s->origin, cam->znear, cam->zfar, corners);
    draw_depth *near = sb_xmalloc(sizeof *near * (s->draw_count + 1));
    receiver_scan rs = {s, (const double(*)[4])planes, corners, pts, eye, fwd, near, 0};
    sb_scene_cull(s, (const double(*)[4])planes, 6, scan_receiver, &rs);
    double znear = near ? nearest_receiver(s, (const double(*)[4])planes, eye, fwd, near, rs.near_count) : cam->znear;
    free(near);
    if (pts->n == 0 || znear >= 1e300) return false; /* nothing the camera can see */
    if (znear > cam->znear) { /* the receivers' boxes again, cut at the nearest visible receiver */
        double zcut = fmax(cam->znear, znear * (1 - 1e-3));
        planes[4][0] = fwd.x;
        planes[4][1] = fwd.y;
        planes[4][2] = fwd.z;
        planes[4][3] = -sb_v3_dot(fwd, eye) - zcut;
        sb_frustum_corners(cam, s->origin, zcut, cam->zfar, corners);
        pts->n = 0;
        rs.near = NULL;
        sb_scene_cull(s, (const double(*)[4])planes, 6, scan_receiver, &rs);
    }
    return pts->n > 0;
}

/* The PPS camera: near and far pushed to the receivers (and moved back for
 * behind=shift until every caster is in front). Returns its projection x view;
 * *n1, *f1 the pushed planes before any shift, *texel the world texel size. */
static sb_m4 psm_camera(const sb_scene *s, const sb_camera *cam, const sb_psm_desc *d, const point_list *pts,
                        sb_psm_info *info, double *n1, double *f1, double *texel) {
    sb_v3 eye = sb_v3_sub(cam->pos, s->origin), fwd = cam->forward;
    double zmin = 1e300, zmax = -1e300;
    sb_v3 wlo = {1e300, 1e300, 1e300}, whi = {-1e300, -1e300, -1e300};
    for (int i = 0; i < pts->n; i++) {
        double z = sb_v3_dot(sb_v3_sub(pts->p[i], eye), fwd);
        zmin = fmin(zmin, z);
        zmax = fmax(zmax, z);
        wlo = sb_v3_min(wlo, pts->p[i]);
        whi = sb_v3_max(whi, pts->p[i]);
    }
    *texel = fmax(whi.x - wlo.x, fmax(whi.y - wlo.y, whi.z - wlo.z)) / d->res;
    *n1 = fmax(cam->znear, zmin * (1 - 1e-3));
    *f1 = fmax(zmax * (1 + 1e-3), *n1 * 1.001);
    double shift = 0;
    if (d->behind == SB_PSM_SHIFT) { /* every caster in front of the moved camera */
        double cmin = 1e300;
        for (int k = 0; k < 8; k++) {
            sb_v3 q = sb_aabb_corner(&s->bounds, k);
            cmin = fmin(cmin, sb_v3_dot(sb_v3_sub(q, eye), fwd));
        }
        shift = fmax(0, 1e-3 * *f1 - cmin);
    }
    info->shift = shift;
    info->znear = *n1 + shift;
    info->zfar = *f1 + shift;
    return sb_m4_mul(sb_m4_perspective(cam->fov_deg * SB_PI / 180, cam->aspect, *n1 + shift, *f1 + shift),
                     sb_m4_view(sb_v3_sub(eye, sb_v3_scale(fwd, shift)), cam->right, cam->up, fwd));
}

/* The sun perpendicular to the view: still a directional light in PPS (dir),
 * an orthographic map there (w_clip = the camera's w). */
static void psm_ortho(const point_list *pts, sb_v3 dir, sb_m4 C, int res, double texel, sb_light_fit *out) {
    sb_m4 lv = sb_light_view(dir);
    sb_v3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    for (int i = 0; i < pts->n; i++) {
        sb_v3 q = sb_m4_point(lv, pts->p[i]);
        lo = sb_v3_min(lo, q);
        hi = sb_v3_max(hi, q);
    }
    double ztop = hi.z; /* toward the light: the unit cube's extent, casters beyond clamp to 0 */
    for (int k = 0; k < 8; k++)
        ztop = fmax(ztop, sb_m4_point(lv, sb_v3_make(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1)).z);
    double gx = 2 * (hi.x - lo.x) / res + 1e-12, gy = 2 * (hi.y - lo.y) / res + 1e-12;
    double pad = 1e-4 * (ztop - lo.z) + 1e-12;
    sb_m4 o = sb_m4_ortho(lo.x - gx, hi.x + gx, lo.y - gy, hi.y + gy, -ztop - pad, -lo.z + pad);
    psm_finish(out, sb_m4_mul(lv, C), o, false, texel);
}

/* One frustum from the PPS light l around the receivers' centre; false when
 * none narrower than max_half_fov_deg holds them (the caller falls back). */
static bool psm_single(const point_list *pts, sb_v3 l, sb_v3 centre, sb_m4 C, const sb_psm_desc *d, int depth,
                       bool naive, double texel, sb_light_fit *out) {
    sb_v3 axis = sb_v3_norm(sb_v3_sub(centre, l)), r, u;
    sb_basis(axis, &r, &u);
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300, z0 = 1e300, z1 = -1e300;
    for (int i = 0; i < pts->n; i++) {
        sb_v3 q = sb_v3_sub(pts->p[i], l);
        double z = sb_v3_dot(q, axis);
        if (z <= 1e-9 * sb_v3_len(q)) return false;
        u0 = fmin(u0, sb_v3_dot(q, r) / z);
        u1 = fmax(u1, sb_v3_dot(q, r) / z);
        v0 = fmin(v0, sb_v3_dot(q, u) / z);
        v1 = fmax(v1, sb_v3_dot(q, u) / z);
        z0 = fmin(z0, z);
        z1 = fmax(z1, z);
    }
    double lim = tan((d->max_half_fov_deg > 0 ? d->max_half_fov_deg : 80) * SB_PI / 180);
    if (fmax(fmax(-u0, u1), fmax(-v0, v1)) > lim) return false;
    double gu = 2 * (u1 - u0) / d->res, gv = 2 * (v1 - v0) / d->res;
    double nn = depth == DEPTH_ORDINARY ? 0.5 * z0 : z0 * (1 - 1e-4);
    sb_m4 lp = pps_light_proj(u0 - gu, u1 + gu, v0 - gv, v1 + gv, depth, nn, z1 * (1 + 1e-4));
    psm_finish(out, sb_m4_mul(pps_light_view(l, r, u, axis), C), lp, naive, texel);
    return true;
}

/* Cube face k around l, unless a plane of its pyramid has every receiver
 * outside; when every receiver is in front of the face's plane, its window
 * and depth are fitted to them. */
static void psm_face(const point_list *pts, int k, sb_v3 l, double dist, double far, sb_m4 C, int res, int depth,
                     bool naive, double texel, sb_light_fit *out) {
    double g1 = 1 + 4.0 / res;   /* a 90-degree face plus a guard band */
    sb_v3 axis = {0, 0, 0}, r, u;
    v3_set(&axis, k / 2, k & 1 ? -1 : 1);
    sb_basis(axis, &r, &u);
    bool sep[5] = {true, true, true, true, true}, front = true;
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300, z0 = 1e300, z1 = -1e300;
    for (int i = 0; i < pts->n; i++) {
        sb_v3 q = sb_v3_sub(pts->p[i], l);
        double z = sb_v3_dot(q, axis), x = sb_v3_dot(q, r), y = sb_v3_dot(q, u);
        if (z > 0) sep[0] = false;
        if (x <= g1 * z) sep[1] = false;
        if (x >= -g1 * z) sep[2] = false;
        if (y <= g1 * z) sep[3] = false;
        if (y >= -g1 * z) sep[4] = false;
        if (z <= 1e-9 * sb_v3_len(q)) {
            front = false;
            continue;
        }
        u0 = fmin(u0, x / z);
        u1 = fmax(u1, x / z);
        v0 = fmin(v0, y / z);
        v1 = fmax(v1, y / z);
        z0 = fmin(z0, z);
        z1 = fmax(z1, z);
    }
    if (sep[0] || sep[1] || sep[2] || sep[3] || sep[4]) return;
    double zlo = dist / sqrt(1 + 2 * g1 * g1), zhi = far; /* z' bounds of any receiver inside the face */
    double w[4] = {-g1, g1, -g1, g1};
    if (front) {
        double gu = 2 * (u1 - u0) / res, gv = 2 * (v1 - v0) / res;
        w[0] = fmax(w[0], u0 - gu);
        w[1] = fmin(w[1], u1 + gu);
        w[2] = fmax(w[2], v0 - gv);
        w[3] = fmin(w[3], v1 + gv);
        zlo = z0;
        zhi = z1;
    }
    if (!(zlo > 0) || !(w[1] > w[0]) || !(w[3] > w[2])) return;
    double nn = depth == DEPTH_ORDINARY ? 0.5 * zlo : zlo * (1 - 1e-4);
    sb_m4 lp = pps_light_proj(w[0], w[1], w[2], w[3], depth, nn, zhi * (1 + 1e-4));
    psm_finish(out, sb_m4_mul(pps_light_view(l, r, u, axis), C), lp, naive, texel);
}

int sb_light_fit_psm(const sb_scene *s, sb_v3 sun, const sb_camera *cam, const sb_psm_desc *d, sb_light_fit out[6],
                     sb_psm_info *info) {
    int nfit = d->cube ? 6 : 1;
    memset(out, 0, sizeof *out * (size_t)nfit);
    memset(info, 0, sizeof *info);
    for (int k = 0; k < nfit; k++) out[k].empty = true;
    sun = sb_v3_norm(sun);
    point_list pts = {0};
    if (!psm_receivers(s, cam, &pts)) {
        free(pts.p);
        return nfit;
    }
    double n1, f1, texel;
    sb_m4 C = psm_camera(s, cam, d, &pts, info, &n1, &f1, &texel);
    const double sun4[4] = {sun.x, sun.y, sun.z, 0};
    double L[4];
    m4_v4(C, sun4, L);
    info->inverted = L[3] < 0;
    for (int i = 0; i < pts.n; i++) pts.p[i] = sb_m4_point(C, pts.p[i]); /* all in front: w > 0 */
    sb_v3 plo = {1e300, 1e300, 1e300}, phi = {-1e300, -1e300, -1e300}, centre = {0, 0, 0};
    for (int i = 0; i < pts.n; i++) {
        plo = sb_v3_min(plo, pts.p[i]);
        phi = sb_v3_max(phi, pts.p[i]);
        centre = sb_v3_add(centre, sb_v3_scale(pts.p[i], 1.0 / pts.n));
    }
    double lxyz = sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
    bool naive = d->behind == SB_PSM_NAIVE && info->inverted;
    int depth = info->inverted ? (naive ? DEPTH_NAIVE : DEPTH_INVERSE) : DEPTH_ORDINARY;
    if (fabs(L[3]) * 1e7 <= lxyz) {
        info->ortho = true;
        psm_ortho(&pts, sb_v3_make(L[0] / lxyz, L[1] / lxyz, L[2] / lxyz), C, d->res, texel, &out[0]);
    } else {
        sb_v3 l = sb_v3_make(L[0] / L[3], L[1] / L[3], L[2] / L[3]);
        info->light = l;
        if (!d->cube) {
            if (!psm_single(&pts, l, centre, C, d, depth, naive, texel, &out[0])) {
                /* no single frustum from l holds the receivers: the uniform map */
                info->fallback = true;
                sb_v3 sc[8];
                sb_frustum_corners(cam, s->origin, n1, f1, sc);
                sb_light_fit_points(s, sun, sc, 8, d->res, &out[0]);
            }
        } else {
            sb_v3 near_pt = sb_v3_max(plo, sb_v3_min(l, phi)); /* closest point of the receivers' box to l */
            double dist = sb_v3_len(sb_v3_sub(near_pt, l)), far = 0;
            for (int i = 0; i < pts.n; i++) far = fmax(far, sb_v3_len(sb_v3_sub(pts.p[i], l)));
            for (int k = 0; k < 6; k++) psm_face(&pts, k, l, dist, far, C, d->res, depth, naive, texel, &out[k]);
        }
    }
    free(pts.p);
    return nfit;
}
