/* gltf_draco.h - KHR_draco_mesh_compression decoding (scenes/gltf_draco.cc). */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "util.h"

#define SB_DRACO_MAX_ATTRS 16

typedef struct sb_draco_out {
    uint32_t *indices;          /* triangle list into the decoded points */
    size_t index_count;
    uint32_t points;
    double *values[SB_DRACO_MAX_ATTRS]; /* attribute a: points x ncomp[a] */
} sb_draco_out;

/* Decodes a Draco mesh and the attributes with the unique ids ids[0..nattr)
 * (the extension's attribute map), each as ncomp[a] floats a point. False
 * with the reason in why on a bad bitstream or a build without Draco. */
bool sb_draco_decode(const unsigned char *data, size_t len, const int *ids, const int *ncomp, int nattr,
                     sb_draco_out *out, char *why, size_t why_len);
void sb_draco_free(sb_draco_out *out);
