/* scene.h - the one scene model every module reads (cgltf-style: flat arrays).
 *
 * A scene is a flat vertex array (position + normal, float, relative to
 * `origin`), one index array, and a list of draws. A draw is one node's
 * primitive (or a spatial chunk of a big one) with its own world AABB: it is
 * the unit of culling and of draw calls. `origin` is the scene's centre in
 * double precision; every CPU matrix is built relative to it, so a scene far
 * from the world origin keeps float precision on the GPU. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "sbmath.h"
#include "util.h"

typedef struct sb_aabb {
    sb_v3 lo, hi;
} sb_aabb;

typedef struct sb_draw {
    uint32_t first_index;   /* into sb_scene.indices */
    uint32_t index_count;   /* multiple of 3 */
    sb_aabb box;            /* relative to origin */
    float color[4];         /* base colour factor */
    bool alpha_mask;        /* glTF alphaMode MASK */
    float alpha_cutoff;
    uint32_t node;          /* source node index, for messages */
} sb_draw;

typedef struct sb_bvh_node {
    sb_aabb box;
    int32_t left, right;    /* children, -1 for a leaf */
    uint32_t first, count;  /* leaf: range in sb_bvh.items */
} sb_bvh_node;

typedef struct sb_bvh {
    sb_bvh_node *nodes;
    uint32_t node_count;
    uint32_t *items;        /* draw indices */
} sb_bvh;

typedef enum sb_light_type { SB_LIGHT_DIRECTIONAL, SB_LIGHT_POINT, SB_LIGHT_SPOT } sb_light_type;

typedef struct sb_light {
    sb_light_type type;
    sb_v3 position;         /* relative to origin (point/spot) */
    sb_v3 direction;        /* direction the light travels (spot/directional) */
    float color[3];
    double intensity, range;
} sb_light;

typedef struct sb_scene_camera {
    double yfov, znear, zfar;   /* zfar 0 = infinite/unspecified */
    int node;                    /* node that carries it, -1 if none */
} sb_scene_camera;

/* A large planar receiver found at load (planar projected shadows use them):
 * n·p + d = 0 in origin-relative coordinates, n facing up the light side. */
#define SB_MAX_PLANES 4
typedef struct sb_plane {
    double n[3], d;
    double area;
    uint32_t *tris;              /* triangle numbers (index / 3) on the plane */
    uint32_t tri_count;
} sb_plane;

/* How a scene file is read; zero means the default. */
typedef struct sb_scene_opts {
    bool allow_external_uris;    /* buffer and image URIs may leave the scene's folder */
} sb_scene_opts;

typedef struct sb_scene {
    char *file;
    sb_v3 origin;                /* world position of the local frame */
    float *vertices;             /* 6 floats per vertex: position, normal */
    uint32_t vertex_count, vertex_cap;
    uint32_t *indices;
    uint32_t index_count, index_cap;
    sb_draw *draws;
    uint32_t draw_count, draw_cap;
    sb_aabb bounds;              /* relative to origin */
    sb_bvh bvh;

    sb_light *lights;
    uint32_t light_count;
    bool has_sun;                /* a KHR_lights_punctual directional light was found */
    sb_v3 sun;                   /* unit vector toward the sun */
    sb_scene_camera *cameras;
    uint32_t camera_count;

    uint64_t content_hash;       /* FNV-1a of the file bytes (for run ids) */
    sb_scene_opts opts;          /* as loaded (a glTF camera path of the scene is read alike) */
    double load_ms;
    uint32_t images_skipped;     /* textures present but not decoded */
    uint32_t alpha_mask_draws;
    uint32_t nodes_drawn;        /* node instances with a mesh reached from the scene graph */
    sb_plane planes[SB_MAX_PLANES];
    uint32_t plane_count;
    char degenerate[128];        /* why nothing in it can cast or receive a shadow ("" if it can) */

    /* builder scratch, freed by sb_scene_finish */
    double *build_pos;
    uint32_t build_cap;
} sb_scene;

/* Loads .gltf/.glb (through tinygltf, after gltf_check.h's checks) or a bundled
 * name ("plane-box", "desert", ...; looked up in SB_DATA_DIR and the build's
 * scene folder). opts may be NULL. */
bool sb_scene_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err);
void sb_scene_free(sb_scene *s);
uint64_t sb_scene_triangles(const sb_scene *s);
/* The index-th point or spot light of the scene in file order (NULL if there
 * is none); *count (may be NULL) gets how many there are. */
const sb_light *sb_scene_point_light(const sb_scene *s, int index, int *count);
/* Resolves a bundled scene or path name to a file; returns false if it is not one. */
bool sb_resolve_bundled(const char *name, const char *ext, char *out, size_t outlen);

/* Builder used by the glTF adapter: appends one primitive already transformed
 * to world space (double positions); vertices are re-based to the origin later. */
typedef struct sb_prim_desc {
    const double *positions;     /* 3 per vertex, world space */
    const double *normals;       /* 3 per vertex, world space, may be NULL */
    uint32_t vertex_count;
    const uint32_t *indices;     /* triangle list */
    uint32_t index_count;
    float color[4];
    bool alpha_mask;
    float alpha_cutoff;
    uint32_t node;
} sb_prim_desc;

void sb_scene_begin(sb_scene *s);
void sb_scene_add_prim(sb_scene *s, const sb_prim_desc *p);
/* Finds the large planar receivers (a plane holding at least 10% of the area of
 * the bounds' largest face); called by sb_scene_finish. */
void sb_scene_find_planes(sb_scene *s);
/* Re-bases to the centre, splits big draws into spatial chunks, builds AABBs and the BVH. */
bool sb_scene_finish(sb_scene *s, sb_err *err);

/* Culling: visits every draw whose AABB is not fully outside any of the planes
 * (plane: n·p + d >= 0 is inside). Exact AABB-vs-plane tests over the BVH. */
typedef void (*sb_draw_visit)(uint32_t draw, void *user);
uint32_t sb_bvh_cull(const sb_scene *s, const double (*planes)[4], int plane_count,
                     sb_draw_visit visit, void *user);
/* Collects the draws sb_bvh_cull would visit into out (draw_count capacity); returns how many. */
uint32_t sb_bvh_collect(const sb_scene *s, const double (*planes)[4], int plane_count, uint32_t *out);
bool sb_aabb_outside_plane(const sb_aabb *b, const double plane[4]);
void sb_bvh_build(sb_scene *s);
void sb_bvh_free(sb_bvh *b);
