/* scene_cache.h - flattened scenes kept on disk, so a scene read before loads
 * in milliseconds: an entry holds what the loader wrote into it (scene_load.c:
 * the vertices, indices, draws, planes, materials, lights and cameras as
 * sb_scene_finish left them) and what the load logged. The cache stores
 * bytes and knows nothing of the scene model.
 *
 * An entry is found by the bytes of the scene file (hashed, never by its
 * name or time), the folder it stands in (its real path: the same file in
 * another folder is another entry), the load options and the identity of the
 * running binary (size and modification time of /proc/self/exe: any rebuild
 * starts afresh), and it is used only when every other file the load read
 * (external buffers, images), found again as the scene resolves it from its
 * own folder (a path relative to it; an external one as it was), still
 * hashes as it did: a dependency copied, moved, edited, cut or missing is a
 * miss, and the load that follows says what is wrong with it. Entries are written whole under a temporary
 * name and renamed (sb_write_file_atomic); one that does not check (truncated, another version,
 * damaged: a checksum covers it) is ignored and written again. The folder is
 * kept under SB_SCENE_CACHE_MAX_BYTES, least recently used first.
 *
 * Where: $SB_SCENE_CACHE (a folder, or "off"), else
 * $XDG_CACHE_HOME/shadowbench/scenes, else ~/.cache/shadowbench/scenes. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "blob.h"

#define SB_SCENE_CACHE_MAX_BYTES ((uint64_t)2 << 30)

/* The cache folder, or false when the cache is off (or there is no home). */
bool sb_scene_cache_dir(char *out, size_t len);

/* While a load runs: files it read besides the scene file (their real paths), with their hashes (gltf_load.cc). */
void sb_scene_cache_note_file(const char *path, uint64_t hash);

/* The entry's key: the scene file's bytes, its folder (scene_dir, a real path), the load options (as canonical
 * bytes), the binary. */
uint64_t sb_scene_cache_key(const char *scene_dir, const void *opts, size_t opts_len, const void *bytes, size_t size);

/* Reads an entry's payload (arrays may be used in place); it owns the mapped
 * entry (map, len) from the call on, whatever it returns: kept while used,
 * released with sb_unmap_file. */
typedef bool (*sb_scene_cache_read)(sb_rbuf *payload, void *map, size_t len, void *user);
/* Writes the payload of an entry. */
typedef void (*sb_scene_cache_write)(sb_wbuf *payload, const void *user);

/* Hands the entry of that key to read, its dependencies found from scene_dir
 * (the scene's folder, a real path); false on a miss or when read refuses
 * it. On a hit says again what the load had logged. */
bool sb_scene_cache_get(uint64_t key, const char *scene_dir, sb_scene_cache_read read, void *user);

/* Starts recording a load of a scene in scene_dir (files read, lines logged);
 * put ends it and, when write is not NULL (the load succeeded), writes the
 * entry. Failing to write is not an error of the load: the next load reads
 * the file again. */
void sb_scene_cache_begin(const char *scene_dir);
void sb_scene_cache_put(uint64_t key, sb_scene_cache_write write, const void *user);
