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
        if (m->uv) m->uv = grow(m->uv, (size_t)m->capv * 8);
    }
    float *p = m->pos + 3 * (size_t)m->nv, *n = m->nrm + 3 * (size_t)m->nv;
    p[0] = (float)x; p[1] = (float)y; p[2] = (float)z;
    n[0] = (float)nx; n[1] = (float)ny; n[2] = (float)nz;
    return m->nv++;
}

void sb_glb_uv(sb_glb_mesh *m, double u, double v) {
    if (!m->uv) m->uv = calloc((size_t)m->capv * 2, sizeof(float));
    if (!m->uv || m->nv == 0) {
        fprintf(stderr, "glb: sb_glb_uv before a vertex (or out of memory)\n");
        exit(1);
    }
    m->uv[2 * (size_t)(m->nv - 1)] = (float)u;
    m->uv[2 * (size_t)(m->nv - 1) + 1] = (float)v;
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

/* ---- JSON text ---- */

static void vput(sb_glb_str *b, const char *fmt, va_list ap0) {
    for (;;) {
        va_list ap;
        va_copy(ap, ap0);
        int n = vsnprintf(b->s ? b->s + b->len : NULL, b->s ? b->cap - b->len : 0, fmt, ap);
        va_end(ap);
        if (b->s && b->len + (size_t)n < b->cap) {
            b->len += (size_t)n;
            return;
        }
        b->cap = (b->cap + (size_t)n + 1) * 2;
        b->s = grow(b->s, b->cap);
        if (b->len == 0) b->s[0] = 0;
    }
}

static void put(sb_glb_str *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(sb_glb_str *b, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vput(b, fmt, ap);
    va_end(ap);
}

/* Appends one JSON item to a list: a comma first unless it is the first. */
static void item(sb_glb_str *b, const char *fmt, va_list ap) {
    if (b->len) put(b, ",");
    vput(b, fmt, ap);
}

static const char *text(const sb_glb_str *b) { return b->s ? b->s : ""; }

/* ---- the caller's own parts ---- */

static size_t append_bin(sb_glb_scene *s, const void *data, size_t len) {
    size_t off = s->bin_len;
    s->bin = grow(s->bin, off + len + 4);
    memcpy(s->bin + off, data, len);
    s->bin_len = off + len;
    while (s->bin_len % 4) s->bin[s->bin_len++] = 0; /* views start 4-aligned */
    return off;
}

/* target: 34962 vertex data, 34963 indices, 0 none; stride 0: none given */
static int view_with(sb_glb_scene *s, const void *data, size_t len, int target, int stride) {
    size_t off = append_bin(s, data, len);
    char tgt[64] = "";
    if (target && stride) snprintf(tgt, sizeof tgt, ",\"byteStride\":%d,\"target\":%d", stride, target);
    else if (target) snprintf(tgt, sizeof tgt, ",\"target\":%d", target);
    put(&s->views, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu%s}", s->nviews ? "," : "", off, len, tgt);
    return s->nviews++;
}

static int view_for(sb_glb_scene *s, const void *data, size_t len, int target) {
    return view_with(s, data, len, target, 0);
}

int sb_glb_view(sb_glb_scene *s, const void *data, size_t len) { return view_for(s, data, len, 0); }

int sb_glb_view_strided(sb_glb_scene *s, const void *data, size_t len, int stride) {
    return view_with(s, data, len, 34962, stride);
}

int sb_glb_accessor(sb_glb_scene *s, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    item(&s->accessors, fmt, ap);
    va_end(ap);
    return s->naccessors++;
}

int sb_glb_material(sb_glb_scene *s, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    item(&s->materials, fmt, ap);
    va_end(ap);
    return 5 + s->nmaterials++;
}

int sb_glb_node(sb_glb_scene *s, bool root, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    item(&s->nodes, fmt, ap);
    va_end(ap);
    if (root) put(&s->roots, "%s%d", s->roots.len ? "," : "", s->nnodes);
    return s->nnodes++;
}

void sb_glb_top(sb_glb_scene *s, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    item(&s->top, fmt, ap);
    va_end(ap);
}

void sb_glb_extension(sb_glb_scene *s, const char *name, bool required) {
    put(&s->used, ",\"%s\"", name);
    if (required) put(&s->required, "%s\"%s\"", s->required.len ? "," : "", name);
}

/* ---- PNG: stored (uncompressed) deflate blocks, enough for test textures ---- */

static uint32_t crc_update(uint32_t c, const unsigned char *p, size_t n) {
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return c;
}

static void be32(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)(v >> 24), p[1] = (unsigned char)(v >> 16), p[2] = (unsigned char)(v >> 8), p[3] = (unsigned char)v;
}

static void chunk(sb_glb_str *out, const char *type, const unsigned char *data, size_t len) {
    unsigned char hdr[8];
    be32(hdr, (uint32_t)len);
    memcpy(hdr + 4, type, 4);
    size_t need = out->len + 12 + len;
    if (need > out->cap) out->s = grow(out->s, out->cap = need * 2);
    memcpy(out->s + out->len, hdr, 8);
    if (len) memcpy(out->s + out->len + 8, data, len);
    uint32_t crc = crc_update(0xFFFFFFFFu, hdr + 4, 4);
    crc = crc_update(crc, data, len) ^ 0xFFFFFFFFu;
    be32((unsigned char *)out->s + out->len + 8 + len, crc);
    out->len = need;
}

int sb_glb_png(sb_glb_scene *s, int w, int h, int channels, const uint8_t *pixels) {
    static const unsigned char types[5] = {0, 0, 4, 2, 6};
    size_t row = (size_t)w * channels + 1, raw_len = row * h;
    unsigned char *raw = grow(NULL, raw_len);
    for (int y = 0; y < h; y++) {
        raw[y * row] = 0; /* filter: none */
        memcpy(raw + y * row + 1, pixels + (size_t)y * w * channels, row - 1);
    }
    size_t blocks = raw_len / 65535 + 1, z_len = 2 + raw_len + 5 * blocks + 4;
    unsigned char *z = grow(NULL, z_len), *q = z;
    *q++ = 0x78, *q++ = 0x01;
    uint32_t a = 1, b = 0;
    for (size_t off = 0; off < raw_len || off == 0;) {
        size_t n = raw_len - off > 65535 ? 65535 : raw_len - off;
        *q++ = off + n == raw_len ? 1 : 0;
        *q++ = (unsigned char)n, *q++ = (unsigned char)(n >> 8), *q++ = (unsigned char)~n, *q++ = (unsigned char)(~n >> 8);
        memcpy(q, raw + off, n);
        for (size_t i = 0; i < n; i++) a = (a + raw[off + i]) % 65521, b = (b + a) % 65521;
        q += n;
        off += n;
        if (n == 0) break;
    }
    be32(q, b << 16 | a);
    q += 4;
    sb_glb_str png = {0};
    png.s = grow(NULL, png.cap = 64 + (size_t)(q - z));
    memcpy(png.s, "\x89PNG\r\n\x1a\n", 8);
    png.len = 8;
    unsigned char ihdr[13];
    be32(ihdr, (uint32_t)w), be32(ihdr + 4, (uint32_t)h);
    ihdr[8] = 8, ihdr[9] = types[channels], ihdr[10] = ihdr[11] = ihdr[12] = 0;
    chunk(&png, "IHDR", ihdr, 13);
    chunk(&png, "IDAT", z, (size_t)(q - z));
    chunk(&png, "IEND", NULL, 0);
    int view = sb_glb_view(s, png.s, png.len);
    free(png.s);
    free(z);
    free(raw);
    put(&s->images, "%s{\"bufferView\":%d,\"mimeType\":\"image/png\"}", s->nimages ? "," : "", view);
    return s->nimages++;
}

/* ---- the meshes ---- */

static const float materials[][4] = {
    {0.8f, 0.8f, 0.78f, 1}, /* 0 ground */
    {0.75f, 0.3f, 0.25f, 1}, /* 1 red */
    {0.85f, 0.75f, 0.55f, 1}, /* 2 sand */
    {0.6f, 0.65f, 0.75f, 1}, /* 3 glass-ish */
    {0.7f, 0.7f, 0.7f, 1}, /* 4 concrete */
};

static void bounds(const sb_glb_mesh *m, float lo[3], float hi[3]) {
    for (int k = 0; k < 3; k++) lo[k] = 1e30f, hi[k] = -1e30f;
    for (uint32_t v = 0; v < m->nv; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], m->pos[3 * v + k]);
            hi[k] = fmaxf(hi[k], m->pos[3 * v + k]);
        }
}

/* A mesh's data as views and accessors; *attrs gets its attribute map. */
static void mesh_data(sb_glb_scene *s, const sb_glb_mesh *m, sb_glb_str *attrs, sb_glb_str *ext, int *indices) {
    float lo[3], hi[3];
    bounds(m, lo, hi);
    int draco_view = -1, pos_id = 0, nrm_id = 0;
    if (m->draco) {
        unsigned char *dr;
        size_t dlen;
        if (!sb_glb_draco_encode(m->pos, m->nrm, m->nv, m->idx, m->ni, &dr, &dlen, &pos_id, &nrm_id)) {
            fprintf(stderr, "glb: Draco encoding failed\n");
            exit(1);
        }
        draco_view = sb_glb_view(s, dr, dlen);
        free(dr);
    }
    int vp = m->draco ? -1 : view_for(s, m->pos, (size_t)m->nv * 12, 34962);
    int vn = m->draco ? -1 : view_for(s, m->nrm, (size_t)m->nv * 12, 34962);
    int vi = m->draco ? -1 : view_for(s, m->idx, (size_t)m->ni * 4, 34963);
    char view[32] = "";
#define VIEW(v) ((v) >= 0 ? (snprintf(view, sizeof view, "\"bufferView\":%d,", (v)), view) : "")
    int ap = sb_glb_accessor(s, "{%s\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\",\"min\":[%.9g,%.9g,%.9g],"
                             "\"max\":[%.9g,%.9g,%.9g]}", VIEW(vp), m->nv, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    int an = sb_glb_accessor(s, "{%s\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"}", VIEW(vn), m->nv);
    *indices = sb_glb_accessor(s, "{%s\"componentType\":5125,\"count\":%u,\"type\":\"SCALAR\"}", VIEW(vi), m->ni);
#undef VIEW
    put(attrs, "\"POSITION\":%d,\"NORMAL\":%d", ap, an);
    if (m->uv) {
        int vu = view_for(s, m->uv, (size_t)m->nv * 8, 34962);
        put(attrs, ",\"TEXCOORD_0\":%d",
            sb_glb_accessor(s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":%u,\"type\":\"VEC2\"}", vu, m->nv));
    }
    if (m->prim_extra[0]) put(attrs, ",%s", m->prim_extra);
    if (m->draco)
        put(ext, ",\"extensions\":{\"KHR_draco_mesh_compression\":{\"bufferView\":%d,\"attributes\":{\"POSITION\":%d,"
            "\"NORMAL\":%d}}}", draco_view, pos_id, nrm_id);
}

static void write_meshes(sb_glb_scene *s, sb_glb_str *meshes) {
    for (int i = 0; i < s->n; i++) {
        const sb_glb_mesh *m = &s->meshes[i];
        if (m->custom[0]) {
            put(meshes, "%s{\"primitives\":[%s]}", i ? "," : "", m->custom);
        } else {
            sb_glb_str attrs = {0}, ext = {0};
            int indices;
            mesh_data(s, m, &attrs, &ext, &indices);
            put(meshes, "%s{\"primitives\":[{\"attributes\":{%s},\"indices\":%d,\"material\":%d%s}]}", i ? "," : "",
                text(&attrs), indices, m->material, text(&ext));
            free(attrs.s);
            free(ext.s);
        }
        if (m->no_node) continue;
        sb_glb_node(s, true, "{\"mesh\":%d,\"translation\":[%.17g,%.17g,%.17g]%s%s}", i, s->offset.x, s->offset.y,
                    s->offset.z, m->node_extra[0] ? "," : "", m->node_extra);
    }
}

static void write_lights(sb_glb_scene *s, sb_glb_str *lights) {
    int nl = 0;
    if (!s->no_sun) {
        sb_quat q = sb_quat_look(sb_v3_scale(s->sun, -1), fabs(s->sun.y) > 0.99 ? sb_v3_make(0, 0, 1) : sb_v3_make(0, 1, 0));
        sb_glb_node(s, true, "{\"name\":\"sun\",\"rotation\":[%.12g,%.12g,%.12g,%.12g],"
                             "\"extensions\":{\"KHR_lights_punctual\":{\"light\":%d}}}", q.x, q.y, q.z, q.w, nl);
        put(lights, "{\"type\":\"directional\",\"name\":\"sun\",\"color\":[1,0.97,0.9],\"intensity\":3}");
        nl++;
    }
    for (int i = 0; i < s->nlamps; i++) {
        sb_v3 p = sb_v3_add(s->lamps[i], s->offset);
        sb_glb_node(s, true, "{\"name\":\"lamp%d\",\"translation\":[%.17g,%.17g,%.17g],"
                             "\"extensions\":{\"KHR_lights_punctual\":{\"light\":%d}}}", i, p.x, p.y, p.z, nl);
        char range[48] = "";
        if (s->lamp_range[i] > 0) snprintf(range, sizeof range, ",\"range\":%.17g", s->lamp_range[i]);
        put(lights, "%s{\"type\":\"point\",\"name\":\"lamp%d\",\"color\":[1,0.85,0.6],\"intensity\":40%s}", nl ? "," : "", i,
            range);
        nl++;
    }
}

void sb_glb_free(sb_glb_scene *s) {
    for (int i = 0; i < s->n; i++) {
        free(s->meshes[i].pos);
        free(s->meshes[i].nrm);
        free(s->meshes[i].uv);
        free(s->meshes[i].idx);
    }
    free(s->meshes);
    sb_glb_str *strs[] = {&s->views, &s->accessors, &s->materials, &s->nodes, &s->roots, &s->top, &s->used,
                          &s->required, &s->images};
    for (size_t i = 0; i < sizeof strs / sizeof strs[0]; i++) free(strs[i]->s);
    free(s->bin);
    memset(s, 0, sizeof *s);
}

static int write_file(const char *path, const sb_glb_str *js, const unsigned char *bin, size_t bin_len) {
    uint32_t json_len = (uint32_t)js->len, bin_pad = (uint32_t)((4 - bin_len % 4) % 4);
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
    fwrite(js->s, 1, json_len, f);
    uint32_t bh[2] = {(uint32_t)bin_len + bin_pad, 0x004E4942u};
    fwrite(bh, 4, 2, f);
    fwrite(bin, 1, bin_len, f);
    static const unsigned char zeros[4] = {0};
    fwrite(zeros, 1, bin_pad, f);
    return fclose(f) == 0 ? 0 : 1;
}

int sb_glb_write(sb_glb_scene *s, const char *path) {
    sb_glb_str meshes = {0}, lights = {0}, mats = {0}, js = {0};
    write_meshes(s, &meshes);
    write_lights(s, &lights);
    for (size_t i = 0; i < sizeof materials / sizeof materials[0]; i++)
        put(&mats, "%s{\"pbrMetallicRoughness\":{\"baseColorFactor\":[%g,%g,%g,%g],\"metallicFactor\":0}}",
            i ? "," : "", materials[i][0], materials[i][1], materials[i][2], materials[i][3]);
    if (s->materials.len) put(&mats, ",%s", text(&s->materials));
    put(&js,
        "{\"asset\":{\"version\":\"2.0\",\"generator\":\"shadowbench scenegen\"},"
        "\"extensionsUsed\":[\"KHR_lights_punctual\"%s],%s%s%s"
        "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[%s]}},"
        "\"scene\":0,\"scenes\":[{\"nodes\":[%s]}],\"nodes\":[%s],\"meshes\":[%s],\"materials\":[%s],",
        text(&s->used), s->required.len ? "\"extensionsRequired\":[" : "", text(&s->required),
        s->required.len ? "]," : "", text(&lights), text(&s->roots), text(&s->nodes), text(&meshes), text(&mats));
    if (s->images.len) put(&js, "\"images\":[%s],", text(&s->images));
    if (s->top.len) put(&js, "%s,", text(&s->top));
    put(&js, "\"accessors\":[%s],\"bufferViews\":[%s],\"buffers\":[{\"byteLength\":%zu}]}", text(&s->accessors),
        text(&s->views), s->bin_len);
    while (js.len % 4) put(&js, " ");
    int rc = write_file(path, &js, s->bin, s->bin_len);
    free(js.s);
    free(meshes.s);
    free(lights.s);
    free(mats.s);
    sb_glb_free(s);
    return rc;
}
