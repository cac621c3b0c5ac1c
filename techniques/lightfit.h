/* lightfit.h - fitting an orthographic light frustum to receivers, in double.
 * Shared by every directional-light shadow-map technique (sm now; the
 * cascaded techniques fit one per slice with the same code). */
#pragma once
#include "render.h"

typedef struct sb_light_fit {
    sb_m4 view, proj, view_proj;     /* origin-relative world -> light clip */
    sb_m4 shadow_mat;                /* -> [0,1]^3 texture space */
    double planes[6][4];             /* the light volume (casters culled against it) */
    double l, r, b, t, zn, zf;       /* light-space box: x/y window, near/far distance */
    double texel_world;              /* world size of one shadow texel */
    bool empty;                      /* no receiver inside the scene */
    bool warped;                     /* a LiSPSM perspective warp is in the matrices */
    double n_opt;                    /* LiSPSM: distance of the warp's centre to the body */
} sb_light_fit;

/* Light view looking along -sun from the origin, with a stable basis. */
sb_m4 sb_light_view(sb_v3 sun);
/* Corners of the camera frustum slice [znear, zfar] in origin-relative world. */
void sb_frustum_corners(const sb_camera *cam, sb_v3 origin, double znear, double zfar, sb_v3 out[8]);
/* Fits the light box to the receiver points (clipped to the scene bounds),
 * extends it toward the light to the farthest caster overlapping its x/y
 * window (BVH query), and sets the far plane at the receivers. */
void sb_light_fit_points(const sb_scene *s, sb_v3 sun, const sb_v3 *pts, int n, int res, sb_light_fit *out);
/* LiSPSM (Wimmer et al. 2004): a perspective warp in light space along the
 * view direction's projection, with n_opt = (zn + sqrt(zn zf)) / sin(gamma)
 * (gamma: angle between view and light directions); below `min_gamma_deg`
 * it falls back to the uniform fit. pts: the slice's 8 corners; eye and
 * forward: the camera (origin-relative). n_opt's z_n is the nearest visible
 * receiver in the slice; receivers: the body is the receivers' boxes inside
 * the slice (fit=receivers), not the slice clipped to the scene's box. */
void sb_light_fit_lispsm(const sb_scene *s, sb_v3 sun, sb_v3 eye, sb_v3 forward, double zn, double zf,
                         const sb_v3 *pts, int n, int res, double min_gamma_deg, bool receivers, sb_light_fit *out);
/* TSM (Martin & Tan 2004): the uniform fit, then the view frustum's footprint
 * in the map enclosed by a trapezoid along the view's centre line (the
 * focus point at `focus` of the depth maps to 80% of the map) and the
 * trapezoid mapped to the square by a projective transform; the warp is no
 * stronger than LiSPSM's n_opt for the slice's view depths [zn, zf] asks for
 * (a cascade's short slice is warped gently). pts: the slice's 8 corners,
 * near corners first. */
void sb_light_fit_tsm(const sb_scene *s, sb_v3 sun, const sb_v3 *pts, int res, double focus, double zn, double zf,
                      sb_light_fit *out);
/* The fit of the receivers inside a view slice: the draws' boxes clipped to the slice (corners: near four, then
 * far four), not the whole slice; the slice where it holds none. */
void sb_light_fit_receivers(const sb_scene *s, sb_v3 sun, const sb_v3 corners[8], int res, sb_light_fit *out);
/* Stable variant: a bounding sphere of the points (rotation-invariant size)
 * whose light-space window is snapped to whole texels (no shimmer). */
void sb_light_fit_stable(const sb_scene *s, sb_v3 sun, const sb_v3 *pts, int n, int res, sb_light_fit *out);

/* PSM (Stamminger & Drettakis 2002) with the Novosibirsk paper's fixes: the
 * map is built in the post-projective space (PPS) of a camera whose near and
 * far planes are pushed to the visible receivers, where the sun is a point
 * light l = P (sun, 0). `behind` decides what happens to casters behind the
 * camera when the sun is behind it (l "inverted", w < 0):
 *   SB_PSM_INVERSE  depth z_ndc = a / z' (near -a, far a): one function of 1/z'
 *                   orders both sides of the plane at infinity, so casters
 *                   behind the camera land in front of every receiver;
 *   SB_PSM_SHIFT    the original fix: the PPS camera is moved back until every
 *                   caster is in front of it (costs resolution);
 *   SB_PSM_NAIVE    an ordinary near plane at the receivers' side: casters
 *                   behind the camera are clipped (for comparison only).
 * The light frustum is fitted to the receivers (visible draw boxes clipped to
 * the view frustum). Single map: one fit, the uniform fit instead (info
 * fallback) when the receivers need a frustum wider than max_half_fov_deg
 * (light nearly along the view). cube: six 90-degree faces around l, fits
 * flagged empty where no receiver is. Returns the number of fits (1 or 6);
 * every fit is empty when no receiver is in view. Fits leave the near plane
 * out of the culling planes: casters toward the light are clamped to depth 0
 * (GL_DEPTH_CLAMP), except naive with an inverted light, which clips them. */
enum { SB_PSM_INVERSE, SB_PSM_SHIFT, SB_PSM_NAIVE };
typedef struct sb_psm_desc {
    int behind;                 /* SB_PSM_* */
    bool cube;
    int res;
    double max_half_fov_deg;    /* single map: 0 means 80 */
} sb_psm_desc;
typedef struct sb_psm_info {
    bool inverted;              /* the sun is behind the camera: l has w < 0 */
    bool ortho;                 /* the sun is perpendicular to the view: a directional light in PPS */
    bool fallback;              /* single map too wide: the uniform fit was used */
    double shift;               /* SB_PSM_SHIFT: how far the PPS camera moved back */
    double znear, zfar;         /* the PPS camera's pushed planes */
    sb_v3 light;                /* l in PPS (finite unless ortho) */
} sb_psm_info;
int sb_light_fit_psm(const sb_scene *s, sb_v3 sun, const sb_camera *cam, const sb_psm_desc *d, sb_light_fit out[6],
                     sb_psm_info *info);
