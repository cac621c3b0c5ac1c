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
#include <stdio.h>

#include "bvh.h"
#include "sbmath.h"
#include "util.h"

typedef struct sb_draw {
    uint32_t first_index;   /* into sb_scene.indices */
    uint32_t index_count;   /* multiple of 3 */
    sb_aabb box;            /* relative to origin */
    float color[4];         /* base colour factor */
    bool double_sided;      /* glTF doubleSided: back faces drawn and hit; otherwise culled (see README) */
    bool closed;            /* its primitive is a closed, consistently wound surface: culling its back
                               faces changes nothing a shadow map or a ray from outside it sees */
    uint32_t material;      /* into sb_scene.materials: what the alpha test of its surface is (0: none) */
    uint32_t node;          /* source node index, for messages */
    uint32_t first_vertex, vertex_count;    /* the vertices of its primitive (every chunk of it names them all) */
    /* Instancing: a draw that repeats another's triangles under a similarity transform names that draw (`proto`,
     * whose own proto is itself) and the transform, origin-relative, as three rows of a 3x4 matrix (identity
     * otherwise). The scene holds the triangles once: an instance's index run and vertex range are its proto's
     * (first_index, index_count, first_vertex and vertex_count name them), placed by the transform wherever they
     * are read (sb_draw_point on the CPU; the GPU and the reference's BVH draw or trace them through it). */
    uint32_t proto;
    float xform[12];
    uint8_t motion;         /* sb_draw_motion: whether a playing clip moves it, and how */
} sb_draw;

/* How a draw moves while the file's clips play (motion.h). */
typedef enum sb_draw_motion {
    SB_DRAW_STILL,          /* never: its vertices are those of the load */
    SB_DRAW_RIGID,          /* under an animated node: moved whole */
    SB_DRAW_DEFORMING,      /* skinned by moving joints, or morphed by animated weights */
} sb_draw_motion;

/* Whether draw d repeats another's geometry (sb_draw.proto). */
#define SB_DRAW_IS_INSTANCE(s, d) ((s)->draws[d].proto != (d))
/* The identity as sb_draw.xform's rows. */
extern const float sb_xform_identity[12];
/* Whether a transform's rotation part is the identity (within rounding): a tile of the same orientation. */
bool sb_xform_translation_only(const float x[12]);

/* The alpha test of a surface: a glTF MASK material (or a BLEND one under
 * --blend-casters mask). A point of a triangle is there when
 * alpha * texel(uv) >= cutoff; the texel is the nearest one (no filtering), in
 * every GL pass and in the reference's rays alike. Material 0 has no test. */
typedef struct sb_material {
    bool test;              /* the alpha test applies */
    float cutoff;           /* alphaCutoff (0.5 under --blend-casters mask) */
    float alpha;            /* baseColorFactor alpha */
    int32_t texture;        /* into sb_scene.textures, -1: none (alpha alone decides) */
    float uv[6];            /* KHR_texture_transform: u' = uv[0]u + uv[1]v + uv[2], v' = uv[3]u + uv[4]v + uv[5] */
} sb_material;

/* The alpha channel of a decoded base-colour texture (8 bits a texel). */
typedef struct sb_texture {
    uint32_t w, h;
    uint32_t offset;        /* first texel in sb_scene.texels */
    uint32_t wrap_s, wrap_t;    /* GL enums: GL_REPEAT, GL_CLAMP_TO_EDGE, GL_MIRRORED_REPEAT */
} sb_texture;

/* No draw holds more triangles: bigger primitives are split into spatial chunks. */
#define SB_CHUNK_TRIS 4096u

/* A vertex: position (3 floats, origin-relative), normal (3), texture
 * coordinates of the material's alpha texture (2), material (1, as uint32 bits). */
#define SB_VERTEX_FLOATS 9
#define SB_VERTEX_BYTES (SB_VERTEX_FLOATS * 4)

/* How the scene's BLEND materials take part in shadows (--blend-casters). */
typedef enum sb_blend_policy {
    SB_BLEND_MASK,          /* default: alpha-tested at 0.5, like a MASK material */
    SB_BLEND_OPAQUE,        /* drawn, cast and hit as opaque */
    SB_BLEND_NONE,          /* left out: neither seen, nor casting, nor hit */
} sb_blend_policy;
const char *sb_blend_policy_name(sb_blend_policy p);

/* What a loaded file held and how it was treated (shadowbench info SCENE). */
typedef struct sb_scene_features {
    uint32_t prims, double_sided, mask, blend, textures_decoded, textures_skipped;
    uint32_t skinned, skins, instanced_nodes, instances, draco, quantized, sparse;
    uint32_t morph_ignored, vertex_alpha_ignored, undecodable_alpha;
    uint32_t clips;         /* the file's animation clips, whether they play or not */
    bool posed;             /* skins and node animation at --pose T */
} sb_scene_features;

typedef enum sb_light_type { SB_LIGHT_DIRECTIONAL, SB_LIGHT_POINT, SB_LIGHT_SPOT } sb_light_type;

typedef struct sb_light {
    sb_light_type type;
    sb_v3 position;         /* relative to origin (point/spot) */
    sb_v3 direction;        /* direction the light travels (spot/directional) */
    float color[3];
    double intensity, range;
    double cone;            /* a spot light's outer cone, its half-angle in radians (0: none, a point light) */
} sb_light;

typedef struct sb_scene_camera {
    double yfov, znear, zfar;   /* zfar 0 = infinite/unspecified */
    int node;                    /* node that carries it, -1 if none */
} sb_scene_camera;

/* A large planar receiver, found when a technique first needs one (planar projected shadows):
 * n·p + d = 0 in origin-relative coordinates, n facing up the light side. */
#define SB_MAX_PLANES 4
typedef struct sb_plane {
    double n[3], d;
    double area;
    uint32_t *tris;              /* triangle numbers (index / 3) on the plane */
    uint32_t tri_count;
} sb_plane;

/* The farthest a vertex, a lamp or a key's value may lie from the origin (scene units): the reference's float
 * BVH and the rasterizer hold positions well within it (their products stay finite), as the path files do. A
 * file whose geometry reaches past it, as placed or as its clips can pose it, is refused at load. */
#define SB_SCENE_MAX_COORD 1e12

/* Which of a file's animations play (--anim). */
typedef enum sb_anim_mode {
    SB_ANIM_ALL,                 /* the default: every clip of the file plays, as the file says */
    SB_ANIM_NONE,                /* none: the scene as loaded (its nodes' own transforms), frozen */
    SB_ANIM_LIST,                /* the clips named in sb_scene_opts.anim_clips */
} sb_anim_mode;

/* How a scene file is read; zero means the default. */
typedef struct sb_scene_opts {
    bool allow_external_uris;    /* buffer and image URIs may leave the scene's folder */
    sb_blend_policy blend;       /* --blend-casters */
    bool pose;                   /* --pose T: nodes and skins at time T of the first animation, frozen (no clip plays) */
    double pose_time;            /* otherwise: the nodes' own transforms (skins in their rest pose) */
    sb_anim_mode anim;           /* --anim */
    char anim_clips[256];        /* SB_ANIM_LIST: clip names (or indices), comma-separated */
    double anim_speed;           /* --anim-speed: clip seconds a second of the path's clock (0: 1) */
} sb_scene_opts;

/* The parts of a scene's load, timed: reading, checking and parsing the file
 * (tinygltf), flattening the node graph into draws (skins, instances,
 * materials), the draws' chunks and boxes, the culling BVH; and the plane search, timed when it runs (on a
 * technique's first need, or before the scene cache is written: not part of a load that needs no plane). */
enum { SB_LOAD_PARSE, SB_LOAD_FLATTEN, SB_LOAD_DRAWS, SB_LOAD_BVH, SB_LOAD_PLANES, SB_LOAD_PARTS };
extern const char *const sb_load_part_names[SB_LOAD_PARTS];

typedef struct sb_scene {
    char *file;
    sb_v3 origin;                /* world position of the local frame */
    float *vertices;             /* SB_VERTEX_FLOATS per vertex */
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

    sb_material *materials;      /* [0]: no alpha test */
    uint32_t material_count;
    sb_texture *textures;
    uint32_t texture_count;
    uint8_t *texels;             /* every texture's alpha, one after the other */
    uint32_t texel_count;
    uint32_t alpha_tested_draws; /* draws whose material has the alpha test */
    uint32_t single_sided_draws;
    sb_scene_features features;

    uint64_t content_hash;       /* sb_hash_bytes of the file, the files it reads and the options that change geometry (run ids) */
    sb_scene_opts opts;          /* as loaded (a glTF camera path of the scene is read alike) */
    double load_ms;
    double load_part_ms[SB_LOAD_PARTS]; /* where load_ms went (sb_load_part_names) */
    bool from_cache;             /* read from the scene cache (scene_cache.h): load_ms is that read */
    void *cache_map;             /* the mapped cache entry the arrays point into (sb_scene_free unmaps it) */
    size_t cache_map_len;
    uint32_t nodes_drawn;        /* node instances with a mesh reached from the scene graph */
    sb_plane planes[SB_MAX_PLANES];
    uint32_t plane_count;
    bool planes_found;           /* the plane search ran (sb_scene_find_planes): plane_count holds */
    char degenerate[128];        /* why nothing in it can cast or receive a shadow ("" if it can) */
    char unused[512];            /* what the file holds that nothing draws and is left out, or breaks a rule
                                    there ("; "-separated; "" if nothing): info and every run's warnings say it */

    uint32_t instance_draws;     /* draws that repeat another's geometry (sb_draw.proto) */

    /* Motion (motion.h): the file's clips as they play; NULL for a scene where nothing moves. */
    struct sb_motion *motion;
    void (*motion_free)(struct sb_motion *);   /* how sb_scene_free frees it (the motion module's) */
    uint32_t moving_draws;       /* draws whose sb_draw.motion is not SB_DRAW_STILL */
    sb_aabb still_bounds;        /* the bounds of the draws that never move (relative to origin) */
    double pose_time;            /* the clip time the pose holds (NAN: as loaded); the CPU's vertices: motion.h */
    char anim[288];              /* what plays, as a run's `anim` column says it: "" a still file, or every clip at
                                    speed 1 (the default); "none" (a file's clips held still); the clips that play in
                                    file order ("walk", "all") with " x3" at another --anim-speed */
    uint64_t pose_serial;        /* how many poses moved something (a changed serial: the geometry moved) */

    /* builder scratch, freed by sb_scene_finish */
    double *build_pos;
    uint32_t build_cap;
    double *build_rel;           /* 12 a draw as added: an instance's world transform rows (sb_prim_desc.relative) */
    uint32_t build_rel_cap;
} sb_scene;

/* "parse 40, flatten 120, ..." (ms) into out, or "from the scene cache" */
void sb_scene_load_parts(const sb_scene *s, char *out, size_t len);

void sb_scene_free(sb_scene *s);
/* What the file held and how it is drawn (shadowbench info SCENE), as lines "key: value". */
void sb_scene_info(const sb_scene *s, FILE *out);
uint64_t sb_scene_triangles(const sb_scene *s);
/* The bytes the loaded scene holds on the CPU: its vertices, indices, draws, materials, alpha texels, planes
 * and BVH (a mapped scene-cache entry counted as if read). */
double sb_scene_cpu_bytes(const sb_scene *s);
/* The index-th point or spot light of the scene in file order (NULL if there
 * is none); *count (may be NULL) gets how many there are. */
const sb_light *sb_scene_point_light(const sb_scene *s, int index, int *count);

/* The lights one run shadows (--lights): each the index of a point or spot light in the order of
 * sb_scene_point_light, or SB_LIGHT_SUN. */
#define SB_MAX_LIGHTS 256
#define SB_LIGHT_SUN (-1)
typedef struct sb_light_set {
    int count;
    int16_t idx[SB_MAX_LIGHTS];
} sb_light_set;
/* Reads sun|lamps|all|LIST (LIST: sun and lamp indices, commas between) against the scene: false, with one line
 * naming what the scene lacks and what it has, for a lamp it does not have, a sun where it has none (the run's
 * --sun counts as one: has_sun), an empty set, a word it does not know or a light named twice. */
bool sb_scene_light_set(const sb_scene *s, const char *spec, bool has_sun, sb_light_set *out, sb_err *err);
/* The set's one name, whatever words chose it: "sun", "lamps" (every lamp), "all" (the sun and every lamp) or the
 * list, the sun first and the lamps by number ("sun,0,3"); what a run's identity and its `light` column hold. */
void sb_light_set_text(const sb_scene *s, const sb_light_set *set, char *out, size_t len);

/* Builder used by the glTF adapter: appends one primitive already transformed
 * to world space (double positions); vertices are re-based to the origin later. */
typedef struct sb_prim_desc {
    const double *positions;     /* 3 per vertex, world space */
    const double *normals;       /* 3 per vertex, world space, may be NULL */
    const double *uv;            /* 2 per vertex (the alpha texture's set), may be NULL */
    uint32_t vertex_count;
    const uint32_t *indices;     /* triangle list */
    uint32_t index_count;
    float color[4];
    bool double_sided;
    uint32_t material;           /* from sb_scene_add_material, 0: none */
    uint32_t node;
    int closed_known;            /* 0: work out whether it is closed; 1: it is not; 2: it is (an instance of a
                                    primitive already added: the answer does not change with the transform) */
    /* Another placement of a primitive already added (0: none): 1 + the draw index it was added as, and the
     * world transform from that placement to this one (4x4 column-major). The same vertices and triangles in
     * the same order, so the scene keeps one copy (CPU, GPU, rays) when the transform is a similarity that keeps
     * the winding (sb_scene_add_prim decides; otherwise it is a copy like any other). */
    uint32_t instance_of;
    double relative[16];
} sb_prim_desc;

void sb_scene_begin(sb_scene *s);
/* Room for this many more vertices, indices and draws (a loader that knows them: no growing as it adds). */
void sb_scene_reserve(sb_scene *s, uint64_t vertices, uint64_t indices, uint32_t draws);
/* Adds a material (the alpha test) and returns its index; equal ones are shared. */
uint32_t sb_scene_add_material(sb_scene *s, const sb_material *m);
/* Adds a texture's alpha (w*h bytes, copied) and returns its index. */
int32_t sb_scene_add_texture(sb_scene *s, uint32_t w, uint32_t h, const uint8_t *alpha, uint32_t wrap_s,
                             uint32_t wrap_t);
/* Whether the surface of material m is there at texture coordinates (u, v):
 * the alpha test, exactly as the shaders do it (alpha.glsl). */
bool sb_material_covers(const sb_scene *s, uint32_t m, float u, float v);
/* The first float of vertex i. */
static inline float *sb_vertex(const sb_scene *s, uint32_t i) { return s->vertices + (size_t)SB_VERTEX_FLOATS * i; }
/* Vertex v of draw d's triangles (an index of its run) where the draw places it, origin-relative: an instance's
 * through its transform (d is one of s->draws). */
static inline void sb_draw_point(const sb_scene *s, const sb_draw *d, uint32_t v, float out[3]) {
    const float *p = sb_vertex(s, v);
    if (d->proto == (uint32_t)(d - s->draws)) {
        out[0] = p[0], out[1] = p[1], out[2] = p[2];
        return;
    }
    const float *x = d->xform;
    for (int r = 0; r < 3; r++) out[r] = x[4 * r] * p[0] + x[4 * r + 1] * p[1] + x[4 * r + 2] * p[2] + x[4 * r + 3];
}
/* Every triangle placed with vertices of its own, for what needs the world's triangles as one array (the
 * volumes' silhouettes, the GPU's copy of draws that cannot share): the scene's own vertices and indices (the
 * scene's arrays themselves where no draw is an instance), then, for each instance draw `which` names (NULL:
 * every one), in draw order, its triangles on vertices placed by its transform (normals turned with it). */
typedef struct sb_scene_flat {
    const float *vertices;       /* SB_VERTEX_FLOATS each */
    uint32_t vertex_count;
    const uint32_t *indices;
    uint32_t index_count;
    uint32_t *first;             /* per draw: its first index in indices (an instance not expanded: its proto's) */
    bool owned;                  /* the arrays are the flat's own (sb_scene_flat_free frees them) */
} sb_scene_flat;
void sb_scene_flatten(const sb_scene *s, const uint8_t *which, sb_scene_flat *out);
void sb_scene_flat_free(sb_scene_flat *f);
/* The placed triangles' numbering (the planes' tris, and the GPU's index buffer once no draw shares: planar's
 * receivers): the index array's own, t < index_count / 3, then every instance draw's in draw order, each in its
 * run's order; sb_scene_triangles counts them. sb_scene_flatten with every draw lays them out so. */
void sb_scene_add_prim(sb_scene *s, const sb_prim_desc *p);
/* Finds the large planar receivers (a plane holding at least 10% of the area of
 * the bounds' largest face) once: later calls return at once. A load does not search
 * (most techniques need no plane); the technique that needs one and the scene cache ask. */
void sb_scene_find_planes(sb_scene *s);
/* Re-bases to the centre, splits big draws into spatial chunks, builds AABBs and the BVH. */
bool sb_scene_finish(sb_scene *s, sb_err *err);

/* ---- motion ---- */

/* Whether the scene's clips move anything (motion.h poses it). */
static inline bool sb_scene_moves(const sb_scene *s) { return s->motion && s->moving_draws; }
/* The posing step of one primitive: writes its vertices [first, first + count) from world positions and
 * normals (NULL: face normals, as at load) and, with boxes, the exact boxes of its draws (the ndraws of draws:
 * its chunks; without, they keep the bounds that follow the joints, motion.h). */
void sb_scene_repose_prim(sb_scene *s, uint32_t first, uint32_t count, const double *pos, const double *nrm,
                          const uint32_t *draws, uint32_t ndraws, bool boxes);

/* Culling: visits every draw whose AABB is not fully outside any of the planes
 * (plane: n·p + d >= 0 is inside). Exact AABB-vs-plane tests over the BVH. */
uint32_t sb_scene_cull(const sb_scene *s, const double (*planes)[4], int plane_count, sb_bvh_visit visit, void *user);
/* Collects the draws sb_scene_cull would visit into out (draw_count capacity); returns how many. */
uint32_t sb_scene_collect(const sb_scene *s, const double (*planes)[4], int plane_count, uint32_t *out);
/* (Re)builds the culling BVH over the draws' boxes. */
void sb_scene_build_bvh(sb_scene *s);
/* The BVH over the draws' boxes as they are now (a pose moved them), its tree kept. */
void sb_scene_refit_bvh(sb_scene *s);
/* The nearest triangle (either side) the ray o + t d meets, t in (0, tmax)
 * (origin-relative; d need not be unit): its t, or INFINITY. *backface (may
 * be NULL): it is the inside of a closed single-sided surface (o is inside it). The CPU's vertices as they are:
 * in a moving scene, motion.h's sb_scene_sync_vertices first. */
double sb_scene_raycast(const sb_scene *s, sb_v3 o, sb_v3 d, double tmax, bool *backface);
