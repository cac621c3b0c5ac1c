/* scenegen.c - writes the bundled scenes (.glb with a KHR_lights_punctual sun)
 * and their fly-through paths, deterministically (no randomness beyond a
 * fixed-seed LCG). Run by the build: scenegen OUTDIR.
 *
 *   plane-box  a 2x2x2 box on a 40x40 slab: analytic shadows for tests
 *   desert     wide flat terrain, ~6000 low boxy buildings (>200k triangles)
 *   towers     a dense block of skyscrapers with setbacks and narrow streets
 *   overhangs  cantilevered buildings and bridges over open ground, far views */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sbmath.h"

typedef struct {
    float *pos, *nrm;
    uint32_t nv, capv;
    uint32_t *idx;
    uint32_t ni, capi;
    int material;
} mesh;

typedef struct {
    mesh *meshes;
    int n, cap;
    sb_v3 sun;          /* toward the sun */
} scene;

static uint32_t g_seed = 12345u;
static double rnd(void) { /* deterministic LCG in [0,1) */
    g_seed = g_seed * 1664525u + 1013904223u;
    return (g_seed >> 8) / 16777216.0;
}

static mesh *new_mesh(scene *s, int material) {
    if (s->n == s->cap) {
        s->cap = s->cap ? s->cap * 2 : 64;
        s->meshes = realloc(s->meshes, (size_t)s->cap * sizeof(mesh));
    }
    mesh *m = &s->meshes[s->n++];
    memset(m, 0, sizeof *m);
    m->material = material;
    return m;
}

static uint32_t vert(mesh *m, double x, double y, double z, double nx, double ny, double nz) {
    if (m->nv == m->capv) {
        m->capv = m->capv ? m->capv * 2 : 256;
        m->pos = realloc(m->pos, (size_t)m->capv * 12);
        m->nrm = realloc(m->nrm, (size_t)m->capv * 12);
    }
    float *p = m->pos + 3 * (size_t)m->nv, *n = m->nrm + 3 * (size_t)m->nv;
    p[0] = (float)x; p[1] = (float)y; p[2] = (float)z;
    n[0] = (float)nx; n[1] = (float)ny; n[2] = (float)nz;
    return m->nv++;
}

static void tri(mesh *m, uint32_t a, uint32_t b, uint32_t c) {
    if (m->ni + 3 > m->capi) {
        m->capi = m->capi ? m->capi * 2 : 768;
        m->idx = realloc(m->idx, (size_t)m->capi * 4);
    }
    m->idx[m->ni++] = a;
    m->idx[m->ni++] = b;
    m->idx[m->ni++] = c;
}

/* A closed axis-aligned box with flat normals, counter-clockwise outside. */
static void box(mesh *m, double x0, double y0, double z0, double x1, double y1, double z1) {
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
            v[k] = vert(m, c[faces[f][k][0]][0], c[faces[f][k][1]][1], c[faces[f][k][2]][2], normals[f][0],
                        normals[f][1], normals[f][2]);
        tri(m, v[0], v[1], v[2]);
        tri(m, v[0], v[2], v[3]);
    }
}

static double terrain_h(double x, double z) {
    return 1.2 * sin(x / 37.0) * cos(z / 53.0) + 0.6 * sin(x / 13.0 + z / 17.0);
}

/* A terrain tile of cells x cells quads with smooth normals, as a closed slab skirt-less surface. */
static void terrain_tile(mesh *m, double x0, double z0, double size, int cells) {
    uint32_t base = m->nv;
    double d = size / cells, e = 0.01;
    for (int j = 0; j <= cells; j++)
        for (int i = 0; i <= cells; i++) {
            double x = x0 + i * d, z = z0 + j * d;
            double hx = (terrain_h(x + e, z) - terrain_h(x - e, z)) / (2 * e);
            double hz = (terrain_h(x, z + e) - terrain_h(x, z - e)) / (2 * e);
            sb_v3 n = sb_v3_norm(sb_v3_make(-hx, 1, -hz));
            vert(m, x, terrain_h(x, z), z, n.x, n.y, n.z);
        }
    for (int j = 0; j < cells; j++)
        for (int i = 0; i < cells; i++) {
            uint32_t a = base + j * (cells + 1) + i, b = a + 1, c = a + cells + 1, dd = c + 1;
            tri(m, a, c, b);
            tri(m, b, c, dd);
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
        b->s = realloc(b->s, b->cap);
    }
}

static const float materials[][4] = {
    {0.8f, 0.8f, 0.78f, 1}, /* 0 ground */
    {0.75f, 0.3f, 0.25f, 1}, /* 1 red */
    {0.85f, 0.75f, 0.55f, 1}, /* 2 sand */
    {0.6f, 0.65f, 0.75f, 1}, /* 3 glass-ish */
    {0.7f, 0.7f, 0.7f, 1}, /* 4 concrete */
};

static int write_glb(const scene *s, const char *path) {
    str js = {0};
    size_t bin_len = 0;
    for (int i = 0; i < s->n; i++) bin_len += (size_t)s->meshes[i].nv * 24 + (size_t)s->meshes[i].ni * 4;
    unsigned char *bin = malloc(bin_len ? bin_len : 1);
    size_t off = 0;
    str acc = {0}, views = {0}, meshes = {0}, nodes = {0}, roots = {0};
    for (int i = 0; i < s->n; i++) {
        const mesh *m = &s->meshes[i];
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
        put(&nodes, "%s{\"mesh\":%d}", i ? "," : "", i);
        put(&roots, "%s%d", i ? "," : "", i);
    }
    sb_quat q = sb_quat_look(sb_v3_scale(s->sun, -1), fabs(s->sun.y) > 0.99 ? sb_v3_make(0, 0, 1) : sb_v3_make(0, 1, 0));
    put(&nodes, ",{\"name\":\"sun\",\"rotation\":[%.12g,%.12g,%.12g,%.12g],"
                "\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}", q.x, q.y, q.z, q.w);
    put(&roots, ",%d", s->n);
    str mats = {0};
    for (size_t i = 0; i < sizeof materials / sizeof materials[0]; i++)
        put(&mats, "%s{\"pbrMetallicRoughness\":{\"baseColorFactor\":[%g,%g,%g,%g],\"metallicFactor\":0}}",
            i ? "," : "", materials[i][0], materials[i][1], materials[i][2], materials[i][3]);
    put(&js,
        "{\"asset\":{\"version\":\"2.0\",\"generator\":\"shadowbench scenegen\"},"
        "\"extensionsUsed\":[\"KHR_lights_punctual\"],"
        "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"directional\",\"name\":\"sun\","
        "\"color\":[1,0.97,0.9],\"intensity\":3}]}},"
        "\"scene\":0,\"scenes\":[{\"nodes\":[%s]}],\"nodes\":[%s],\"meshes\":[%s],\"materials\":[%s],"
        "\"accessors\":[%s],\"bufferViews\":[%s],\"buffers\":[{\"byteLength\":%zu}]}",
        roots.s, nodes.s, meshes.s, mats.s, acc.s, views.s, bin_len);
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
    free(js.s); free(acc.s); free(views.s); free(meshes.s); free(nodes.s); free(roots.s); free(mats.s);
    for (int i = 0; i < s->n; i++) {
        free(s->meshes[i].pos);
        free(s->meshes[i].nrm);
        free(s->meshes[i].idx);
    }
    free(s->meshes);
    return rc;
}

static int write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fputs(text, f);
    return fclose(f) == 0 ? 0 : 1;
}

/* ---- the scenes ---- */

static int gen_plane_box(const char *dir) {
    scene s = {0};
    s.sun = sb_sun_dir(30, 50);
    box(new_mesh(&s, 0), -20, -0.5, -20, 20, 0, 20);
    box(new_mesh(&s, 1), -1, 0, -1, 1, 2, 1);
    char p[4096];
    snprintf(p, sizeof p, "%s/plane-box.glb", dir);
    int rc = write_glb(&s, p);
    snprintf(p, sizeof p, "%s/plane-box.path", dir);
    rc |= write_text(p,
                     "# plane-box: a slow half orbit around the box\n"
                     "fov 60\n"
                     "look 0   0 6 12     0 0.5 0\n"
                     "look 4   10 6 6     0 0.5 0\n"
                     "look 8   12 7 -4    0 0.5 0\n"
                     "look 12  4 9 -11    0 0.5 0\n");
    return rc;
}

static int gen_desert(const char *dir) {
    scene s = {0};
    s.sun = sb_sun_dir(120, 35);
    g_seed = 1;
    const int tiles = 16, cells = 16;
    const double size = 400, tile = size / tiles, x0 = -size / 2;
    for (int tj = 0; tj < tiles; tj++)
        for (int ti = 0; ti < tiles; ti++) {
            double tx = x0 + ti * tile, tz = x0 + tj * tile;
            terrain_tile(new_mesh(&s, 2), tx, tz, tile, cells);
            mesh *b = new_mesh(&s, 4);
            /* streets on the tile borders: buildings keep 3 units away */
            for (int k = 0; k < 23; k++) {
                double w = 2 + 3 * rnd(), d = 2 + 3 * rnd(), h = 3 + 7 * rnd();
                double bx = tx + 3 + rnd() * (tile - 6 - w), bz = tz + 3 + rnd() * (tile - 6 - d);
                double ground = fmin(fmin(terrain_h(bx, bz), terrain_h(bx + w, bz)),
                                     fmin(terrain_h(bx, bz + d), terrain_h(bx + w, bz + d))) - 0.3;
                box(b, bx, ground, bz, bx + w, ground + 0.3 + h, bz + d);
            }
        }
    char p[4096];
    snprintf(p, sizeof p, "%s/desert.glb", dir);
    int rc = write_glb(&s, p);
    snprintf(p, sizeof p, "%s/desert.path", dir);
    rc |= write_text(p,
                     "# desert: low along a street between blocks, then up to a wide view (50 s)\n"
                     "fov 60\n"
                     "look 0    -175 4 -150    -175 4 -100\n"
                     "look 10   -175 4 -50     -170 4 0\n"
                     "look 20   -175 5 25      -100 3 25\n"
                     "look 30   -100 6 25      0 2 25\n"
                     "look 40   -40 40 60      50 0 0\n"
                     "look 50   0 120 190      0 0 0\n");
    return rc;
}

static int gen_towers(const char *dir) {
    scene s = {0};
    s.sun = sb_sun_dir(200, 55);
    g_seed = 2;
    box(new_mesh(&s, 0), -160, -1, -160, 160, 0, 160);
    const int blocks = 8;
    const double pitch = 26, street = 6, half = blocks * pitch / 2;
    for (int bj = 0; bj < blocks; bj++)
        for (int bi = 0; bi < blocks; bi++) {
            mesh *m = new_mesh(&s, 3);
            double bx = -half + bi * pitch + street / 2, bz = -half + bj * pitch + street / 2;
            double lot = (pitch - street) / 2;
            for (int k = 0; k < 4; k++) {
                double lx = bx + (k & 1) * lot + 0.5, lz = bz + (k >> 1) * lot + 0.5, w = lot - 1;
                double h = 40 + 110 * rnd() * rnd();
                /* three setbacks */
                box(m, lx, 0, lz, lx + w, h * 0.5, lz + w);
                box(m, lx + 1, h * 0.5, lz + 1, lx + w - 1, h * 0.8, lz + w - 1);
                box(m, lx + 2.5, h * 0.8, lz + 2.5, lx + w - 2.5, h, lz + w - 2.5);
            }
        }
    char p[4096];
    snprintf(p, sizeof p, "%s/towers.glb", dir);
    int rc = write_glb(&s, p);
    snprintf(p, sizeof p, "%s/towers.path", dir);
    /* streets run along x = -104 + 26k and z = -104 + 26k */
    rc |= write_text(p,
                     "# towers: down a narrow street between skyscrapers, then up above the roofs (25 s)\n"
                     "fov 60\n"
                     "look 0    0 4 -120    0 4 -60\n"
                     "look 5    0 4 -60     0 5 0\n"
                     "look 10   0 5 0       10 8 60\n"
                     "look 14   2 20 40     20 15 80\n"
                     "look 19   20 80 90    0 20 0\n"
                     "look 25   120 200 200 0 0 0\n");
    return rc;
}

static int gen_overhangs(const char *dir) {
    scene s = {0};
    s.sun = sb_sun_dir(60, 30);
    g_seed = 3;
    box(new_mesh(&s, 0), -600, -1, -600, 600, 0, 600);
    const int n = 10;
    const double pitch = 40;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            mesh *m = new_mesh(&s, (i + j) % 2 ? 4 : 1);
            double cx = (i - n / 2 + 0.5) * pitch, cz = (j - n / 2 + 0.5) * pitch;
            double h = 15 + 30 * rnd();
            /* a slim core, a wide cantilevered slab (overhang) and a roof ring */
            box(m, cx - 4, 0, cz - 4, cx + 4, h, cz + 4);
            box(m, cx - 12, h * 0.6, cz - 9, cx + 12, h * 0.6 + 2, cz + 9);
            box(m, cx - 9, h, cz - 9, cx + 9, h + 1.5, cz + 9);
            for (int k = 0; k < 6; k++) { /* pillars and fins */
                double a = k * SB_PI / 3;
                double px = cx + 7 * cos(a), pz = cz + 7 * sin(a);
                box(m, px - 0.5, 0, pz - 0.5, px + 0.5, h * 0.6, pz + 0.5);
            }
            if (i + 1 < n && rnd() < 0.5) /* bridge to the east neighbour */
                box(m, cx + 12, h * 0.6 + 0.5, cz - 1.5, cx + pitch - 12, h * 0.6 + 1.5, cz + 1.5);
            if (j + 1 < n && rnd() < 0.4) /* bridge to the north neighbour */
                box(m, cx - 1.5, h * 0.4, cz + 9, cx + 1.5, h * 0.4 + 1, cz + pitch - 9);
        }
    char p[4096];
    snprintf(p, sizeof p, "%s/overhangs.glb", dir);
    int rc = write_glb(&s, p);
    snprintf(p, sizeof p, "%s/overhangs.path", dir);
    rc |= write_text(p,
                     "# overhangs: under the slabs and bridges, then out to a far view (25 s)\n"
                     "fov 60\n"
                     "look 0    -220 3 0       -100 4 0\n"
                     "look 6    -100 3 0       -40 6 20\n"
                     "look 12   -20 4 20       20 8 60\n"
                     "look 18   40 30 120      0 10 0\n"
                     "look 25   300 120 400    0 0 0\n");
    return rc;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: scenegen OUTDIR\n");
        return 2;
    }
    return gen_plane_box(argv[1]) | gen_desert(argv[1]) | gen_towers(argv[1]) | gen_overhangs(argv[1]);
}
