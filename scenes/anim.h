/* anim.h - glTF animation samplers: the value of one channel at a time t
 * (STEP, LINEAR with spherical interpolation of rotations, CUBICSPLINE with
 * its tangents), and a node's local transform from TRS. Used for --pose T and
 * for glTF camera paths. */
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "sbmath.h"

typedef enum sb_interp { SB_INTERP_LINEAR, SB_INTERP_STEP, SB_INTERP_CUBIC } sb_interp;

typedef struct sb_anim_sampler {
    const double *in;       /* key times, increasing */
    const double *out;      /* ncomp values a key (CUBICSPLINE: in-tangent, value, out-tangent) */
    size_t keys;
    int ncomp;              /* 3: translation/scale, 4: rotation, N: morph weights */
    bool rotation;          /* a quaternion (x, y, z, w): slerp, normalised */
    sb_interp interp;
} sb_anim_sampler;

/* The channel's value at t (clamped to the first and last key); rotations come out normalised. */
void sb_anim_sample(const sb_anim_sampler *s, double t, double *out);

/* A node's local TRS (glTF order: translation, rotation x y z w, scale). */
typedef struct sb_trs {
    double t[3], r[4], s[3];
} sb_trs;
sb_m4 sb_trs_matrix(const sb_trs *x);
