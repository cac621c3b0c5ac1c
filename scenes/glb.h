/* glb.h - a small writer of binary glTF (.glb) scenes made of meshes and a
 * KHR_lights_punctual sun: the bundled scenes and the conformance set
 * (scenegen) and the stress battery's generated cases are written with it and
 * read back through the normal loader.
 *
 * The plain path: meshes (positions, normals, indices, one of five fixed
 * materials), each with a node at `offset`, then the sun and the lamps. For
 * the conformance scenes: texture coordinates, materials, nodes, accessors,
 * buffer views, PNG images and top-level JSON of the caller's own, each
 * returning its index; what the caller adds comes first in its array (meshes
 * are numbered as created), so a scene without extras is written as before. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sbmath.h"

typedef struct sb_glb_mesh {
    float *pos, *nrm, *uv;      /* uv: 2 floats a vertex once sb_glb_uv was called (else NULL) */
    uint32_t nv, capv;
    uint32_t *idx;
    uint32_t ni, capi;
    int material;               /* 0 ground ... 4 concrete; 5 on: sb_glb_material's */
    bool no_node;               /* no node of its own (drawn by a node of sb_glb_node) */
    bool draco;                 /* stored with KHR_draco_mesh_compression (scenegen built with Draco) */
    char node_extra[256];       /* JSON members added to its node, e.g. "\"skin\":0" */
    char prim_extra[256];       /* JSON members added to its primitive's attributes, e.g. "\"JOINTS_0\":3" */
    char custom[512];           /* the whole primitive's JSON instead (then no vertex data is written) */
} sb_glb_mesh;

typedef struct sb_glb_str {
    char *s;
    size_t len, cap;
} sb_glb_str;

typedef struct sb_glb_scene {
    sb_glb_mesh *meshes;
    int n, cap;
    sb_v3 sun;                  /* toward the sun */
    sb_v3 offset;               /* translation of every mesh node (double precision in the JSON) */
    bool no_sun;                /* a night scene: point lights only */
    sb_v3 lamps[256];           /* point lights (KHR_lights_punctual), positions */
    double lamp_range[256];     /* each one's range (0: none written, no limit) */
    int nlamps;
    /* the caller's own (conformance scenes): */
    unsigned char *bin;         /* buffer views so far */
    size_t bin_len;
    sb_glb_str views, accessors, materials, nodes, roots, top, used, required, images;
    int nviews, naccessors, nmaterials, nnodes, nimages;
} sb_glb_scene;

sb_glb_mesh *sb_glb_new_mesh(sb_glb_scene *s, int material);
uint32_t sb_glb_vert(sb_glb_mesh *m, double x, double y, double z, double nx, double ny, double nz);
/* The texture coordinates of the mesh's last vertex (the mesh gets a TEXCOORD_0). */
void sb_glb_uv(sb_glb_mesh *m, double u, double v);
void sb_glb_tri(sb_glb_mesh *m, uint32_t a, uint32_t b, uint32_t c);
/* A closed axis-aligned box with flat normals, counter-clockwise outside. */
void sb_glb_box(sb_glb_mesh *m, double x0, double y0, double z0, double x1, double y1, double z1);

/* The caller's own parts; each returns its index in its glTF array. */
int sb_glb_view(sb_glb_scene *s, const void *data, size_t len);
/* A vertex-attribute view with a byteStride (elements padded to a multiple of 4). */
int sb_glb_view_strided(sb_glb_scene *s, const void *data, size_t len, int stride);
int sb_glb_accessor(sb_glb_scene *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
int sb_glb_material(sb_glb_scene *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A node; root: listed in the scene. */
int sb_glb_node(sb_glb_scene *s, bool root, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* Top-level members, e.g. "\"skins\":[...]" (comma-separated, no leading comma). */
void sb_glb_top(sb_glb_scene *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* An extension named in extensionsUsed (and extensionsRequired when required). */
void sb_glb_extension(sb_glb_scene *s, const char *name, bool required);
/* An 8-bit PNG (channels 1..4, rows top-down) as a buffer view; returns its image index
 * (images are written in call order). */
int sb_glb_png(sb_glb_scene *s, int w, int h, int channels, const uint8_t *pixels);

/* Writes the scene and frees it; returns 0 on success. */
int sb_glb_write(sb_glb_scene *s, const char *path);
/* Frees a scene without writing it. */
void sb_glb_free(sb_glb_scene *s);

/* Draco compression of one mesh (scenes/glb_draco.cc, built into scenegen
 * when Draco is found): positions and normals, no quantization, into *out
 * (malloc'd); the attribute ids of POSITION and NORMAL. */
bool sb_glb_draco_encode(const float *pos, const float *nrm, uint32_t nv, const uint32_t *idx, uint32_t ni,
                         unsigned char **out, size_t *len, int *pos_id, int *nrm_id);
