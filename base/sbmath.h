/* sbmath.h - double-precision vector, matrix and quaternion math.
 * Everything that decides where shadows land is computed here in double; only
 * the final matrices sent to the GPU are converted to float (sb_m4_to_float).
 * Matrices are column-major (m[col*4+row]) as in GL. */
#pragma once
#include <math.h>
#include <stdbool.h>

typedef struct { double x, y, z; } sb_v3;
typedef struct { double x, y, z, w; } sb_quat;
/* An axis-aligned box. */
typedef struct sb_aabb {
    sb_v3 lo, hi;
} sb_aabb;
typedef struct { double m[16]; } sb_m4;

#define SB_PI 3.14159265358979323846

static inline sb_v3 sb_v3_make(double x, double y, double z) { return (sb_v3){x, y, z}; }
static inline sb_v3 sb_v3_add(sb_v3 a, sb_v3 b) { return (sb_v3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline sb_v3 sb_v3_sub(sb_v3 a, sb_v3 b) { return (sb_v3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline sb_v3 sb_v3_scale(sb_v3 a, double s) { return (sb_v3){a.x * s, a.y * s, a.z * s}; }
static inline double sb_v3_dot(sb_v3 a, sb_v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline sb_v3 sb_v3_cross(sb_v3 a, sb_v3 b) {
    return (sb_v3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline double sb_v3_len(sb_v3 a) { return sqrt(sb_v3_dot(a, a)); }
static inline sb_v3 sb_v3_norm(sb_v3 a) {
    double l = sb_v3_len(a);
    return l > 0 ? sb_v3_scale(a, 1.0 / l) : a;
}
static inline sb_v3 sb_v3_lerp(sb_v3 a, sb_v3 b, double t) {
    return sb_v3_add(a, sb_v3_scale(sb_v3_sub(b, a), t));
}
static inline sb_v3 sb_v3_min(sb_v3 a, sb_v3 b) {
    return (sb_v3){fmin(a.x, b.x), fmin(a.y, b.y), fmin(a.z, b.z)};
}
static inline sb_v3 sb_v3_max(sb_v3 a, sb_v3 b) {
    return (sb_v3){fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)};
}
static inline sb_v3 sb_v3_abs(sb_v3 a) { return (sb_v3){fabs(a.x), fabs(a.y), fabs(a.z)}; }
static inline bool sb_v3_finite(sb_v3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

sb_m4 sb_m4_identity(void);
sb_m4 sb_m4_mul(sb_m4 a, sb_m4 b);                 /* a * b */
bool sb_m4_invert(sb_m4 a, sb_m4 *out);
sb_v3 sb_m4_point(sb_m4 a, sb_v3 p);               /* w-divided transform */
sb_v3 sb_m4_dir(sb_m4 a, sb_v3 d);                 /* upper 3x3 only */
sb_m4 sb_m4_translate(sb_v3 t);
sb_m4 sb_m4_scale(sb_v3 s);
/* View matrix from eye and orientation basis: right, up, and forward (camera looks along forward). */
sb_m4 sb_m4_view(sb_v3 eye, sb_v3 right, sb_v3 up, sb_v3 forward);
sb_m4 sb_m4_look_at(sb_v3 eye, sb_v3 target, sb_v3 up_hint);
sb_m4 sb_m4_perspective(double fovy_rad, double aspect, double znear, double zfar);
sb_m4 sb_m4_ortho(double l, double r, double b, double t, double n, double f);
void sb_m4_to_float(sb_m4 a, float out[16]);
bool sb_m4_finite(sb_m4 a);

sb_quat sb_quat_identity(void);
sb_quat sb_quat_norm(sb_quat q);
sb_quat sb_quat_mul(sb_quat a, sb_quat b);
sb_quat sb_quat_slerp(sb_quat a, sb_quat b, double t);   /* shortest arc */
sb_v3 sb_quat_rotate(sb_quat q, sb_v3 v);
sb_m4 sb_quat_to_m4(sb_quat q);
sb_quat sb_quat_from_m4(sb_m4 m);                       /* rotation part, assumed orthonormal */
/* Orientation whose -Z axis looks along dir (glTF camera convention), +Y near up_hint. */
sb_quat sb_quat_look(sb_v3 dir, sb_v3 up_hint);

/* ---- boxes ---- */

/* Corner k (0..7) of a box: bit 0 picks x's high end, bit 1 y's, bit 2 z's. */
static inline sb_v3 sb_aabb_corner(const sb_aabb *b, int k) {
    return sb_v3_make(k & 1 ? b->hi.x : b->lo.x, k & 2 ? b->hi.y : b->lo.y, k & 4 ? b->hi.z : b->lo.z);
}
/* The smallest box holding both. */
static inline sb_aabb sb_aabb_union(sb_aabb a, sb_aabb b) {
    return (sb_aabb){sb_v3_min(a.lo, b.lo), sb_v3_max(a.hi, b.hi)};
}
/* The box of the eight corners through m (sb_m4_point: projected where m projects). */
sb_aabb sb_aabb_transform(sb_m4 m, const sb_aabb *b);
/* The same box through an affine m (last row 0 0 0 1; else sb_aabb_transform), from the box's centre and half-size
 * (Arvo 1990): equal but for rounding, a fraction of the cost; for boxes remade every frame (the moving draws'). */
sb_aabb sb_aabb_transform_affine(sb_m4 m, const sb_aabb *b);
/* The squared distance from p to the box (0 inside it). */
double sb_aabb_dist2(const sb_aabb *b, sb_v3 p);

/* Planes (inside: n·p + d >= 0) of the clip-space box of the matrix m (Gribb-Hartmann), normalised. */
void sb_frustum_planes(sb_m4 m, double planes[6][4]);
/* Planes of the axis-aligned cube of half-size r around c. */
void sb_cube_planes(sb_v3 c, double r, double planes[6][4]);

/* Unit vector toward a sun at azimuth/elevation in degrees (Y up, azimuth 0 = +Z, 90 = +X). */
sb_v3 sb_sun_dir(double azimuth_deg, double elevation_deg);
/* A stable orthonormal basis around dir: picks the helper axis least parallel to dir. */
void sb_basis(sb_v3 dir, sb_v3 *right, sb_v3 *up);
