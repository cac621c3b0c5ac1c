/* lightgrid.h - lamps found by cluster (Olsson, Billeter and Assarsson 2012,
 * "Clustered deferred and forward shading"; PlayCanvas's clustered lights):
 * the view cut into tiles of SB_GRID_TILE pixels and SB_GRID_SLICES slices of
 * view depth (spaced geometrically from the pass camera's near plane to its
 * far one), each cluster listing the lamps whose range reaches into it.
 *
 * Built once a frame on the CPU from each lamp's sphere of range: its
 * footprint (the screen rectangle and depth span of the sphere's box in the
 * pass camera's view, widened by a pixel and by 2 % in depth) is
 * conservative, so a cluster never misses a lamp that lights one of its
 * pixels; it may hold lamps that light none (they cost the loop a range test).
 * Two texture buffers carry it to the camera pass (lightgrid.glsl): a pixel
 * finds its cluster from gl_FragCoord and its view depth (its position in the
 * pass camera's view) and loops over that cluster's lamps,
 * in the order they were given, instead of over every lamp in view.
 *
 * The atlas's camera pass reads the lists; the per-light passes of cube and
 * dpsm (--lights) read a lamp's footprint, as the rectangle their added pass
 * is cut to (lamp.c). */
#pragma once
#include "render.h"

#define SB_GRID_TILE 32
#define SB_GRID_SLICES 16

#define SB_GRID_UNIFORMS 5

/* The counter of a technique with a light grid (its own counters' row; one column for all of them). */
#define SB_GRID_ITEMS_COUNTER                                                                                       \
    {.name = "grid_items", .unit = "count", .stats = SB_STAT_MEAN,                                                  \
     .doc = "grid=on (atlas; cube and dpsm with --lights): lamp-cluster pairs the frame's light grid lists (a "     \
            "cluster: a 32-pixel tile and a depth slice; 0 with grid=off or one lamp)"}

typedef struct sb_lightgrid {
    int tx, ty, slices;         /* tiles across and down; depth slices */
    double near, far;           /* the slices' span: the pass camera's planes, this frame */
    double zrow[4];             /* the pass view's third row: a fragment's view depth from its position */
    uint32_t *heads;            /* per cluster (x fastest, then y, then slice): first item, count */
    uint32_t *items;            /* lamp indices, cluster after cluster */
    size_t item_cap;
    uint32_t item_count;        /* this frame's */
    GLuint buf[2], tex[2];      /* [heads, items] */
    size_t gl_cap[2];           /* bytes the GL buffers hold */
    struct sb_lamp_footprint *fp;   /* scratch, a footprint a lamp (lamp_cap of them), kept across frames */
    bool *seen;
    int lamp_cap;
    GLint u[SB_GRID_UNIFORMS];  /* the camera pass's grid uniforms (sb_lightgrid_locate) */
} sb_lightgrid;

/* A lamp's footprint in the camera a frame's pass draws from (the look's for a flicker twin): the pixels its
 * range can light (x0, y0 inclusive, x1, y1 exclusive) and the view-depth span; false when none is in view. A lamp
 * without range (0) covers the whole view. */
typedef struct sb_lamp_footprint {
    int x0, y0, x1, y1;
    double z0, z1;
} sb_lamp_footprint;
bool sb_lamp_footprint_of(const sb_frame *f, sb_v3 pos, double range, sb_lamp_footprint *out);

/* The grid for targets of width x height pixels (no GL: its buffers are made at the first build). */
void sb_lightgrid_init(sb_lightgrid *g, int width, int height);
void sb_lightgrid_free(sb_lightgrid *g);
/* This frame's lists of n lamps (origin-relative positions, ranges), as the pass of f sees them, on the CPU;
 * returns the items (lamp-cluster pairs) listed. */
uint32_t sb_lightgrid_fill(sb_lightgrid *g, const sb_frame *f, const sb_v3 *pos, const double *range, int n);
/* The same, uploaded for the camera pass. */
uint32_t sb_lightgrid_build(sb_lightgrid *g, const sb_frame *f, const sb_v3 *pos, const double *range, int n);
/* The cluster (its first item and count in g->heads) holding the pixel at (px, py) whose view depth is depth: the
 * camera pass's rule (lightgrid.glsl), for tests. */
const uint32_t *sb_lightgrid_cell(const sb_lightgrid *g, double px, double py, double depth);
/* Finds the grid's uniforms in the camera pass's program (once, when it is made). */
void sb_lightgrid_locate(sb_lightgrid *g, GLuint prog);
/* Binds the lists to texture units `unit` and unit + 1 and sets the grid's uniforms of the bound program. */
void sb_lightgrid_bind(const sb_lightgrid *g, int unit);
