/* reference.h - exact shadows by ray casting (Embree 3): the ground truth
 * every technique's error is measured against, and the `raycast` technique. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "scene.h"

typedef struct sb_reference {
    void *device, *scene;       /* RTCDevice, RTCScene */
    const sb_scene *src;        /* the scene (positions, materials) the filter reads */
    uint8_t *tri;               /* per triangle: SB_REF_* flags (NULL when no triangle needs the filter) */
    /* A scene with shared geometry (sb_draw.proto): one Embree geometry a draw, an instance of its proto's
       scene (built once) for each draw that repeats one; geom_first[id] is the first scene triangle of the draw
       behind top-level geometry id (NULL without sharing: one geometry, primID the scene's triangle). */
    uint32_t *geom_first;
    void **protos;              /* RTCScene per draw that others repeat (NULL where none) */
    struct sb_ref_geo *geo;     /* what the filter reads of each geometry */
    double build_ms;
    float eps_scene;            /* a length relative to the scene size, for ray offsets */
    /* A scene whose clips play (sb_scene_moves): every draw a geometry of its own, the moving ones refit when
       the scene is posed (sb_reference_update); the answers a pose gives are kept under its key. */
    uint32_t *moving_geoms;     /* top-level geometry ids of the moving draws */
    uint32_t moving_count;
    uint64_t pose_serial;       /* the scene's pose_serial the geometry holds */
    uint64_t pose_key;          /* what view keys of kept answers mix in: 0 for a still scene */
    double refit_ms;            /* time spent refitting, summed */
    uint32_t refits;
    /* the light's size (sb_reference_set_light_size; 0: a light of no size, one ray a point) */
    double sun_size_deg, sun_tan;   /* the sun's angular diameter; tan of half of it */
    float lamp_radius;          /* a point or spot light's radius */
    int samples;                /* rays over the light at a penumbra point */
} sb_reference;

/* Gives the light a size: the sun an angular diameter (degrees), point and
 * spot lights a radius. With a size, a point's visibility is the share of
 * the light it sees: the centre and 8 points of the rim first; when they all
 * agree the point is in full light or umbra (those 9 rays), otherwise
 * `samples` rays toward points of a golden-angle spiral over the light's
 * disc (equal area each) decide it. Sizes of 0 keep one ray a point. */
void sb_reference_set_light_size(sb_reference *r, double sun_size_deg, double lamp_radius, int samples);

/* Triangles the rays see as the rasterizer draws them: an open single-sided
 * surface is hit only from the side its front faces (the light's side for a
 * shadow ray, the eye's for a camera ray), an alpha-tested one only where its
 * material covers the hit point (sb_material_covers). */
enum { SB_REF_SINGLE_SIDED = 1, SB_REF_ALPHA = 2 };

/* Builds an Embree scene of the scene's triangles, with an intersection
 * filter for those that need one (the scene must outlive it). */
bool sb_reference_build(sb_reference *r, const sb_scene *s, sb_err *err);
void sb_reference_free(sb_reference *r);
/* After sb_scene_pose: the moving draws' triangles refit (RTC_BUILD_QUALITY_REFIT) to the scene's vertices as
 * they are now, and the top level committed again. Nothing when the reference already holds that pose. */
void sb_reference_update(sb_reference *r);

/* A point to test: origin-relative position, geometric normal facing the
 * viewer (may be zero), and how far the point may be off the true surface
 * (the ray starts that far out along the normal, and toward the light). */
typedef struct sb_ref_point {
    float p[3], n[3];
    float eps;
} sb_ref_point;

/* The error bound of a float position relative to the origin, rasterized at
 * distance `dist` from the camera: a few ulps of the larger of the two. */
float sb_ref_position_eps(const sb_reference *r, const float p[3], float dist);

/* Visibility of the directional light `sun` (unit vector toward it) at each
 * point: 255 lit, 0 shadowed; with a light size (sb_reference_set_light_size)
 * the lit share of the light in between (never 128, which the reference
 * images keep for "not evaluated": written 129). Runs on `threads` threads;
 * returns the number of rays cast. */
uint64_t sb_reference_visibility(const sb_reference *r, sb_v3 sun, const sb_ref_point *pts, int n,
                                 unsigned char *vis, int threads);
/* The same toward any light: light[3] 0: xyz toward the sun; 1: xyz a point
 * light's position (origin-relative; rays stop short of it). */
uint64_t sb_reference_visibility_light(const sb_reference *r, const double light[4], const sb_ref_point *pts, int n,
                                       unsigned char *vis, int threads);

/* The same for a view's points (pix[k]: the pixel of pts[k] in a w x h
 * frame, as sb_ref_points gives them), with a sized light cheaper: every
 * point's centre ray first; then only points where the centre rays' answer
 * changes between screen neighbours, and the neighbours of each point found
 * inside a penumbra in turn, are answered over the light (its rim, then its
 * samples), until the penumbra band is closed. A penumbra with no centre-ray
 * edge in it (an occluder whose hard shadow falls between pixels) is missed.
 * Without a size: sb_reference_visibility_light. */
uint64_t sb_reference_visibility_view(const sb_reference *r, const double light[4], const sb_ref_point *pts,
                                      const int *pix, int n, int w, int h, unsigned char *vis, int threads);

/* The first surface each camera ray from from[i] toward to[i] (origin-relative)
 * meets, seen as the camera pass draws it. */
typedef struct sb_ref_hit {
    float t;                    /* distance from from[i] (INFINITY: nothing hit) */
    float n[3];                 /* geometric normal of the hit triangle, facing the ray's origin */
    bool front;                 /* the triangle's front (counter-clockwise) face is the one facing the origin */
    uint32_t prim;              /* the triangle in the scene's index array (an instance's: its proto's) */
    uint32_t draw;              /* the draw it is of where the reference traces draws apart (shared or moving
                                   geometry), else UINT32_MAX (the draw whose run holds prim) */
} sb_ref_hit;
void sb_reference_rays(const sb_reference *r, const float (*from)[3], const float (*to)[3], int n, sb_ref_hit *out,
                       int threads);
/* The same with both faces of every triangle hit (a single-sided one's back
 * too, which the camera pass culls): what a camera inside a closed mesh would
 * meet. */
void sb_reference_rays_all_faces(const sb_reference *r, const float (*from)[3], const float (*to)[3], int n,
                                 sb_ref_hit *out, int threads);
