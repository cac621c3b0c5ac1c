/* conformance.c - the conformance set (see conformance.h): one small scene a
 * glTF feature, written with glb.c, each with a path looking down on it. */
#include "conformance.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "glb.h"
#include "sbmath.h"

static void floor_slab(sb_glb_scene *s) {
    s->sun = sb_sun_dir(SB_CONF_SUN_AZ, SB_CONF_SUN_EL);
    sb_glb_box(sb_glb_new_mesh(s, 0), -20, -0.5, -20, 20, 0, 20);
}

/* A horizontal rectangle at height y, its front face up or down, with texture
 * coordinates spanning [0, 1] over it when uv. */
static void rect(sb_glb_mesh *m, const double r[4], double y, bool up, bool uv) {
    const double x[4] = {r[0], r[0], r[1], r[1]}, z[4] = {r[2], r[3], r[3], r[2]};
    uint32_t v[4];
    for (int k = 0; k < 4; k++) {
        v[k] = sb_glb_vert(m, x[k], y, z[k], 0, up ? 1 : -1, 0);
        if (uv) sb_glb_uv(m, (x[k] - r[0]) / (r[1] - r[0]), (z[k] - r[2]) / (r[3] - r[2]));
    }
    if (up) { /* (x0,z0) -> (x0,z1) -> (x1,z1) turns counter-clockwise seen from +y */
        sb_glb_tri(m, v[0], v[1], v[2]);
        sb_glb_tri(m, v[0], v[2], v[3]);
    } else {
        sb_glb_tri(m, v[0], v[2], v[1]);
        sb_glb_tri(m, v[0], v[3], v[2]);
    }
}

static int finish(sb_glb_scene *s, const char *dir, const char *name) {
    char p[4096];
    snprintf(p, sizeof p, "%s/%s.glb", dir, name);
    int rc = sb_glb_write(s, p);
    snprintf(p, sizeof p, "%s/%s.path", dir, name);
    FILE *f = fopen(p, "w");
    if (!f) return 1;
    fprintf(f, "# %s: looking down on the casters from two sides\nfov 60\nlook 0   0 16 14    0 1 0\n"
               "look 4   12 16 6    0 1 0\n", name);
    return rc | (fclose(f) != 0);
}

static int double_sided(const char *dir) {
    sb_glb_scene s = {0};
    floor_slab(&s);
    const double a[4] = SB_CONF_RECT_A, b[4] = SB_CONF_RECT_B;
    int two = sb_glb_material(&s, "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.6,0.6,0.9,1]},\"doubleSided\":true}");
    int one = sb_glb_material(&s, "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.9,0.6,0.6,1]}}");
    rect(sb_glb_new_mesh(&s, two), a, SB_CONF_H, false, false);
    rect(sb_glb_new_mesh(&s, one), b, SB_CONF_H, false, false);
    return finish(&s, dir, "conf-double-sided");
}

static int blend(const char *dir) {
    sb_glb_scene s = {0};
    floor_slab(&s);
    const double a[4] = SB_CONF_RECT_A, b[4] = SB_CONF_RECT_B;
    const char *fmt = "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.7,0.9,%g]},\"alphaMode\":\"BLEND\"}";
    rect(sb_glb_new_mesh(&s, sb_glb_material(&s, fmt, SB_CONF_BLEND_ALPHA_A)), a, SB_CONF_H, true, false);
    rect(sb_glb_new_mesh(&s, sb_glb_material(&s, fmt, SB_CONF_BLEND_ALPHA_B)), b, SB_CONF_H, true, false);
    return finish(&s, dir, "conf-blend");
}

static int alpha_card(const char *dir) {
    sb_glb_scene s = {0};
    floor_slab(&s);
    uint8_t px[4 * 4 * 4];
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            uint8_t *p = px + 4 * (j * 4 + i);
            p[0] = p[1] = p[2] = 200;
            p[3] = (i + j) % 2 == 0 ? 255 : 0;
        }
    int img = sb_glb_png(&s, 4, 4, 4, px);
    sb_glb_top(&s, "\"samplers\":[{\"magFilter\":9728,\"minFilter\":9728,\"wrapS\":10497,\"wrapT\":10497}],"
                   "\"textures\":[{\"sampler\":0,\"source\":%d}]", img);
    sb_glb_extension(&s, "KHR_texture_transform", false);
    int m = sb_glb_material(&s, "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,1],\"baseColorTexture\":"
                                "{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"scale\":[2,2]}}}},"
                                "\"alphaMode\":\"MASK\",\"alphaCutoff\":0.5}");
    const double c[4] = {-SB_CONF_CARD, SB_CONF_CARD, -SB_CONF_CARD, SB_CONF_CARD};
    rect(sb_glb_new_mesh(&s, m), c, SB_CONF_H, true, true);
    s.lamps[0] = sb_v3_make(SB_CONF_CARD_LAMP_X, SB_CONF_CARD_LAMP_Y, SB_CONF_CARD_LAMP_Z);
    s.nlamps = 1;
    return finish(&s, dir, "conf-alpha-card");
}

/* Joints and weights for every vertex of the arm: segment k's 24 vertices on joint k. */
static void arm_weights(sb_glb_scene *s, sb_glb_mesh *m) {
    uint8_t j[48 * 4] = {0};
    float w[48 * 4] = {0};
    for (int v = 0; v < 48; v++) {
        j[4 * v] = (uint8_t)(v / 24);
        w[4 * v] = 1;
    }
    int aj = sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5121,\"count\":48,\"type\":\"VEC4\"}",
                             sb_glb_view_strided(s, j, sizeof j, 4));
    int aw = sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":48,\"type\":\"VEC4\"}",
                             sb_glb_view_strided(s, w, sizeof w, 16));
    snprintf(m->prim_extra, sizeof m->prim_extra, "\"JOINTS_0\":%d,\"WEIGHTS_0\":%d", aj, aw);
}

static int skin(const char *dir) {
    sb_glb_scene s = {0};
    floor_slab(&s);
    const double L = SB_CONF_ARM_LEN, h = SB_CONF_H, q = sqrt(0.5);
    int j1 = sb_glb_node(&s, false, "{\"name\":\"elbow\",\"translation\":[%g,0,0],\"rotation\":[0,0,%.17g,%.17g]}", L, q, q);
    int j0 = sb_glb_node(&s, true, "{\"name\":\"shoulder\",\"translation\":[0,%g,0],\"children\":[%d]}", h, j1);
    const float ibm[32] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, (float)-h, 0, 1,
                           1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, (float)-L, (float)-h, 0, 1};
    int aibm = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":2,\"type\":\"MAT4\"}",
                               sb_glb_view(&s, ibm, sizeof ibm));
    const float times[2] = {0, 1}, rot[8] = {0, 0, 0, 1, 0, 0, (float)q, (float)q};
    int at = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\","
                                 "\"min\":[0],\"max\":[1]}", sb_glb_view(&s, times, sizeof times));
    int ar = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":2,\"type\":\"VEC4\"}",
                             sb_glb_view(&s, rot, sizeof rot));
    sb_glb_top(&s, "\"skins\":[{\"inverseBindMatrices\":%d,\"joints\":[%d,%d]}],\"animations\":[{\"channels\":"
                   "[{\"sampler\":0,\"target\":{\"node\":%d,\"path\":\"rotation\"}}],\"samplers\":[{\"input\":%d,"
                   "\"output\":%d,\"interpolation\":\"LINEAR\"}]}]", aibm, j0, j1, j1, at, ar);
    sb_glb_mesh *m = sb_glb_new_mesh(&s, 1);
    sb_glb_box(m, 0, h - 0.5, -0.5, L, h + 0.5, 0.5);
    sb_glb_box(m, L, h - 0.5, -0.5, 2 * L, h + 0.5, 0.5);
    arm_weights(&s, m);
    snprintf(m->node_extra, sizeof m->node_extra, "\"skin\":0");
    return finish(&s, dir, "conf-skin");
}

static int instanced(const char *dir) {
    sb_glb_scene s = {0};
    floor_slab(&s);
    float t[3 * SB_CONF_INSTANCES], sc[3 * SB_CONF_INSTANCES];
    for (int k = 0; k < SB_CONF_INSTANCES; k++) {
        t[3 * k] = (float)(-8 + 4 * k), t[3 * k + 1] = 0, t[3 * k + 2] = 0;
        sc[3 * k] = 1, sc[3 * k + 1] = (float)(1 + 0.5 * k), sc[3 * k + 2] = 1;
    }
    int at = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"}",
                             sb_glb_view(&s, t, sizeof t), SB_CONF_INSTANCES);
    int as = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\"}",
                             sb_glb_view(&s, sc, sizeof sc), SB_CONF_INSTANCES);
    sb_glb_mesh *m = sb_glb_new_mesh(&s, 4);
    sb_glb_box(m, -0.5, 0, -0.5, 0.5, 1, 0.5);
    m->no_node = true;
    sb_glb_node(&s, true, "{\"mesh\":%d,\"extensions\":{\"EXT_mesh_gpu_instancing\":{\"attributes\":"
                          "{\"TRANSLATION\":%d,\"SCALE\":%d}}}}", s.n - 1, at, as);
    sb_glb_extension(&s, "EXT_mesh_gpu_instancing", true);
    return finish(&s, dir, "conf-instanced");
}

/* Box 1: positions as normalized int16 in [-1, 1] (stride 8), normals as
 * normalized int8 (stride 4), scaled into place by its node. */
static void quantized_box(sb_glb_scene *s) {
    sb_glb_scene tmp = {0};
    sb_glb_mesh *b = sb_glb_new_mesh(&tmp, 0);
    sb_glb_box(b, -1, -1, -1, 1, 1, 1);
    int16_t pos[24 * 4] = {0};
    int8_t nrm[24 * 4] = {0};
    uint16_t idx[36];
    for (int v = 0; v < 24; v++)
        for (int k = 0; k < 3; k++) {
            pos[4 * v + k] = (int16_t)lrint(b->pos[3 * v + k] * 32767);
            nrm[4 * v + k] = (int8_t)lrint(b->nrm[3 * v + k] * 127);
        }
    for (int i = 0; i < 36; i++) idx[i] = (uint16_t)b->idx[i];
    int ap = sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5122,\"normalized\":true,\"count\":24,"
                                "\"type\":\"VEC3\",\"min\":[-32767,-32767,-32767],\"max\":[32767,32767,32767]}",
                             sb_glb_view_strided(s, pos, sizeof pos, 8));
    int an = sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5120,\"normalized\":true,\"count\":24,"
                                "\"type\":\"VEC3\"}", sb_glb_view_strided(s, nrm, sizeof nrm, 4));
    int ai = sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5123,\"count\":36,\"type\":\"SCALAR\"}",
                             sb_glb_view(s, idx, sizeof idx));
    sb_glb_mesh *m = sb_glb_new_mesh(s, 4);
    m->no_node = true;
    snprintf(m->custom, sizeof m->custom, "{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d},\"indices\":%d,\"material\":4}",
             ap, an, ai);
    sb_glb_node(s, true, "{\"mesh\":%d,\"translation\":[-4,1,0],\"scale\":[2,1,2]}", s->n - 1);
    sb_glb_free(&tmp);
}

/* Box 2: a POSITION accessor without a buffer view, every element from its sparse values. */
static void sparse_box(sb_glb_scene *s) {
    sb_glb_scene tmp = {0};
    sb_glb_mesh *b = sb_glb_new_mesh(&tmp, 0);
    sb_glb_box(b, 2, 0, -2, 6, 2, 2);
    uint8_t which[24];
    for (int v = 0; v < 24; v++) which[v] = (uint8_t)v;
    int vi = sb_glb_view(s, which, sizeof which), vv = sb_glb_view(s, b->pos, 24 * 12);
    int ap = sb_glb_accessor(s, "{\"componentType\":5126,\"count\":24,\"type\":\"VEC3\",\"min\":[2,0,-2],\"max\":[6,2,2],"
                                "\"sparse\":{\"count\":24,\"indices\":{\"bufferView\":%d,\"componentType\":5121},"
                                "\"values\":{\"bufferView\":%d}}}", vi, vv);
    int an = sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":24,\"type\":\"VEC3\"}",
                             sb_glb_view_strided(s, b->nrm, 24 * 12, 12));
    int ai = sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5125,\"count\":36,\"type\":\"SCALAR\"}",
                             sb_glb_view(s, b->idx, 36 * 4));
    sb_glb_mesh *m = sb_glb_new_mesh(s, 1);
    m->no_node = true;
    snprintf(m->custom, sizeof m->custom, "{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d},\"indices\":%d,\"material\":1}",
             ap, an, ai);
    sb_glb_node(s, true, "{\"mesh\":%d}", s->n - 1);
    sb_glb_free(&tmp);
}

static int quantized(const char *dir) {
    sb_glb_scene s = {0};
    floor_slab(&s);
    quantized_box(&s);
    sparse_box(&s);
    sb_glb_extension(&s, "KHR_mesh_quantization", true);
    return finish(&s, dir, "conf-quantized");
}

/* A wall that faces a lamp and not the sun: a shadow pass for the lamp must
 * keep it, one for the sun must not. */
static int lamp_wall(const char *dir) {
    sb_glb_scene s = {0};
    floor_slab(&s);
    sb_glb_mesh *m = sb_glb_new_mesh(&s, sb_glb_material(&s, "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.7,0.5,1]}}"));
    const double y[4] = {0.5, 0.5, 3.5, 3.5}, z[4] = {-2, 2, 2, -2};
    uint32_t v[4];
    for (int k = 0; k < 4; k++) v[k] = sb_glb_vert(m, 0, y[k], z[k], -1, 0, 0);
    sb_glb_tri(m, v[0], v[1], v[2]); /* counter-clockwise seen from -x */
    sb_glb_tri(m, v[0], v[2], v[3]);
    s.lamps[0] = sb_v3_make(SB_CONF_LAMP_X, SB_CONF_LAMP_Y, 0);
    s.nlamps = 1;
    return finish(&s, dir, "conf-lamp-wall");
}

int sb_conformance_write(const char *dir) {
    return double_sided(dir) | blend(dir) | alpha_card(dir) | skin(dir) | instanced(dir) | quantized(dir) |
           lamp_wall(dir);
}
