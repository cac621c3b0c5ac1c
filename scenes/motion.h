/* motion.h - a scene's animations as they play: the glTF clips (node
 * translation, rotation and scale, morph target weights, and the skins the
 * moving joints carry) sampled at a time on the path's clock, posing the
 * scene's moving primitives again. Built by the glTF adapter (gltf_load.cc)
 * when a file has clips and they play (sb_scene_opts.anim); read by
 * sb_scene_pose (scene.h), which keeps the scene's boxes, bounds and BVH true
 * to the pose. A primitive is posed on the CPU, in double precision, by the
 * same code that placed it at load: a rigid one by its node's (and its
 * EXT_mesh_gpu_instancing instance's) world transform, a morphing one by its
 * targets at the node's weights, a skinned one by its joints. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "pose_data.h"

struct sb_scene;
typedef struct sb_motion sb_motion;

/* What a clip is (shadowbench info SCENE). */
typedef struct sb_clip_info {
    const char *name;           /* the file's name, or its index ("0") when it has none */
    double duration;            /* its last key time: it loops with that period */
    uint32_t channels;          /* channels played */
    uint32_t nodes;             /* nodes it animates */
} sb_clip_info;

/* What moves (info, the run's warnings). */
typedef struct sb_motion_stats {
    uint32_t clips, channels, skipped;      /* clips and channels played; channels left out (warnings) */
    uint32_t animated_nodes;                /* nodes a played channel targets */
    uint32_t rigid_prims, skinned_prims, morphing_prims;   /* primitive placements that move, by kind */
    /* after the first pose: its work's groups that share no node (a thread's each, a few at a time), and the
       GPU-posed placements that read two groups (bounded after them, alone) */
    uint32_t pose_groups, lone_places;
} sb_motion_stats;

#include <stdio.h>

/* Poses the scene at clip time t: the nodes, the moving draws' boxes (bounds that follow the joints: each
 * joint's share of a draw's vertices, boxed once in the mesh's space and carried by the joint's matrix, so the
 * box holds every vertex the pose can put there), the scene's bounds and its BVH. The vertices of the
 * placements the GPU poses (sb_pose_data) are left where they were: the GPU's posing pass moves its own copy,
 * and sb_scene_sync_vertices moves the CPU's for the code that reads it. A placement the GPU cannot pose (no
 * normals in the file: its face normals are the CPU's; a negative skin weight: no box holds it) is posed here
 * as before, its boxes exact. False when nothing moves or the scene already holds that time. */
bool sb_scene_pose(struct sb_scene *s, double t);
/* The CPU's vertices at the scene's pose (sb_scene_pose), posed now if they hold another: for whatever reads
 * them (the reference's refit on evaluated frames, raycast, the light-facing order of open single-sided draws,
 * psm's nearest receiver, volumes' silhouettes, a path's checks). The boxes are left as sb_scene_pose made
 * them. A const scene may be synced: the vertices are a copy of its pose, not a part of it. */
void sb_scene_sync_vertices(const struct sb_scene *s);
/* How many times the CPU's vertices were posed (sb_scene_sync_vertices and the CPU-only placements' poses
 * excepted): what a run's evaluated frames and CPU readers cost. */
uint64_t sb_scene_cpu_poses(const struct sb_scene *s);

/* The GPU's posing data of a moving scene (NULL: nothing the GPU poses). */
const sb_pose_data *sb_motion_gpu_data(const struct sb_scene *s);
/* The pose's matrices (column-major, 16 floats each, relative to the scene's origin: palette_count of them) and
 * morph weights (weight_count), at the time the scene holds. */
void sb_motion_gpu_frame(const struct sb_scene *s, float *palette, float *weights);
/* The animation lines of `shadowbench info SCENE`: the clips that play, what moves and how. */
void sb_motion_info(const struct sb_scene *s, FILE *out);

/* Marks the scene's draws by how they move (sb_draw.motion) once the scene is
 * finished (its draws chunked); returns how many move. */
uint32_t sb_motion_mark(sb_motion *m, struct sb_scene *s);
sb_motion_stats sb_motion_statistics(const sb_motion *m);
/* The i-th clip played (i < stats.clips). */
sb_clip_info sb_motion_clip(const sb_motion *m, uint32_t i);
void sb_motion_free(sb_motion *m);

/* The scene cache's copy (scene_load.c): everything posing needs (the node graph's rest pose, the clips'
 * channels, every moving placement's rest data, the skins), written after the scene's arrays; read back against
 * the scene it belongs to, NULL when the entry is short or does not hold together (then the file is read again).
 * sb_motion_mark makes the draws' marks again once read. */
struct sb_wbuf;
struct sb_rbuf;
void sb_motion_write(const sb_motion *m, struct sb_wbuf *b);
sb_motion *sb_motion_read(struct sb_rbuf *r, const struct sb_scene *s);
