/* scene_load.h - loading a scene: a .gltf/.glb file or a bundled name, through
 * the scene cache (scene_cache.h) or the glTF loader (gltf_load.h). */
#pragma once
#include "scene.h"

/* Loads .gltf/.glb (through tinygltf, after gltf_check.h's checks) or a bundled
 * name ("plane-box", "desert", ...; looked up in SB_DATA_DIR and the build's
 * scene folder). opts may be NULL. */
bool sb_scene_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err);
/* Resolves a bundled scene or path name to a file; returns false if it is not one. */
bool sb_resolve_bundled(const char *name, const char *ext, char *out, size_t outlen);
