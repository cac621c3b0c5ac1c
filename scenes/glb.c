/* glb.c - writing binary glTF scenes (see glb.h). */
#include "glb.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* glb.c is also built into the scene generator (no util.c): its own checked allocation. */
static void *grow(void *p, size_t n) {
    void *q = realloc(p, n);
    if (!q) {
        fprintf(stderr, "glb: out of memory (%zu bytes)\n", n);
        exit(1);
    }
    return q;
}


sb_glb_mesh *sb_glb_new_mesh(sb_glb_scene *s, int material) {
    if (s->n == s->cap) {
        s->cap = s->cap ? s->cap * 2 : 64;
        s->meshes = grow(s->meshes, (size_t)s->cap * sizeof(sb_glb_mesh));
    }
    sb_glb_mesh *m = &s->meshes[s->n++];
    memset(m, 0, sizeof *m);
    m->material = material;
    return m;
}

uint32_t sb_glb_vert(sb_glb_mesh *m, double x, double y, double z, double nx, double ny, double nz) {
    if (m->nv == m->capv) {
        m->capv = m->capv ? m->capv * 2 : 256;
        m->pos = grow(m->pos, (size_t)m->capv * 12);
        m->nrm = grow(m->nrm, (size_t)m->capv * 12);
    }
    float *p = m->pos + 3 * (size_t)m->nv, *n = m->nrm + 3 * (size_t)m->nv;
    p[0] = (float)x; p[1] = (float)y; p[2] = (float)z;
    n[0] = (float)nx; n[1] = (float)ny; n[2] = (float)nz;
    return m->nv++;
}

void sb_glb_tri(sb_glb_mesh *m, uint32_t a, uint32_t b, uint32_t c) {
    if (m->ni + 3 > m->capi) {
        m->capi = m->capi ? m->capi * 2 : 768;
        m->idx = grow(m->idx, (size_t)m->capi * 4);
    }
    m->idx[m->ni++] = a;
    m->idx[m->ni++] = b;
    m->idx[m->ni++] = c;
}

void sb_glb_box(sb_glb_mesh *m, double x0, double y0, double z0, double x1, double y1, double z1) {
    static const int faces[6][4][3] = {
        {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}, /* +x */
        {{0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {0, 0, 0}}, /* -x */
        {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}}, /* +y */
        {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, /* -y */
        {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, /* +z */
        {{1, 0, 0}, {0, 0, 0}, {0, 1, 0}, {1, 1, 0}}, /* -z */
    };
    static const double normals[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    double c[2][3] = {{x0, y0, z0}, {x1, y1, z1}};
    for (int f = 0; f < 6; f++) {
        uint32_t v[4];
        for (int k = 0; k < 4; k++)
            v[k] = sb_glb_vert(m, c[faces[f][k][0]][0], c[faces[f][k][1]][1], c[faces[f][k][2]][2], normals[f][0],
                        normals[f][1], normals[f][2]);
        sb_glb_tri(m, v[0], v[1], v[2]);
        sb_glb_tri(m, v[0], v[2], v[3]);
    }
}

/* ---- GLB writer ---- */

typedef struct {
    char *s;
    size_t len, cap;
} str;

static void put(str *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(str *b, const char *fmt, ...) {
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int n = vsnprintf(b->s ? b->s + b->len : NULL, b->s ? b->cap - b->len : 0, fmt, ap);
        va_end(ap);
        if (b->s && b->len + (size_t)n < b->cap) {
            b->len += (size_t)n;
            return;
        }
        b->cap = (b->cap + (size_t)n + 1) * 2;
        b->s = grow(b->s, b->cap);
    }
}

static const float materials[][4] = {
    {0.8f, 0.8f, 0.78f, 1}, /* 0 ground */
    {0.75f, 0.3f, 0.25f, 1}, /* 1 red */
    {0.85f, 0.75f, 0.55f, 1}, /* 2 sand */
    {0.6f, 0.65f, 0.75f, 1}, /* 3 glass-ish */
    {0.7f, 0.7f, 0.7f, 1}, /* 4 concrete */
};

int sb_glb_write(sb_glb_scene *s, const char *path) {
    str js = {0};
    size_t bin_len = 0;
    for (int i = 0; i < s->n; i++) bin_len += (size_t)s->meshes[i].nv * 24 + (size_t)s->meshes[i].ni * 4;
    unsigned char *bin = grow(NULL, bin_len ? bin_len : 1);
    size_t off = 0;
    str acc = {0}, views = {0}, meshes = {0}, nodes = {0}, roots = {0};
    for (int i = 0; i < s->n; i++) {
        const sb_glb_mesh *m = &s->meshes[i];
        float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
        for (uint32_t v = 0; v < m->nv; v++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fminf(lo[k], m->pos[3 * v + k]);
                hi[k] = fmaxf(hi[k], m->pos[3 * v + k]);
            }
        memcpy(bin + off, m->pos, (size_t)m->nv * 12);
        put(&views, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%u,\"target\":34962}", i ? "," : "", off,
            m->nv * 12);
        off += (size_t)m->nv * 12;
        memcpy(bin + off, m->nrm, (size_t)m->nv * 12);
        put(&views, ",{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%u,\"target\":34962}", off, m->nv * 12);
        off += (size_t)m->nv * 12;
        memcpy(bin + off, m->idx, (size_t)m->ni * 4);
        put(&views, ",{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%u,\"target\":34963}", off, m->ni * 4);
        off += (size_t)m->ni * 4;
        put(&acc,
            "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\","
            "\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]}",
            i ? "," : "", 3 * i, m->nv, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
        put(&acc, ",{\"bufferView\":%d,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"}", 3 * i + 1, m->nv);
        put(&acc, ",{\"bufferView\":%d,\"componentType\":5125,\"count\":%u,\"type\":\"SCALAR\"}", 3 * i + 2, m->ni);
        put(&meshes,
            "%s{\"primitives\":[{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d},\"indices\":%d,\"material\":%d}]}",
            i ? "," : "", 3 * i, 3 * i + 1, 3 * i + 2, m->material);
        put(&nodes, "%s{\"mesh\":%d,\"translation\":[%.17g,%.17g,%.17g]}", i ? "," : "", i, s->offset.x,
            s->offset.y, s->offset.z);
        put(&roots, "%s%d", i ? "," : "", i);
    }
    str lights = {0};
    int nl = 0, nn = s->n;
    if (!s->no_sun) {
        sb_quat q = sb_quat_look(sb_v3_scale(s->sun, -1), fabs(s->sun.y) > 0.99 ? sb_v3_make(0, 0, 1) : sb_v3_make(0, 1, 0));
        put(&nodes, ",{\"name\":\"sun\",\"rotation\":[%.12g,%.12g,%.12g,%.12g],"
                    "\"extensions\":{\"KHR_lights_punctual\":{\"light\":%d}}}", q.x, q.y, q.z, q.w, nl);
        put(&lights, "{\"type\":\"directional\",\"name\":\"sun\",\"color\":[1,0.97,0.9],\"intensity\":3}");
        put(&roots, ",%d", nn++);
        nl++;
    }
    for (int i = 0; i < s->nlamps; i++) {
        sb_v3 p = sb_v3_add(s->lamps[i], s->offset);
        put(&nodes, ",{\"name\":\"lamp%d\",\"translation\":[%.17g,%.17g,%.17g],"
                    "\"extensions\":{\"KHR_lights_punctual\":{\"light\":%d}}}", i, p.x, p.y, p.z, nl);
        put(&lights, "%s{\"type\":\"point\",\"name\":\"lamp%d\",\"color\":[1,0.85,0.6],\"intensity\":40}",
            nl ? "," : "", i);
        put(&roots, ",%d", nn++);
        nl++;
    }
    str mats = {0};
    for (size_t i = 0; i < sizeof materials / sizeof materials[0]; i++)
        put(&mats, "%s{\"pbrMetallicRoughness\":{\"baseColorFactor\":[%g,%g,%g,%g],\"metallicFactor\":0}}",
            i ? "," : "", materials[i][0], materials[i][1], materials[i][2], materials[i][3]);
    put(&js,
        "{\"asset\":{\"version\":\"2.0\",\"generator\":\"shadowbench scenegen\"},"
        "\"extensionsUsed\":[\"KHR_lights_punctual\"],"
        "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[%s]}},"
        "\"scene\":0,\"scenes\":[{\"nodes\":[%s]}],\"nodes\":[%s],\"meshes\":[%s],\"materials\":[%s],"
        "\"accessors\":[%s],\"bufferViews\":[%s],\"buffers\":[{\"byteLength\":%zu}]}",
        lights.s ? lights.s : "", roots.s, nodes.s, meshes.s, mats.s, acc.s, views.s, bin_len);
    while (js.len % 4) put(&js, " ");
    uint32_t json_len = (uint32_t)js.len, bin_pad = (uint32_t)((4 - bin_len % 4) % 4);
    uint32_t total = 12 + 8 + json_len + 8 + (uint32_t)bin_len + bin_pad;
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        return 1;
    }
    uint32_t hdr[3] = {0x46546C67u, 2, total};
    fwrite(hdr, 4, 3, f);
    uint32_t ch[2] = {json_len, 0x4E4F534Au};
    fwrite(ch, 4, 2, f);
    fwrite(js.s, 1, json_len, f);
    uint32_t bh[2] = {(uint32_t)bin_len + bin_pad, 0x004E4942u};
    fwrite(bh, 4, 2, f);
    fwrite(bin, 1, bin_len, f);
    static const unsigned char zeros[4] = {0};
    fwrite(zeros, 1, bin_pad, f);
    int rc = fclose(f) == 0 ? 0 : 1;
    free(bin);
    free(lights.s);
    free(js.s); free(acc.s); free(views.s); free(meshes.s); free(nodes.s); free(roots.s); free(mats.s);
    for (int i = 0; i < s->n; i++) {
        free(s->meshes[i].pos);
        free(s->meshes[i].nrm);
        free(s->meshes[i].idx);
    }
    free(s->meshes);
    s->meshes = NULL;
    s->n = s->cap = 0;
    return rc;
}

