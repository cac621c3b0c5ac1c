/* pose.h - the GPU's posing pass (pose.c): a moving scene's skinned, morphing and rigid placements posed by a
 * compute pass into the scene's vertex buffer. render.c owns the vertex buffer and hands the pass what it needs
 * (the scene, the buffer, its numbering); the pass calls nothing of render.c. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "gl.h"
#include "scene.h"
#include "stage.h"
#include "util.h"

typedef struct sb_gpu_pose sb_gpu_pose;

/* The posing pass's stage (pose_ms): the run adds it to any technique's stages where the GPU poses the scene. */
extern const sb_stage_def sb_stage_pose;

/* Made for a moving scene: *out NULL for a still one, or where the GL's storage blocks cannot hold the data (then
 * the CPU poses every placement, said). vbase[d]: where draw d's first vertex lies in the vertex buffer as uploaded
 * (UINT32_MAX: drawn shared), the owner's array, kept current by it and alive as long as the pass. false: the
 * pass's program did not link. */
bool sb_pose_create(sb_gpu_pose **out, const sb_scene *s, const uint32_t *vbase, sb_err *err);
/* The vertex buffer was uploaded again (its numbering in vbase may have changed, and it holds the CPU's copy): the
 * pass poses again at the next sb_pose_run. */
void sb_pose_remap(sb_gpu_pose *p);
/* sb_scene_pose moved the scene: a pose is due (run in the first frame drawn at it, as stage sb_stage_pose). */
void sb_pose_due(sb_gpu_pose *p);
bool sb_pose_pending(const sb_gpu_pose *p, const sb_scene *s);
/* Runs a due pose into vbo at once; false: none due (or p NULL). */
bool sb_pose_run(sb_gpu_pose *p, const sb_scene *s, GLuint vbo);
/* The last pose's runs of placements (each a range of the vertex buffer) and dispatches (tests). */
void sb_pose_dispatches(const sb_gpu_pose *p, uint32_t *chunks, uint32_t *dispatches);
/* Whether the CPU poses moving draw d (no pass, or a placement the pass leaves): its vertices are sent. */
bool sb_pose_leaves(const sb_gpu_pose *p, uint32_t d);
void sb_pose_free(sb_gpu_pose *p);
