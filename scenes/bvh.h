/* bvh.h - a bounding volume hierarchy over boxes (a scene's draws), exact
 * AABB-versus-planes culling over it, and the traversal rays use. It takes
 * the boxes as an array (with a stride, so they may sit inside larger
 * records) and knows nothing of what they bound. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sbmath.h"

typedef struct sb_bvh_node {
    sb_aabb box;
    int32_t left, right;    /* children, -1 for a leaf */
    uint32_t first, count;  /* leaf: range in sb_bvh.items */
} sb_bvh_node;

typedef struct sb_bvh {
    sb_bvh_node *nodes;
    uint32_t node_count;
    uint32_t *items;        /* box indices */
} sb_bvh;

/* Boxes: box i at (const char *)first + i * stride. */
typedef struct sb_boxes {
    const sb_aabb *first;
    size_t stride;
    uint32_t count;
} sb_boxes;

static inline const sb_aabb *sb_boxes_at(sb_boxes b, uint32_t i) {
    return (const sb_aabb *)((const char *)b.first + (size_t)i * b.stride);
}

/* Builds b over the boxes (freeing what b held); median splits on the widest
 * axis of the centres, a stable order for equal centres. */
void sb_bvh_build(sb_bvh *b, sb_boxes boxes);
void sb_bvh_free(sb_bvh *b);
/* The same tree over boxes that moved: every node's box made again from its items (a child comes after its
 * parent), the split kept; boxes must be the ones it was built over, in number. */
void sb_bvh_refit(sb_bvh *b, sb_boxes boxes);
bool sb_aabb_outside_plane(const sb_aabb *b, const double plane[4]);
/* Visits every box not fully outside any of the planes (n·p + d >= 0 is inside); returns how many. */
typedef void (*sb_bvh_visit)(uint32_t item, void *user);
uint32_t sb_bvh_cull(const sb_bvh *b, sb_boxes boxes, const double (*planes)[4], int plane_count, sb_bvh_visit visit,
                     void *user);
/* Whether the ray o + t inv^-1, t in [0, tmax], meets the box (inv: 1 / direction). */
bool sb_ray_box(const sb_aabb *b, sb_v3 o, sb_v3 inv, double tmax);
