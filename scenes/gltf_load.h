/* gltf_load.h - the tinygltf adapter (gltf_load.cc): a .gltf/.glb file,
 * checked (gltf_check.h), flattened into a begun scene's arrays. */
#pragma once
#include "scene.h"

#ifdef __cplusplus
extern "C" {
#endif
/* Adds the file's primitives, lights and cameras to s (sb_scene_begin'd, file
 * and opts set); false with the reason (file and JSON path) on a refusal. */
bool sb_gltf_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err);

/* An animated glTF camera: the world pose of the node carrying camera K at
 * every time its animations key (paths/path.c makes a path of them). */
typedef struct sb_camera_key {
    double t;               /* from the first key */
    sb_v3 pos;              /* world space */
    sb_quat rot;
} sb_camera_key;
typedef struct sb_camera_keys {
    sb_camera_key *keys;    /* sb_xcalloc'd: the caller frees it */
    int key_count;
    double fov_deg;         /* the camera's vertical field of view; 0: it has none */
    double znear, zfar;     /* 0: not given */
} sb_camera_keys;
bool sb_gltf_camera_keys(sb_camera_keys *out, const char *path, int cam, const sb_scene_opts *opts, sb_err *err);
#ifdef __cplusplus
}
#endif
