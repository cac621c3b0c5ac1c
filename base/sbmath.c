#include "sbmath.h"

#include <string.h>

sb_m4 sb_m4_identity(void) {
    sb_m4 r = {{0}};
    r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0;
    return r;
}

sb_m4 sb_m4_mul(sb_m4 a, sb_m4 b) {
    sb_m4 r;
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += a.m[k * 4 + row] * b.m[c * 4 + k];
            r.m[c * 4 + row] = s;
        }
    return r;
}

bool sb_m4_invert(sb_m4 a, sb_m4 *out) {
    const double *m = a.m;
    double inv[16];
    inv[0] = m[5] * m[10] * m[15] - m[5] * m[11] * m[14] - m[9] * m[6] * m[15] + m[9] * m[7] * m[14] +
             m[13] * m[6] * m[11] - m[13] * m[7] * m[10];
    inv[4] = -m[4] * m[10] * m[15] + m[4] * m[11] * m[14] + m[8] * m[6] * m[15] - m[8] * m[7] * m[14] -
             m[12] * m[6] * m[11] + m[12] * m[7] * m[10];
    inv[8] = m[4] * m[9] * m[15] - m[4] * m[11] * m[13] - m[8] * m[5] * m[15] + m[8] * m[7] * m[13] +
             m[12] * m[5] * m[11] - m[12] * m[7] * m[9];
    inv[12] = -m[4] * m[9] * m[14] + m[4] * m[10] * m[13] + m[8] * m[5] * m[14] - m[8] * m[6] * m[13] -
              m[12] * m[5] * m[10] + m[12] * m[6] * m[9];
    inv[1] = -m[1] * m[10] * m[15] + m[1] * m[11] * m[14] + m[9] * m[2] * m[15] - m[9] * m[3] * m[14] -
             m[13] * m[2] * m[11] + m[13] * m[3] * m[10];
    inv[5] = m[0] * m[10] * m[15] - m[0] * m[11] * m[14] - m[8] * m[2] * m[15] + m[8] * m[3] * m[14] +
             m[12] * m[2] * m[11] - m[12] * m[3] * m[10];
    inv[9] = -m[0] * m[9] * m[15] + m[0] * m[11] * m[13] + m[8] * m[1] * m[15] - m[8] * m[3] * m[13] -
             m[12] * m[1] * m[11] + m[12] * m[3] * m[9];
    inv[13] = m[0] * m[9] * m[14] - m[0] * m[10] * m[13] - m[8] * m[1] * m[14] + m[8] * m[2] * m[13] +
              m[12] * m[1] * m[10] - m[12] * m[2] * m[9];
    inv[2] = m[1] * m[6] * m[15] - m[1] * m[7] * m[14] - m[5] * m[2] * m[15] + m[5] * m[3] * m[14] +
             m[13] * m[2] * m[7] - m[13] * m[3] * m[6];
    inv[6] = -m[0] * m[6] * m[15] + m[0] * m[7] * m[14] + m[4] * m[2] * m[15] - m[4] * m[3] * m[14] -
             m[12] * m[2] * m[7] + m[12] * m[3] * m[6];
    inv[10] = m[0] * m[5] * m[15] - m[0] * m[7] * m[13] - m[4] * m[1] * m[15] + m[4] * m[3] * m[13] +
              m[12] * m[1] * m[7] - m[12] * m[3] * m[5];
    inv[14] = -m[0] * m[5] * m[14] + m[0] * m[6] * m[13] + m[4] * m[1] * m[14] - m[4] * m[2] * m[13] -
              m[12] * m[1] * m[6] + m[12] * m[2] * m[5];
    inv[3] = -m[1] * m[6] * m[11] + m[1] * m[7] * m[10] + m[5] * m[2] * m[11] - m[5] * m[3] * m[10] -
             m[9] * m[2] * m[7] + m[9] * m[3] * m[6];
    inv[7] = m[0] * m[6] * m[11] - m[0] * m[7] * m[10] - m[4] * m[2] * m[11] + m[4] * m[3] * m[10] +
             m[8] * m[2] * m[7] - m[8] * m[3] * m[6];
    inv[11] = -m[0] * m[5] * m[11] + m[0] * m[7] * m[9] + m[4] * m[1] * m[11] - m[4] * m[3] * m[9] -
              m[8] * m[1] * m[7] + m[8] * m[3] * m[5];
    inv[15] = m[0] * m[5] * m[10] - m[0] * m[6] * m[9] - m[4] * m[1] * m[10] + m[4] * m[2] * m[9] +
              m[8] * m[1] * m[6] - m[8] * m[2] * m[5];
    double det = m[0] * inv[0] + m[1] * inv[4] + m[2] * inv[8] + m[3] * inv[12];
    if (det == 0 || !isfinite(det)) return false;
    det = 1.0 / det;
    for (int i = 0; i < 16; i++) out->m[i] = inv[i] * det;
    return true;
}

sb_v3 sb_m4_point(sb_m4 a, sb_v3 p) {
    const double *m = a.m;
    double x = m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12];
    double y = m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13];
    double z = m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14];
    double w = m[3] * p.x + m[7] * p.y + m[11] * p.z + m[15];
    if (w != 1.0 && w != 0.0) {
        x /= w;
        y /= w;
        z /= w;
    }
    return (sb_v3){x, y, z};
}

sb_v3 sb_m4_dir(sb_m4 a, sb_v3 d) {
    const double *m = a.m;
    return (sb_v3){m[0] * d.x + m[4] * d.y + m[8] * d.z, m[1] * d.x + m[5] * d.y + m[9] * d.z,
                   m[2] * d.x + m[6] * d.y + m[10] * d.z};
}

sb_m4 sb_m4_translate(sb_v3 t) {
    sb_m4 r = sb_m4_identity();
    r.m[12] = t.x;
    r.m[13] = t.y;
    r.m[14] = t.z;
    return r;
}

sb_m4 sb_m4_scale(sb_v3 s) {
    sb_m4 r = sb_m4_identity();
    r.m[0] = s.x;
    r.m[5] = s.y;
    r.m[10] = s.z;
    return r;
}

sb_m4 sb_m4_view(sb_v3 eye, sb_v3 right, sb_v3 up, sb_v3 forward) {
    sb_m4 r = sb_m4_identity();
    sb_v3 back = sb_v3_scale(forward, -1);
    r.m[0] = right.x; r.m[4] = right.y; r.m[8] = right.z;
    r.m[1] = up.x;    r.m[5] = up.y;    r.m[9] = up.z;
    r.m[2] = back.x;  r.m[6] = back.y;  r.m[10] = back.z;
    r.m[12] = -sb_v3_dot(right, eye);
    r.m[13] = -sb_v3_dot(up, eye);
    r.m[14] = -sb_v3_dot(back, eye);
    return r;
}

sb_m4 sb_m4_look_at(sb_v3 eye, sb_v3 target, sb_v3 up_hint) {
    sb_v3 f = sb_v3_norm(sb_v3_sub(target, eye));
    sb_v3 r = sb_v3_cross(f, up_hint);
    if (sb_v3_len(r) < 1e-12) {
        sb_v3 bu;
        sb_basis(f, &r, &bu);
    }
    r = sb_v3_norm(r);
    sb_v3 u = sb_v3_cross(r, f);
    return sb_m4_view(eye, r, u, f);
}

sb_m4 sb_m4_perspective(double fovy, double aspect, double n, double f) {
    sb_m4 r = {{0}};
    double t = 1.0 / tan(fovy * 0.5);
    r.m[0] = t / aspect;
    r.m[5] = t;
    r.m[10] = (f + n) / (n - f);
    r.m[11] = -1;
    r.m[14] = 2 * f * n / (n - f);
    return r;
}

sb_m4 sb_m4_ortho(double l, double r, double b, double t, double n, double f) {
    sb_m4 o = sb_m4_identity();
    o.m[0] = 2 / (r - l);
    o.m[5] = 2 / (t - b);
    o.m[10] = -2 / (f - n);
    o.m[12] = -(r + l) / (r - l);
    o.m[13] = -(t + b) / (t - b);
    o.m[14] = -(f + n) / (f - n);
    return o;
}

void sb_m4_to_float(sb_m4 a, float out[16]) {
    for (int i = 0; i < 16; i++) out[i] = (float)a.m[i];
}

bool sb_m4_finite(sb_m4 a) {
    for (int i = 0; i < 16; i++)
        if (!isfinite(a.m[i])) return false;
    return true;
}

sb_quat sb_quat_identity(void) { return (sb_quat){0, 0, 0, 1}; }

sb_quat sb_quat_norm(sb_quat q) {
    double l = sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (l == 0) return sb_quat_identity();
    return (sb_quat){q.x / l, q.y / l, q.z / l, q.w / l};
}

sb_quat sb_quat_mul(sb_quat a, sb_quat b) {
    return (sb_quat){a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                     a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                     a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
                     a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

sb_quat sb_quat_slerp(sb_quat a, sb_quat b, double t) {
    double d = a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
    if (d < 0) {
        b = (sb_quat){-b.x, -b.y, -b.z, -b.w};
        d = -d;
    }
    double wa, wb;
    if (d > 0.9995) {
        wa = 1 - t;
        wb = t;
    } else {
        double th = acos(d), s = sin(th);
        wa = sin((1 - t) * th) / s;
        wb = sin(t * th) / s;
    }
    return sb_quat_norm((sb_quat){wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z,
                                  wa * a.w + wb * b.w});
}

sb_v3 sb_quat_rotate(sb_quat q, sb_v3 v) {
    sb_v3 u = {q.x, q.y, q.z};
    sb_v3 t = sb_v3_scale(sb_v3_cross(u, v), 2.0);
    return sb_v3_add(sb_v3_add(v, sb_v3_scale(t, q.w)), sb_v3_cross(u, t));
}

sb_m4 sb_quat_to_m4(sb_quat q) {
    sb_m4 r = sb_m4_identity();
    sb_v3 x = sb_quat_rotate(q, sb_v3_make(1, 0, 0));
    sb_v3 y = sb_quat_rotate(q, sb_v3_make(0, 1, 0));
    sb_v3 z = sb_quat_rotate(q, sb_v3_make(0, 0, 1));
    r.m[0] = x.x; r.m[1] = x.y; r.m[2] = x.z;
    r.m[4] = y.x; r.m[5] = y.y; r.m[6] = y.z;
    r.m[8] = z.x; r.m[9] = z.y; r.m[10] = z.z;
    return r;
}

sb_quat sb_quat_from_m4(sb_m4 a) {
    const double *m = a.m;
    double m00 = m[0], m11 = m[5], m22 = m[10];
    double tr = m00 + m11 + m22;
    sb_quat q;
    if (tr > 0) {
        double s = sqrt(tr + 1.0) * 2;
        q.w = 0.25 * s;
        q.x = (m[6] - m[9]) / s;
        q.y = (m[8] - m[2]) / s;
        q.z = (m[1] - m[4]) / s;
    } else if (m00 > m11 && m00 > m22) {
        double s = sqrt(1.0 + m00 - m11 - m22) * 2;
        q.w = (m[6] - m[9]) / s;
        q.x = 0.25 * s;
        q.y = (m[4] + m[1]) / s;
        q.z = (m[8] + m[2]) / s;
    } else if (m11 > m22) {
        double s = sqrt(1.0 + m11 - m00 - m22) * 2;
        q.w = (m[8] - m[2]) / s;
        q.x = (m[4] + m[1]) / s;
        q.y = 0.25 * s;
        q.z = (m[9] + m[6]) / s;
    } else {
        double s = sqrt(1.0 + m22 - m00 - m11) * 2;
        q.w = (m[1] - m[4]) / s;
        q.x = (m[8] + m[2]) / s;
        q.y = (m[9] + m[6]) / s;
        q.z = 0.25 * s;
    }
    return sb_quat_norm(q);
}

sb_quat sb_quat_look(sb_v3 dir, sb_v3 up_hint) {
    sb_v3 f = sb_v3_norm(dir);
    sb_v3 r = sb_v3_cross(f, up_hint);
    if (sb_v3_len(r) < 1e-12) {
        sb_v3 bu;
        sb_basis(f, &r, &bu);
    }
    r = sb_v3_norm(r);
    sb_v3 u = sb_v3_cross(r, f);
    sb_m4 m = sb_m4_identity();
    m.m[0] = r.x; m.m[1] = r.y; m.m[2] = r.z;
    m.m[4] = u.x; m.m[5] = u.y; m.m[6] = u.z;
    m.m[8] = -f.x; m.m[9] = -f.y; m.m[10] = -f.z;
    return sb_quat_from_m4(m);
}

sb_v3 sb_sun_dir(double az, double el) {
    double a = az * SB_PI / 180, e = el * SB_PI / 180;
    return sb_v3_norm(sb_v3_make(cos(e) * sin(a), sin(e), cos(e) * cos(a)));
}

void sb_basis(sb_v3 d, sb_v3 *right, sb_v3 *up) {
    d = sb_v3_norm(d);
    sb_v3 helper = fabs(d.y) < 0.99 ? sb_v3_make(0, 1, 0) : sb_v3_make(1, 0, 0);
    *right = sb_v3_norm(sb_v3_cross(helper, d));
    *up = sb_v3_cross(d, *right);
}

void sb_frustum_planes(sb_m4 m, double p[6][4]) {
    const double *a = m.m;
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 4; k++) {
            p[2 * i][k] = a[k * 4 + 3] + a[k * 4 + i];
            p[2 * i + 1][k] = a[k * 4 + 3] - a[k * 4 + i];
        }
    }
    for (int i = 0; i < 6; i++) {
        double l = sqrt(p[i][0] * p[i][0] + p[i][1] * p[i][1] + p[i][2] * p[i][2]);
        if (l > 0)
            for (int k = 0; k < 4; k++) p[i][k] /= l;
    }
}

void sb_cube_planes(sb_v3 c, double r, double p[6][4]) {
    const double box[6][4] = {{1, 0, 0, -(c.x - r)}, {-1, 0, 0, c.x + r}, {0, 1, 0, -(c.y - r)},
                              {0, -1, 0, c.y + r},   {0, 0, 1, -(c.z - r)}, {0, 0, -1, c.z + r}};
    for (int i = 0; i < 6; i++)
        for (int k = 0; k < 4; k++) p[i][k] = box[i][k];
}

sb_aabb sb_aabb_transform(sb_m4 m, const sb_aabb *b) {
    sb_v3 q = sb_m4_point(m, sb_aabb_corner(b, 0));
    sb_aabb out = {q, q};
    for (int k = 1; k < 8; k++) {
        q = sb_m4_point(m, sb_aabb_corner(b, k));
        out.lo = sb_v3_min(out.lo, q), out.hi = sb_v3_max(out.hi, q);
    }
    return out;
}

sb_aabb sb_aabb_transform_affine(sb_m4 m, const sb_aabb *b) {
    const double *a = m.m;
    if (a[3] != 0 || a[7] != 0 || a[11] != 0 || a[15] != 1) return sb_aabb_transform(m, b);
    double c[3] = {0.5 * (b->lo.x + b->hi.x), 0.5 * (b->lo.y + b->hi.y), 0.5 * (b->lo.z + b->hi.z)};
    double h[3] = {0.5 * (b->hi.x - b->lo.x), 0.5 * (b->hi.y - b->lo.y), 0.5 * (b->hi.z - b->lo.z)};
    double oc[3], oh[3];
    for (int r = 0; r < 3; r++) {
        oc[r] = a[12 + r] + a[r] * c[0] + a[4 + r] * c[1] + a[8 + r] * c[2];
        oh[r] = fabs(a[r]) * h[0] + fabs(a[4 + r]) * h[1] + fabs(a[8 + r]) * h[2];
    }
    return (sb_aabb){{oc[0] - oh[0], oc[1] - oh[1], oc[2] - oh[2]}, {oc[0] + oh[0], oc[1] + oh[1], oc[2] + oh[2]}};
}

double sb_aabb_dist2(const sb_aabb *b, sb_v3 p) {
    double e[3] = {p.x < b->lo.x ? b->lo.x - p.x : p.x > b->hi.x ? p.x - b->hi.x : 0,
                   p.y < b->lo.y ? b->lo.y - p.y : p.y > b->hi.y ? p.y - b->hi.y : 0,
                   p.z < b->lo.z ? b->lo.z - p.z : p.z > b->hi.z ? p.z - b->hi.z : 0};
    return e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
}
