/* glb.h - a small writer of binary glTF (.glb) scenes made of meshes and a
 * KHR_lights_punctual sun: the bundled scenes (scenegen) and the stress
 * battery's generated cases are written with it and read back through the
 * normal loader. */
#pragma once
#include <stdint.h>

#include "sbmath.h"

typedef struct sb_glb_mesh {
    float *pos, *nrm;
    uint32_t nv, capv;
    uint32_t *idx;
    uint32_t ni, capi;
    int material;               /* index into the fixed material list (0 ground ... 4 concrete) */
} sb_glb_mesh;

typedef struct sb_glb_scene {
    sb_glb_mesh *meshes;
    int n, cap;
    sb_v3 sun;                  /* toward the sun */
    sb_v3 offset;               /* translation of every mesh node (double precision in the JSON) */
    bool no_sun;                /* a night scene: point lights only */
    sb_v3 lamps[16];            /* point lights (KHR_lights_punctual), positions */
    int nlamps;
} sb_glb_scene;

sb_glb_mesh *sb_glb_new_mesh(sb_glb_scene *s, int material);
uint32_t sb_glb_vert(sb_glb_mesh *m, double x, double y, double z, double nx, double ny, double nz);
void sb_glb_tri(sb_glb_mesh *m, uint32_t a, uint32_t b, uint32_t c);
/* A closed axis-aligned box with flat normals, counter-clockwise outside. */
void sb_glb_box(sb_glb_mesh *m, double x0, double y0, double z0, double x1, double y1, double z1);
/* Writes the scene and frees its meshes; returns 0 on success. */
int sb_glb_write(sb_glb_scene *s, const char *path);
