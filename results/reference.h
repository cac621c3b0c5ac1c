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
    double build_ms;
    float eps_scene;            /* a length relative to the scene size, for ray offsets */
} sb_reference;

/* Triangles the rays see as the rasterizer draws them: an open single-sided
 * surface is hit only from the side its front faces (the light's side for a
 * shadow ray, the eye's for a camera ray), an alpha-tested one only where its
 * material covers the hit point (sb_material_covers). */
enum { SB_REF_SINGLE_SIDED = 1, SB_REF_ALPHA = 2 };

/* Builds an Embree scene of the scene's triangles, with an intersection
 * filter for those that need one (the scene must outlive it). */
bool sb_reference_build(sb_reference *r, const sb_scene *s, sb_err *err);
void sb_reference_free(sb_reference *r);

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
 * point: 1 lit, 0 shadowed. Runs on `threads` threads; returns the number of
 * rays cast. */
uint64_t sb_reference_visibility(const sb_reference *r, sb_v3 sun, const sb_ref_point *pts, int n,
                                 unsigned char *vis, int threads);
/* The same toward any light: light[3] 0: xyz toward the sun; 1: xyz a point
 * light's position (origin-relative; rays stop short of it). */
uint64_t sb_reference_visibility_light(const sb_reference *r, const double light[4], const sb_ref_point *pts, int n,
                                       unsigned char *vis, int threads);

/* The first surface each camera ray from from[i] toward to[i] (origin-relative)
 * meets, seen as the camera pass draws it. */
typedef struct sb_ref_hit {
    float t;                    /* distance from from[i] (INFINITY: nothing hit) */
    float n[3];                 /* geometric normal of the hit triangle, facing the ray's origin */
    bool front;                 /* the triangle's front (counter-clockwise) face is the one facing the origin */
} sb_ref_hit;
void sb_reference_rays(const sb_reference *r, const float (*from)[3], const float (*to)[3], int n, sb_ref_hit *out,
                       int threads);
