/* gltf_check.h - a glTF document held to the specification before any byte of
 * it is read as geometry.
 *
 * The glTF library is trusted with parsing, not with the rules that decide
 * where bytes are read: it adds 64-bit offsets that wrap, takes negative
 * numbers as 0, truncates indices above 2^32 into valid ones, and opens any
 * path a URI names. sb_gltf_check walks the raw JSON (json.h, exact integers)
 * and refuses, with the file and the JSON path, every number of the wrong
 * type, sign or range; every reference to an element that does not exist;
 * every buffer, bufferView, accessor and sparse range that does not fit
 * (compared by subtraction, multiplied with overflow checks); strides smaller
 * than the element or not a multiple of 4; offsets not aligned to the
 * component size; index accessors with a stride; node transforms that are
 * not a rotation, translation and scale; node graphs with two parents or a
 * cycle; invalid lights and cameras; and URIs that leave the scene's folder,
 * are not regular files, or are not data: URIs or relative paths. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "json.h"

/* The deepest node graph read (levels from a root): a chain deeper is refused, naming it. Each level is a node
 * the glTF library holds whole (about a kilobyte): 100,000 levels load in 0.2 s, a million took 3.6 s. */
#define SB_GLTF_MAX_DEPTH 100000

typedef struct sb_gltf_check_desc {
    const char *file;           /* for messages */
    const char *base_dir;       /* the scene's folder: relative URIs resolve against it */
    bool glb;                   /* buffer 0 may be the BIN chunk */
    uint64_t bin_size;          /* size of the BIN chunk (0: none) */
    bool allow_external_uris;   /* URIs may leave base_dir (still regular files only) */
    /* Parts nothing draws are held leniently: what is wrong with them, or that they are left out, is added here
       ("; "-separated, NULL: not kept) instead of refusing the file. Lenient: cameras (checked strictly when a path
       uses one: sb_gltf_check_camera), "pointer" animation channels (not applied), and every buffer, bufferView,
       accessor and light that nothing drawn or animated reads (a primitive, skin, animation sampler, image or node
       reads it): left out, with what is wrong with it said. */
    char *unused;
    size_t unused_len;
} sb_gltf_check_desc;

bool sb_gltf_check(const sb_json *root, const sb_gltf_check_desc *d, sb_err *err);
/* Which buffers something drawn or animated reads (a bufferView of a primitive's, a skin's, an animation's or an
 * image's accessor): 1 a buffer (malloc'd; NULL when the document has no arrays to read). A buffer nothing reads
 * is never opened. */
uint8_t *sb_gltf_used_buffers(const sb_json *root);
/* Camera k held strictly (a path uses it): false with the file and the JSON path. */
bool sb_gltf_check_camera(const sb_json *root, const sb_gltf_check_desc *d, uint64_t k, sb_err *err);
/* Adds a note to a "; "-separated list (dropped when it would not fit whole). */
void sb_gltf_note(char *list, size_t len, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* The chunks of a .glb: the JSON text and the BIN chunk (NULL, 0 if none),
 * with the header and every chunk length checked against the file size.
 * Bytes after the header's declared length are left out (*used: the
 * declared length; a note in unused, when kept); fewer are a refusal. */
bool sb_glb_split(const unsigned char *data, uint64_t size, const char *file, const char **json, uint64_t *json_len,
                  const unsigned char **bin, uint64_t *bin_len, uint64_t *used, char *unused, size_t unused_len,
                  sb_err *err);

/* Resolves a file URI (percent-decoded here) against base_dir into out with
 * sb_file_confined; other schemes than a relative or absolute path are refused. */
bool sb_uri_resolve(const char *base_dir, const char *uri, bool allow_external, char *out, size_t outlen,
                    sb_err *err);
/* A path (relative: to base_dir) must name a regular file and, unless
 * allow_external, lie inside base_dir once '..' and symbolic links are
 * resolved; out gets the resolved path. Fills err with what is wrong (no file
 * name or JSON path: the caller adds them). */
bool sb_file_confined(const char *base_dir, const char *path, bool allow_external, char *out, size_t outlen,
                      sb_err *err);
/* Percent-decodes src into dst (at most len bytes with the NUL); false if malformed. */
bool sb_uri_decode(const char *src, char *dst, size_t len);
