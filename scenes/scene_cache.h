/* scene_cache.h - flattened scenes kept on disk, so a scene read before loads
 * in milliseconds: the vertices, indices, draws, planes, materials, lights and
 * cameras as sb_scene_finish left them, and what the load logged.
 *
 * An entry is found by the bytes of the scene file (hashed, never by its
 * name or time), the load options and the identity of the running binary
 * (size and modification time of /proc/self/exe: any rebuild starts afresh),
 * and it is used only when every other file the load read (external buffers,
 * images) still hashes as it did. Entries are written whole under a temporary
 * name and renamed (sb_write_file_atomic); one that does not check (truncated, another version,
 * damaged: a checksum covers it) is ignored and written again. The folder is
 * kept under SB_SCENE_CACHE_MAX_BYTES, least recently used first.
 *
 * Where: $SB_SCENE_CACHE (a folder, or "off"), else
 * $XDG_CACHE_HOME/shadowbench/scenes, else ~/.cache/shadowbench/scenes. */
#pragma once
#include "scene.h"

#define SB_SCENE_CACHE_MAX_BYTES ((uint64_t)2 << 30)

/* The cache folder, or false when the cache is off (or there is no home). */
bool sb_scene_cache_dir(char *out, size_t len);

/* While a load runs: files it read besides the scene file, with their hashes (gltf_load.cc). */
void sb_scene_cache_note_file(const char *path, uint64_t hash);

/* The entry's key: the scene file's bytes, the load options, the binary. */
uint64_t sb_scene_cache_key(const sb_scene_opts *opts, const void *bytes, size_t size);

/* Fills s from the entry of that key; false on a miss (s untouched). Says
 * again what the load had logged. */
bool sb_scene_cache_get(sb_scene *s, const char *path, const sb_scene_opts *opts, uint64_t key);

/* Starts recording a load (files read, lines logged); put ends it and, when
 * ok, writes the entry for the scene just loaded. Failing to write is not an
 * error of the load: the next load reads the file again. */
void sb_scene_cache_begin(void);
void sb_scene_cache_put(const sb_scene *s, uint64_t key, bool ok);
