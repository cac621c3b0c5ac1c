/* scene.c - building the flat scene model, re-basing, chunking, bundled names. */
#include "scene.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>



static void *grow(void *p, uint32_t *cap, uint32_t need, size_t elem) {
    if (need <= *cap) return p;
    uint32_t c = *cap ? *cap : 1024;
    while (c < need) c *= 2;
    *cap = c;
    return sb_xrealloc(p, (size_t)c * elem);
}

void sb_scene_reserve(sb_scene *s, uint64_t vertices, uint64_t indices, uint32_t draws) {
    if (vertices > UINT32_MAX - s->vertex_count || indices > UINT32_MAX - s->index_count) return;   /* refused later */
    uint32_t nv = s->vertex_count + (uint32_t)vertices, ni = s->index_count + (uint32_t)indices;
    uint32_t cap = s->build_cap;
    if (nv > s->vertex_cap) s->vertices = sb_xrealloc(s->vertices, (size_t)nv * SB_VERTEX_BYTES), s->vertex_cap = nv;
    if (nv > cap) s->build_pos = sb_xrealloc(s->build_pos, (size_t)nv * 3 * sizeof(double)), s->build_cap = nv;
    if (ni > s->index_cap) s->indices = sb_xrealloc(s->indices, (size_t)ni * sizeof(uint32_t)), s->index_cap = ni;
    if (s->draw_count + draws > s->draw_cap)
        s->draws = sb_xrealloc(s->draws, (size_t)(s->draw_count + draws) * sizeof(sb_draw)), s->draw_cap = s->draw_count + draws;
}

void sb_scene_begin(sb_scene *s) {
    memset(s, 0, sizeof *s);
    s->materials = sb_xcalloc(1, sizeof *s->materials); /* material 0: no alpha test, no texture */
    s->materials[0].texture = -1;
    s->material_count = 1;
}

const char *sb_blend_policy_name(sb_blend_policy p) {
    return p == SB_BLEND_OPAQUE ? "opaque" : p == SB_BLEND_NONE ? "none" : "mask";
}

uint32_t sb_scene_add_material(sb_scene *s, const sb_material *m) {
    if (!m->test) return 0;
    for (uint32_t i = 1; i < s->material_count; i++)
        if (!memcmp(&s->materials[i], m, sizeof *m)) return i;
    s->materials = sb_xrealloc(s->materials, (s->material_count + 1) * sizeof *s->materials);
    s->materials[s->material_count] = *m;
    return s->material_count++;
}

int32_t sb_scene_add_texture(sb_scene *s, uint32_t w, uint32_t h, const uint8_t *alpha, uint32_t wrap_s,
                             uint32_t wrap_t) {
    s->textures = sb_xrealloc(s->textures, (s->texture_count + 1) * sizeof *s->textures);
    s->textures[s->texture_count] = (sb_texture){w, h, s->texel_count, wrap_s, wrap_t};
    s->texels = sb_xrealloc(s->texels, (size_t)s->texel_count + (size_t)w * h);
    memcpy(s->texels + s->texel_count, alpha, (size_t)w * h);
    s->texel_count += w * h;
    return (int32_t)s->texture_count++;
}

/* A wrapped texture coordinate (clamping happens on the texel index); the
 * shaders' sb_wrap() in alpha.glsl does the same arithmetic. */
static float wrap_coord(float t, uint32_t mode) {
    if (mode == 0x812F) return t; /* GL_CLAMP_TO_EDGE */
    if (mode == 0x8370) {         /* GL_MIRRORED_REPEAT */
        float f = t - 2.0f * floorf(t * 0.5f);
        return f > 1.0f ? 2.0f - f : f;
    }
    return t - floorf(t); /* GL_REPEAT */
}

static uint32_t texel_index(float t, uint32_t mode, uint32_t n) {
    float x = floorf(wrap_coord(t, mode) * (float)n);
    return x <= 0 ? 0 : x >= (float)n - 1 ? n - 1 : (uint32_t)x;
}

bool sb_material_covers(const sb_scene *s, uint32_t mi, float u, float v) {
    if (mi == 0 || mi >= s->material_count) return true;
    const sb_material *m = &s->materials[mi];
    if (!m->test) return true;
    float a = m->alpha;
    if (m->texture >= 0) {
        const sb_texture *t = &s->textures[m->texture];
        float tu = m->uv[0] * u + m->uv[1] * v + m->uv[2], tv = m->uv[3] * u + m->uv[4] * v + m->uv[5];
        uint32_t x = texel_index(tu, t->wrap_s, t->w), y = texel_index(tv, t->wrap_t, t->h);
        a *= (float)s->texels[t->offset + (size_t)y * t->w + x] / 255.0f;
    }
    return a >= m->cutoff;
}

/* Area-weighted vertex normals from the faces, for a primitive without normals. */
static void face_normals(sb_scene *s, const sb_prim_desc *p, uint32_t base) {
    for (uint32_t i = 0; i + 2 < p->index_count; i += 3) {
        const double *a = p->positions + 3 * (size_t)p->indices[i];
        const double *b = p->positions + 3 * (size_t)p->indices[i + 1];
        const double *c = p->positions + 3 * (size_t)p->indices[i + 2];
        sb_v3 n = sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                              sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2]));
        for (int k = 0; k < 3; k++) {
            float *out = sb_vertex(s, base + p->indices[i + k]);
            out[3] += (float)n.x;
            out[4] += (float)n.y;
            out[5] += (float)n.z;
        }
    }
    for (uint32_t v = 0; v < p->vertex_count; v++) {
        float *out = sb_vertex(s, base + v);
        sb_v3 n = sb_v3_norm(sb_v3_make(out[3], out[4], out[5]));
        out[3] = (float)n.x;
        out[4] = (float)n.y;
        out[5] = (float)n.z;
    }
}

/* Open addressing over a power-of-two table of indices (UINT32_MAX: empty),
 * for grouping in linear time: welding, edges, planes. */
typedef struct {
    uint32_t *slot;
    uint64_t mask;
} idx_table;

static void idx_table_init(idx_table *t, size_t n) {
    size_t cap = 16;
    while (cap < n + n / 2) cap *= 2;   /* at most 2/3 full: half the memory of 1/2, fewer pages to fault in */
    t->slot = sb_xmalloc(cap * sizeof(uint32_t));
    memset(t->slot, 0xff, cap * sizeof(uint32_t));
    t->mask = cap - 1;
}

/* Whether the primitive is a closed surface with consistent winding: with
 * vertices welded by position, every directed edge a->b appears once and so
 * does b->a. Then each ray from outside crossing it leaves through a face
 * turned its way, so back faces can be culled without changing any answer. */
static bool prim_closed(const sb_prim_desc *p) {
    uint32_t nv = p->vertex_count, nt = p->index_count / 3;
    if (nt < 4) return false;
    /* weld: each vertex to the first vertex with its exact position */
    uint32_t *id = sb_xmalloc(sizeof(uint32_t) * nv);
    idx_table w;
    idx_table_init(&w, nv);
    for (uint32_t v = 0; v < nv; v++) {
        const double *q = p->positions + 3 * (size_t)v;
        uint64_t b[3];
        memcpy(b, q, sizeof b);
        /* one mix of the three words multiplied apart (a probe per vertex is the cost here) */
        uint64_t hb = sb_mix64(b[0] * 0x9e3779b97f4a7c15u ^ b[1] * 0xc2b2ae3d27d4eb4fu ^ b[2] * 0x165667b19e3779f9u);
        for (uint64_t h = hb & w.mask;; h = (h + 1) & w.mask) {
            uint32_t o = w.slot[h];
            if (o == UINT32_MAX) {
                w.slot[h] = id[v] = v;
                break;
            }
            if (!memcmp(p->positions + 3 * (size_t)o, q, 3 * sizeof(double))) {
                id[v] = o;
                break;
            }
        }
    }
    free(w.slot);
    /* directed edges, each once; then every edge's reverse present */
    uint64_t *e = sb_xmalloc(sizeof(uint64_t) * 3 * nt);
    size_t ne = 3 * (size_t)nt;
    bool closed = true;
    for (uint32_t t = 0; t < nt && closed; t++)
        for (int j = 0; j < 3; j++) {
            uint32_t a = id[p->indices[3 * t + j]], b = id[p->indices[3 * t + (j + 1) % 3]];
            closed &= a != b;
            e[3 * t + j] = (uint64_t)a << 32 | b;
        }
    idx_table et;
    idx_table_init(&et, closed ? ne : 0);
    for (size_t i = 0; closed && i < ne; i++)
        for (uint64_t h = sb_mix64(e[i]) & et.mask;; h = (h + 1) & et.mask) {
            uint32_t o = et.slot[h];
            if (o == UINT32_MAX) {
                et.slot[h] = (uint32_t)i;
                break;
            }
            if (e[o] == e[i]) {
                closed = false;   /* the same directed edge twice */
                break;
            }
        }
    for (size_t i = 0; closed && i < ne; i++) {
        uint64_t rev = e[i] << 32 | e[i] >> 32;
        bool found = false;
        for (uint64_t h = sb_mix64(rev) & et.mask; et.slot[h] != UINT32_MAX && !found; h = (h + 1) & et.mask)
            found = e[et.slot[h]] == rev;
        closed = found;
    }
    free(et.slot);
    free(e);
    free(id);
    return closed;
}

/* Whether the 4x4 (column-major) is a similarity that keeps the winding: rotation, uniform scale and translation,
 * within rounding. Only such a transform can share a primitive's GPU copy: its normals turn with it (scaled,
 * normalized where used) and its front faces stay front faces. */
static bool similarity(const double *m) {
    if (fabs(m[3]) + fabs(m[7]) + fabs(m[11]) > 1e-12 || fabs(m[15] - 1) > 1e-12) return false;
    double g[3][3], tr = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            g[i][j] = 0;
            for (int k = 0; k < 3; k++) g[i][j] += m[i * 4 + k] * m[j * 4 + k];   /* columns i and j */
        }
    for (int i = 0; i < 3; i++) tr += g[i][i];
    double s2 = tr / 3;
    if (!(s2 > 0)) return false;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (fabs(g[i][j] - (i == j ? s2 : 0)) > 1e-6 * s2) return false;
    double det = m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
                 m[8] * (m[1] * m[6] - m[5] * m[2]);
    return det > 0;
}

/* A similarity's scale (the 4x4's first column's length). */
static double similarity_scale(const double *m) { return sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]); }

bool sb_xform_translation_only(const float x[12]) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            if (fabsf(x[4 * r + c] - (r == c)) > 1e-6f) return false;
    return true;
}

const float sb_xform_identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

void sb_scene_add_prim(sb_scene *s, const sb_prim_desc *p) {
    bool double_sided = p->double_sided;
    bool closed = !double_sided && (p->closed_known ? p->closed_known == 2 : prim_closed(p));
    const sb_draw *of = p->instance_of && p->instance_of <= s->draw_count ? &s->draws[p->instance_of - 1] : NULL;
    /* shared only where the placement is as precise through the proto as its own floats are: never magnified
       from it (a proto placed at scale 1e-6 holds its shape in floats quantized at its position, and a placement
       at scale 1 would magnify that quantum a million times: the box drawn and traced visibly wider); a larger
       placement is a copy of its own, and the loader places later ones from it (sb_prim_desc.instance_of) */
    bool instance = of && of->proto == p->instance_of - 1 && of->vertex_count == p->vertex_count &&
                    of->index_count == p->index_count && of->double_sided == double_sided && of->closed == closed &&
                    of->material == p->material && similarity(p->relative) &&
                    similarity_scale(p->relative) <= 1 + 1e-9;
    sb_draw d = {.double_sided = double_sided, .closed = closed, .material = p->material, .node = p->node,
                 .proto = s->draw_count};
    memcpy(d.color, p->color, sizeof d.color);
    memcpy(d.xform, sb_xform_identity, sizeof d.xform);
    if (instance) {   /* its proto's triangles and vertices, placed by its transform: not copied */
        d.proto = p->instance_of - 1;
        d.first_index = of->first_index, d.index_count = of->index_count;
        d.first_vertex = of->first_vertex, d.vertex_count = of->vertex_count;
        s->build_rel = grow(s->build_rel, &s->build_rel_cap, s->draw_count + 1, 12 * sizeof(double));
        double *rel = s->build_rel + 12 * (size_t)s->draw_count;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++) rel[4 * r + c] = p->relative[c * 4 + r];
    } else {
        uint32_t base = s->vertex_count;
        uint32_t cap = s->build_cap;
        s->build_pos = grow(s->build_pos, &cap, base + p->vertex_count, 3 * sizeof(double));
        s->vertices = grow(s->vertices, &s->vertex_cap, base + p->vertex_count, SB_VERTEX_BYTES);
        s->build_cap = cap;
        for (uint32_t v = 0; v < p->vertex_count; v++) {
            memcpy(s->build_pos + 3 * (size_t)(base + v), p->positions + 3 * (size_t)v, 3 * sizeof(double));
            float *out = sb_vertex(s, base + v);
            memset(out, 0, SB_VERTEX_BYTES);
            if (p->normals) {
                sb_v3 n = sb_v3_norm(sb_v3_make(p->normals[3 * v], p->normals[3 * v + 1], p->normals[3 * v + 2]));
                out[3] = (float)n.x;
                out[4] = (float)n.y;
                out[5] = (float)n.z;
            }
            if (p->uv) {
                out[6] = (float)p->uv[2 * v];
                out[7] = (float)p->uv[2 * v + 1];
            }
            memcpy(out + 8, &p->material, 4);
        }
        if (!p->normals) face_normals(s, p, base);
        s->vertex_count += p->vertex_count;
        uint32_t first = s->index_count;
        s->indices = grow(s->indices, &s->index_cap, first + p->index_count, sizeof(uint32_t));
        for (uint32_t i = 0; i < p->index_count; i++) s->indices[first + i] = base + p->indices[i];
        s->index_count += p->index_count;
        d.first_index = first, d.index_count = p->index_count;
        d.first_vertex = base, d.vertex_count = p->vertex_count;
    }
    s->draws = grow(s->draws, &s->draw_cap, s->draw_count + 1, sizeof(sb_draw));
    sb_draw *dp = &s->draws[s->draw_count++];
    *dp = d;
    /* its box, while its positions are at hand (chunking gives its pieces their own): over the vertices its
       triangles use, each once (an index is read three times a vertex or so, a position once) */
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    uint8_t *used = sb_xcalloc(p->vertex_count ? p->vertex_count : 1, 1);
    for (uint32_t i = 0; i < p->index_count; i++) used[p->indices[i]] = 1;
    for (uint32_t v = 0; v < p->vertex_count; v++) {
        if (!used[v]) continue;
        const double *q = p->positions + 3 * (size_t)v;
        for (int k = 0; k < 3; k++) {
            lo[k] = q[k] < lo[k] ? q[k] : lo[k];
            hi[k] = q[k] > hi[k] ? q[k] : hi[k];
        }
    }
    free(used);
    dp->box = (sb_aabb){{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
}

/* ---- chunking: split a draw's triangles at the centroid median until small ---- */

/* A triangle's sort key: three times its centroid on the split axis, then its
 * number (equal centroids keep their order: the sort is stable). */
typedef struct {
    double key;
    uint32_t tri;
} tri_key;

static inline bool tri_less(const tri_key *x, const tri_key *y) {
    return x->key < y->key || (x->key == y->key && x->tri < y->tri);
}

/* Hoare partition of k[0..n) (n > 2) around the median of three: returns left, with [0, left) <= pivot <=
 * [left, n) by tri_less. */
static size_t partition_tri_keys(tri_key *k, size_t n) {
    tri_key a = k[0], b = k[n / 2], c = k[n - 1], pivot;
    pivot = tri_less(&a, &b) ? (tri_less(&b, &c) ? b : tri_less(&a, &c) ? c : a)
                             : (tri_less(&a, &c) ? a : tri_less(&b, &c) ? c : b);
    size_t i = 0, j = n - 1;
    for (;;) {
        while (tri_less(&k[i], &pivot)) i++;
        while (tri_less(&pivot, &k[j])) j--;
        if (i >= j) return j + 1;
        tri_key t = k[i];
        k[i++] = k[j];
        k[j--] = t;
    }
}

/* Sorts by (key, tri): a total order (tri numbers are unique), so the result
 * is the one any sort gives; typed and inlined, several times qsort's speed. */
static void sort_tri_keys(tri_key *k, size_t n) {
    while (n > 16) {
        /* recurse into the smaller part, loop on the larger */
        size_t left = partition_tri_keys(k, n);
        if (left < n - left) {
            sort_tri_keys(k, left);
            k += left;
            n -= left;
        } else {
            sort_tri_keys(k + left, n - left);
            n = left;
        }
    }
    for (size_t i = 1; i < n; i++) {
        tri_key t = k[i];
        size_t j = i;
        for (; j > 0 && tri_less(&t, &k[j - 1]); j--) k[j] = k[j - 1];
        k[j] = t;
    }
}

static sb_aabb tri_range_box(const sb_scene *s, uint32_t first_index, uint32_t count) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (uint32_t i = first_index; i < first_index + count; i++) {
        const double *p = s->build_pos + 3 * (size_t)s->indices[i];
        for (int k = 0; k < 3; k++) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
    return (sb_aabb){{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
}

typedef struct {
    uint32_t *first, *count;
    uint32_t n, cap;
} leaf_list;

/* Puts the m smallest keys (by tri_less: a total order) first, in no order: quickselect, linear on average. */
static void select_tri_keys(tri_key *k, size_t n, size_t m) {
    while (n > 16 && m > 0 && m < n) {
        size_t left = partition_tri_keys(k, n);
        if (m < left) n = left;
        else k += left, n -= left, m -= left;
    }
    if (m > 0 && m < n) sort_tri_keys(k, n);
}

/* Orders triangles [0, n) of a draw's index run spatially (median splits on
 * the longest axis of their centroids) and records each final run as a leaf.
 * idx: the run's indices (3 a triangle); cen: each triangle's centroid times
 * three, beside it in the same order (both permuted together, read in
 * sequence); first: the run's first triangle in the scene. The halves are
 * chosen by selection (linear), not by sorting: a level costs O(n); a half
 * that is a leaf is then sorted along the axis, so each draw's triangles run
 * along it as a full sort at every level left them. */
static void split_order(uint32_t *idx, double *cen, tri_key *k, uint32_t first, uint32_t n, leaf_list *out) {
    if (n <= SB_CHUNK_TRIS) {
        uint32_t c1 = out->cap, c2 = out->cap;
        out->first = grow(out->first, &c1, out->n + 1, sizeof(uint32_t));
        out->count = grow(out->count, &c2, out->n + 1, sizeof(uint32_t));
        out->cap = c1;
        out->first[out->n] = first;
        out->count[out->n++] = n;
        return;
    }
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (uint32_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            double v = cen[3 * (size_t)i + a];
            lo[a] = v < lo[a] ? v : lo[a];
            hi[a] = v > hi[a] ? v : hi[a];
        }
    int axis = hi[0] - lo[0] >= hi[1] - lo[1] && hi[0] - lo[0] >= hi[2] - lo[2] ? 0 : hi[1] - lo[1] >= hi[2] - lo[2] ? 1 : 2;
    for (uint32_t i = 0; i < n; i++) k[i] = (tri_key){cen[3 * (size_t)i + axis], i};
    uint32_t half = n / 2;
    select_tri_keys(k, n, half);
    /* a half that is a leaf keeps its triangles in order along the axis (as drawn: spatially coherent runs) */
    if (half <= SB_CHUNK_TRIS) sort_tri_keys(k, half);
    if (n - half <= SB_CHUNK_TRIS) sort_tri_keys(k + half, n - half);
    uint32_t *ti = sb_xmalloc((size_t)n * 3 * sizeof(uint32_t));
    double *tc = sb_xmalloc((size_t)n * 3 * sizeof(double));
    for (uint32_t i = 0; i < n; i++) {
        memcpy(ti + 3 * (size_t)i, idx + 3 * (size_t)k[i].tri, 3 * sizeof(uint32_t));
        memcpy(tc + 3 * (size_t)i, cen + 3 * (size_t)k[i].tri, 3 * sizeof(double));
    }
    memcpy(idx, ti, (size_t)n * 3 * sizeof(uint32_t));
    memcpy(cen, tc, (size_t)n * 3 * sizeof(double));
    free(ti);
    free(tc);
    split_order(idx, cen, k, first, half, out);
    split_order(idx + 3 * (size_t)half, cen + 3 * (size_t)half, k, first + half, n - half, out);
}

/* The box of triangles [first_index, first_index + count) placed by an instance's world transform (rows). */
static sb_aabb placed_range_box(const sb_scene *s, uint32_t first_index, uint32_t count, const double *rel) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (uint32_t i = first_index; i < first_index + count; i++) {
        const double *p = s->build_pos + 3 * (size_t)s->indices[i];
        for (int k = 0; k < 3; k++) {
            double q = rel[4 * k] * p[0] + rel[4 * k + 1] * p[1] + rel[4 * k + 2] * p[2] + rel[4 * k + 3];
            lo[k] = q < lo[k] ? q : lo[k];
            hi[k] = q > hi[k] ? q : hi[k];
        }
    }
    return (sb_aabb){{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
}

/* An instance's chunks are its proto's: chunk c of the one is chunk c of the other's index run, placed by the
 * instance's transform. */
static void chunk_instance(sb_scene *s, uint32_t di, const uint32_t *extra_first, const uint32_t *extra_n) {
    sb_draw d = s->draws[di];
    uint32_t p = d.proto, k = 1 + extra_n[p];
    if (k == 1) return;   /* the proto was not cut: neither is this */
    for (uint32_t c = 0; c < k; c++) {
        uint32_t pci = c ? extra_first[p] + c - 1 : p;
        const sb_draw pc = s->draws[pci];
        sb_draw nd = d;
        nd.first_index = pc.first_index;
        nd.index_count = pc.index_count;
        nd.box = placed_range_box(s, nd.first_index, nd.index_count, s->build_rel + 12 * (size_t)di);
        nd.proto = pci;
        if (c == 0) {
            s->draws[di] = nd;
        } else {
            s->draws = grow(s->draws, &s->draw_cap, s->draw_count + 1, sizeof(sb_draw));
            s->build_rel = grow(s->build_rel, &s->build_rel_cap, s->draw_count + 1, 12 * sizeof(double));
            memcpy(s->build_rel + 12 * (size_t)s->draw_count, s->build_rel + 12 * (size_t)di, 12 * sizeof(double));
            s->draws[s->draw_count++] = nd;
        }
    }
}

static void chunk_draws(sb_scene *s) {
    uint32_t n = s->draw_count;
    /* the chunks a draw was cut into beyond its first (which keeps its place): extra_n of them from extra_first */
    uint32_t *extra_first = sb_xcalloc(n ? n : 1, sizeof(uint32_t)), *extra_n = sb_xcalloc(n ? n : 1, sizeof(uint32_t));
    for (uint32_t di = 0; di < n; di++) {
        sb_draw d = s->draws[di];
        uint32_t tris = d.index_count / 3;
        extra_first[di] = s->draw_count;
        if (d.proto != di) {
            uint32_t before = s->draw_count;
            chunk_instance(s, di, extra_first, extra_n);
            extra_n[di] = s->draw_count - before;
            continue;
        }
        if (tris <= SB_CHUNK_TRIS) continue;
        uint32_t *idx = s->indices + d.first_index;
        double *cen = sb_xmalloc((size_t)tris * 3 * sizeof(double));
        for (uint32_t t = 0; t < tris; t++)
            for (int a = 0; a < 3; a++)
                cen[3 * (size_t)t + a] = s->build_pos[3 * (size_t)idx[3 * t] + a] +
                                         s->build_pos[3 * (size_t)idx[3 * t + 1] + a] +
                                         s->build_pos[3 * (size_t)idx[3 * t + 2] + a];
        tri_key *order = sb_xmalloc(tris * sizeof *order);
        leaf_list leaves = {0};
        split_order(idx, cen, order, d.first_index / 3, tris, &leaves);
        free(order);
        free(cen);
        for (uint32_t c = 0; c < leaves.n; c++) {
            sb_draw nd = d;
            nd.first_index = 3 * leaves.first[c];
            nd.index_count = 3 * leaves.count[c];
            nd.box = tri_range_box(s, nd.first_index, nd.index_count);
            if (c == 0) {
                s->draws[di] = nd;
            } else {
                nd.proto = s->draw_count;
                s->draws = grow(s->draws, &s->draw_cap, s->draw_count + 1, sizeof(sb_draw));
                s->draws[s->draw_count++] = nd;
            }
        }
        extra_n[di] = leaves.n - 1;
        free(leaves.first);
        free(leaves.count);
    }
    free(extra_first);
    free(extra_n);
}

/* An instance's transform, origin-relative: q' = A q + (A o + t - o) for q = p - o. */
static void instance_xforms(sb_scene *s) {
    double o[3] = {s->origin.x, s->origin.y, s->origin.z};
    for (uint32_t i = 0; i < s->draw_count; i++) {
        if (!SB_DRAW_IS_INSTANCE(s, i)) continue;
        s->instance_draws++;
        const double *rel = s->build_rel + 12 * (size_t)i;
        float *x = s->draws[i].xform;
        for (int r = 0; r < 3; r++) {
            double t = rel[4 * r + 3] - o[r];
            for (int c = 0; c < 3; c++) {
                x[4 * r + c] = (float)rel[4 * r + c];
                t += rel[4 * r + c] * o[c];
            }
            x[4 * r + 3] = (float)t;
        }
    }
}

bool sb_scene_finish(sb_scene *s, sb_err *err) {
    if (s->index_count == 0) {
        free(s->build_pos);
        s->build_pos = NULL;
        free(s->build_rel);
        s->build_rel = NULL;
        return sb_fail(err, "%s: the scene has no triangles reachable from its scene graph", s->file);
    }
    double t0 = sb_now_ms();
    chunk_draws(s);
    for (uint32_t i = 0; i < s->draw_count; i++) {
        s->alpha_tested_draws += s->draws[i].material != 0;
        s->single_sided_draws += !s->draws[i].double_sided;
    }
    sb_aabb all = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
    for (uint32_t i = 0; i < s->draw_count; i++) {   /* the draws' boxes: made as they were added or chunked */
        all.lo = sb_v3_min(all.lo, s->draws[i].box.lo);
        all.hi = sb_v3_max(all.hi, s->draws[i].box.hi);
    }
    s->origin = sb_v3_scale(sb_v3_add(all.lo, all.hi), 0.5);
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        const double *p = s->build_pos + 3 * (size_t)v;
        float *o = sb_vertex(s, v);
        o[0] = (float)(p[0] - s->origin.x);
        o[1] = (float)(p[1] - s->origin.y);
        o[2] = (float)(p[2] - s->origin.z);
    }
    instance_xforms(s);
    free(s->build_rel);
    s->build_rel = NULL;
    for (uint32_t i = 0; i < s->draw_count; i++) {
        s->draws[i].box.lo = sb_v3_sub(s->draws[i].box.lo, s->origin);
        s->draws[i].box.hi = sb_v3_sub(s->draws[i].box.hi, s->origin);
    }
    for (uint32_t i = 0; i < s->light_count; i++)
        s->lights[i].position = sb_v3_sub(s->lights[i].position, s->origin);
    s->bounds.lo = sb_v3_sub(all.lo, s->origin);
    s->bounds.hi = sb_v3_sub(all.hi, s->origin);
    double area = 0;
    for (uint32_t t = 0; t < s->index_count / 3 && area == 0; t++) {
        const double *a = s->build_pos + 3 * (size_t)s->indices[3 * t], *b = s->build_pos + 3 * (size_t)s->indices[3 * t + 1],
                     *c = s->build_pos + 3 * (size_t)s->indices[3 * t + 2];
        area = sb_v3_len(sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                                     sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2])));
    }
    if (!(area > 0))
        snprintf(s->degenerate, sizeof s->degenerate, "all %u triangles have zero area (a zero scale, or every vertex "
                 "at one point)", (unsigned)sb_scene_triangles(s));
    free(s->build_pos);
    s->build_pos = NULL;
    double t1 = sb_now_ms();
    sb_scene_build_bvh(s);
    s->load_part_ms[SB_LOAD_DRAWS] = t1 - t0;
    s->load_part_ms[SB_LOAD_BVH] = sb_now_ms() - t1;
    return true;
}

const char *const sb_load_part_names[SB_LOAD_PARTS] = {"parse", "flatten", "draws", "bvh", "planes"};

void sb_scene_load_parts(const sb_scene *s, char *out, size_t len) {
    size_t n = 0;
    out[0] = 0;
    if (s->from_cache) {
        snprintf(out, len, "from the scene cache");
        return;
    }
    for (int i = 0; i < SB_LOAD_PARTS && n < len; i++)
        if (i != SB_LOAD_PLANES || s->planes_found)   /* the plane search is left to the first need */
            n += (size_t)snprintf(out + n, len - n, "%s%s %.0f", i ? ", " : "", sb_load_part_names[i], s->load_part_ms[i]);
}

/* A plane group: its quantised key (normal, distance), its first and last
 * triangle (chained in triangle order through next[]), its area and count. */
typedef struct {
    int64_t key[4];
    uint32_t head, tail, count, index;
    double area;
} plane_group;

static int cmp_plane_group(const void *a, const void *b) {
    const plane_group *x = *(const plane_group *const *)a, *y = *(const plane_group *const *)b;
    for (int k = 0; k < 4; k++)
        if (x->key[k] != y->key[k]) return x->key[k] < y->key[k] ? -1 : 1;
    return 0;
}

/* round half away from zero, as llround, inline */
static inline int64_t round_key(double x) { return x >= 0 ? (int64_t)(x + 0.5) : -(int64_t)(0.5 - x); }

/* The open-addressing table of groups: slot = hash's high half << 32 | group + 1 (0: empty), grown at half
 * full. Its size follows the groups, not the triangles, so a large scene's lookups stay in the caches. */
typedef struct {
    uint64_t *slot;
    uint64_t mask;
    uint32_t last;              /* the group found or made last (consecutive triangles often share it) */
} group_table;

static void group_table_put(group_table *t, uint64_t h, uint32_t g) {
    uint64_t i = h & t->mask;
    while (t->slot[i]) i = (i + 1) & t->mask;
    t->slot[i] = (h >> 32) << 32 | (uint64_t)(g + 1);
}

/* One mix of the four keys multiplied apart: a table probe per triangle is the cost here. */
static uint64_t key_hash(const int64_t key[4]) {
    return sb_mix64((uint64_t)key[0] * 0x9e3779b97f4a7c15u ^ (uint64_t)key[1] * 0xc2b2ae3d27d4eb4fu ^
                    (uint64_t)key[2] * 0x165667b19e3779f9u ^ (uint64_t)key[3] * 0x27d4eb2f165667c5u);
}

/* The group of key in (*g)[0..*ng), added (with triangle t and its area) when new; returns its index. */
static uint32_t group_of(group_table *tab, plane_group **g, uint32_t *ng, uint32_t *gcap, const int64_t key[4],
                         uint32_t t, double area, uint32_t *next) {
    if (*ng > 0 && tab->last < *ng && !memcmp((*g)[tab->last].key, key, 4 * sizeof(int64_t))) {
        plane_group *x = &(*g)[tab->last];   /* the group of the triangle before: a quad's two halves, a box's face */
        if (next) next[x->tail] = t;
        x->tail = t;
        x->area += area;
        x->count++;
        return x->index;
    }
    uint64_t h = key_hash(key);
    for (uint64_t i = h & tab->mask; tab->slot[i]; i = (i + 1) & tab->mask)
        if (tab->slot[i] >> 32 == h >> 32 && !memcmp((*g)[(uint32_t)tab->slot[i] - 1].key, key, 4 * sizeof(int64_t))) {
            plane_group *x = &(*g)[(uint32_t)tab->slot[i] - 1];
            tab->last = x->index;
            if (next) next[x->tail] = t;
            x->tail = t;
            x->area += area;
            x->count++;
            return x->index;
        }
    if (*ng == *gcap) *g = sb_xrealloc(*g, (*gcap = *gcap ? 2 * *gcap : 1024) * sizeof **g);
    (*g)[*ng] = (plane_group){{key[0], key[1], key[2], key[3]}, t, t, 1, *ng, area};
    if (2 * (uint64_t)(*ng + 1) > tab->mask + 1) { /* grow: every group again */
        free(tab->slot);
        tab->mask = 2 * (tab->mask + 1) - 1;
        tab->slot = sb_xcalloc(tab->mask + 1, sizeof(uint64_t));
        for (uint32_t q = 0; q < *ng; q++) group_table_put(tab, key_hash((*g)[q].key), q);
    }
    group_table_put(tab, h, *ng);
    tab->last = *ng;
    return (*ng)++;
}

/* The instance draws of the placed numbering (scene.h): draw[k] the k-th instance draw, first[k] its first
 * triangle's number (first[n]: one past the last). */
typedef struct sb_tri_map {
    uint32_t n;
    uint32_t *draw;
    uint64_t *first;
} sb_tri_map;

static void tri_map_make(const sb_scene *s, sb_tri_map *m) {
    m->n = 0;
    m->draw = sb_xmalloc(sizeof(uint32_t) * (s->instance_draws + 1));
    m->first = sb_xmalloc(sizeof(uint64_t) * (s->instance_draws + 1));
    uint64_t at = s->index_count / 3;
    for (uint32_t d = 0; d < s->draw_count && m->n < s->instance_draws; d++) {
        if (!SB_DRAW_IS_INSTANCE(s, d)) continue;
        m->draw[m->n] = d;
        m->first[m->n++] = at;
        at += s->draws[d].index_count / 3;
    }
    m->first[m->n] = at;
}

static void tri_map_free(sb_tri_map *m) {
    free(m->draw);
    free(m->first);
    memset(m, 0, sizeof *m);
}

/* Triangle t of the placed numbering: its three corners' positions (9 floats, origin-relative). */
static void placed_triangle(const sb_scene *s, const sb_tri_map *m, uint64_t t, float out[9]) {
    const sb_draw *d = NULL;
    const uint32_t *ix;
    if (t < s->index_count / 3) {
        ix = s->indices + 3 * t;
    } else {
        uint32_t lo = 0, hi = m->n;   /* the last k with first[k] <= t */
        while (hi - lo > 1) {
            uint32_t mid = (lo + hi) / 2;
            if (m->first[mid] <= t) lo = mid;
            else hi = mid;
        }
        d = &s->draws[m->draw[lo]];
        ix = s->indices + d->first_index + 3 * (t - m->first[lo]);
    }
    for (int k = 0; k < 3; k++) {
        if (d) sb_draw_point(s, d, ix[k], out + 3 * k);
        else memcpy(out + 3 * k, sb_vertex(s, ix[k]), 3 * sizeof(float));
    }
}

/* Triangle t's unit normal, plane distance and area (0: degenerate); t of the placed numbering. */
static double tri_plane(const sb_scene *s, const sb_tri_map *m, uint32_t t, sb_v3 *n, double *d) {
    float p[9];
    placed_triangle(s, m, t, p);
    const float *a = p, *b = p + 3, *c = p + 6;
    sb_v3 x = sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                          sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2]));
    double len = sb_v3_len(x);
    if (!(len > 0)) return 0;
    *n = sb_v3_scale(x, 1.0 / len);   /* one square root a triangle */
    double area = 0.5 * len;
    *d = -(n->x * a[0] + n->y * a[1] + n->z * a[2]);
    return area;
}

static void find_planes(sb_scene *s);

void sb_scene_find_planes(sb_scene *s) {
    if (s->planes_found) return;
    double t0 = sb_now_ms();
    s->planes_found = true;
    find_planes(s);
    s->load_part_ms[SB_LOAD_PLANES] = sb_now_ms() - t0;
}

static void find_planes(sb_scene *s) {
    uint64_t all = sb_scene_triangles(s);
    sb_v3 ext = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    double face = fmax(ext.x * ext.y, fmax(ext.y * ext.z, ext.x * ext.z)), diag = sb_v3_len(ext);
    if (all == 0 || all >= UINT32_MAX || face <= 0) return;
    uint32_t ntri = (uint32_t)all;
    sb_tri_map m;
    tri_map_make(s, &m);
    /* 1: the triangles by quantised normal alone (few groups): a plane's area is at most its normal's, so only
     * triangles of a normal with 0.1 face or more can be in a large plane */
    uint32_t *normal_of = sb_xmalloc(sizeof(uint32_t) * ntri);
    double *dist = sb_xmalloc(sizeof(double) * ntri), *areas = sb_xmalloc(sizeof(double) * ntri);
    plane_group *ngrp = NULL;
    uint32_t nn = 0, ncap = 0;
    group_table tab = {sb_xcalloc(1024, sizeof(uint64_t)), 1023, 0};
    for (uint32_t t = 0; t < ntri; t++) {
        sb_v3 n;
        double d, area = tri_plane(s, &m, t, &n, &d);
        normal_of[t] = UINT32_MAX;
        if (area <= 0) continue;
        int64_t key[4] = {round_key(n.x * 1e3), round_key(n.y * 1e3), round_key(n.z * 1e3), 0};
        normal_of[t] = group_of(&tab, &ngrp, &nn, &ncap, key, t, area, NULL);
        dist[t] = d;
        areas[t] = area;
    }
    free(tab.slot);
    /* 2: those triangles by quantised plane, each group's triangles chained in triangle order; then the large
     * groups in key order, as a sort would visit them */
    uint32_t *next = sb_xmalloc(sizeof(uint32_t) * ntri);
    plane_group *g = NULL;
    uint32_t ng = 0, gcap = 0;
    tab = (group_table){sb_xcalloc(1024, sizeof(uint64_t)), 1023, 0};
    for (uint32_t t = 0; t < ntri; t++) {
        next[t] = UINT32_MAX;
        if (normal_of[t] == UINT32_MAX || ngrp[normal_of[t]].area < 0.1 * face) continue;
        const int64_t *nk = ngrp[normal_of[t]].key;
        int64_t key[4] = {nk[0], nk[1], nk[2], round_key(dist[t] / diag * 1e4)};
        group_of(&tab, &g, &ng, &gcap, key, t, areas[t], next);
    }
    free(tab.slot);
    free(ngrp);
    free(normal_of);
    free(dist);
    free(areas);
    plane_group **big = NULL;   /* the large groups */
    uint32_t nbig = 0;
    for (uint32_t k = 0; k < ng; k++)
        if (g[k].area >= 0.1 * face) {
            big = sb_xrealloc(big, (nbig + 1) * sizeof *big);
            big[nbig++] = &g[k];
        }
    if (nbig > 1) qsort(big, nbig, sizeof *big, cmp_plane_group);
    for (uint32_t b = 0; b < nbig; b++) {
        const plane_group *grp = big[b];
        double area = grp->area;
        /* keep the largest SB_MAX_PLANES */
        int slot = -1;
        if (s->plane_count < SB_MAX_PLANES) slot = (int)s->plane_count++;
        else
            for (int q = 0; q < SB_MAX_PLANES; q++)
                if (s->planes[q].area < area && (slot < 0 || s->planes[q].area < s->planes[slot].area)) slot = q;
        if (slot < 0) continue;
        sb_plane *p = &s->planes[slot];
        free(p->tris);
        sb_v3 n;
        double d;
        tri_plane(s, &m, grp->head, &n, &d);
        p->n[0] = n.x;
        p->n[1] = n.y;
        p->n[2] = n.z;
        p->d = d;
        p->area = area;
        p->tri_count = grp->count;
        p->tris = sb_xmalloc(sizeof(uint32_t) * p->tri_count);
        uint32_t j = 0;
        for (uint32_t t = grp->head; t != UINT32_MAX && j < grp->count; t = next[t]) p->tris[j++] = t;
    }
    free(big);
    free(next);
    free(g);
    tri_map_free(&m);
}

uint64_t sb_scene_triangles(const sb_scene *s) {
    uint64_t n = s->index_count / 3;
    for (uint32_t d = 0; d < s->draw_count && s->instance_draws; d++)
        if (SB_DRAW_IS_INSTANCE(s, d)) n += s->draws[d].index_count / 3;
    return n;
}

void sb_scene_flatten(const sb_scene *s, const uint8_t *which, sb_scene_flat *out) {
    memset(out, 0, sizeof *out);
    out->first = sb_xmalloc(sizeof(uint32_t) * (s->draw_count + 1));
    for (uint32_t d = 0; d < s->draw_count; d++) out->first[d] = s->draws[d].first_index;
    uint64_t nv = s->vertex_count, ni = s->index_count;
    for (uint32_t d = 0; d < s->draw_count && s->instance_draws; d++)
        if (SB_DRAW_IS_INSTANCE(s, d) && (!which || which[d])) nv += s->draws[d].index_count, ni += s->draws[d].index_count;
    out->vertices = s->vertices, out->vertex_count = s->vertex_count;
    out->indices = s->indices, out->index_count = s->index_count;
    if (ni == s->index_count) return;
    /* each expanded draw's vertices: those its triangles use, once (a chunk's of its primitive's) */
    float *v = sb_xmalloc(SB_VERTEX_BYTES * (size_t)nv);
    uint32_t *ix = sb_xmalloc(sizeof(uint32_t) * (size_t)ni);
    memcpy(v, s->vertices, (size_t)s->vertex_count * SB_VERTEX_BYTES);
    memcpy(ix, s->indices, (size_t)s->index_count * sizeof(uint32_t));
    uint32_t *seen = sb_xcalloc(s->vertex_count ? s->vertex_count : 1, sizeof(uint32_t)), *at = sb_xmalloc(
        sizeof(uint32_t) * (s->vertex_count ? s->vertex_count : 1));
    uint32_t vn = s->vertex_count, in = s->index_count;
    for (uint32_t d = 0; d < s->draw_count; d++) {
        const sb_draw *dr = &s->draws[d];
        if (!SB_DRAW_IS_INSTANCE(s, d) || (which && !which[d])) continue;
        out->first[d] = in;
        const float *x = dr->xform;
        for (uint32_t i = 0; i < dr->index_count; i++) {
            uint32_t src = s->indices[dr->first_index + i];
            if (seen[src] != d + 1) {   /* placed: the position by the transform, the normal turned (a similarity) */
                seen[src] = d + 1;
                at[src] = vn;
                float *o = v + (size_t)SB_VERTEX_FLOATS * vn++;
                const float *p = sb_vertex(s, src);
                memcpy(o, p, SB_VERTEX_BYTES);
                sb_draw_point(s, dr, src, o);
                float n[3];
                for (int r = 0; r < 3; r++) n[r] = x[4 * r] * p[3] + x[4 * r + 1] * p[4] + x[4 * r + 2] * p[5];
                float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                for (int r = 0; r < 3; r++) o[3 + r] = len > 0 ? n[r] / len : 0;
            }
            ix[in++] = at[src];
        }
    }
    free(seen);
    free(at);
    out->vertices = v, out->vertex_count = vn;
    out->indices = ix, out->index_count = in;
    out->owned = true;
}

void sb_scene_flat_free(sb_scene_flat *f) {
    if (f->owned) {
        free((void *)f->vertices);
        free((void *)f->indices);
    }
    free(f->first);
    memset(f, 0, sizeof *f);
}

double sb_scene_cpu_bytes(const sb_scene *s) {
    double b = (double)s->vertex_count * SB_VERTEX_BYTES + (double)s->index_count * sizeof(uint32_t) +
               (double)s->draw_count * sizeof(sb_draw) + (double)s->material_count * sizeof(sb_material) +
               (double)s->texture_count * sizeof(sb_texture) + s->texel_count +
               (double)s->light_count * sizeof(sb_light) + (double)s->camera_count * sizeof(sb_scene_camera) +
               (double)s->bvh.node_count * sizeof(sb_bvh_node) + (double)s->draw_count * sizeof(uint32_t);
    for (uint32_t i = 0; i < s->plane_count; i++) b += (double)s->planes[i].tri_count * sizeof(uint32_t);
    return b;
}

const sb_light *sb_scene_point_light(const sb_scene *s, int index, int *count) {
    const sb_light *found = NULL;
    int k = 0;
    for (uint32_t i = 0; i < s->light_count; i++)
        if (s->lights[i].type != SB_LIGHT_DIRECTIONAL && k++ == index) found = &s->lights[i];
    if (count) *count = k;
    return found;
}

static bool light_add(sb_light_set *o, int idx, const char *spec, sb_err *err) {
    for (int i = 0; i < o->count; i++)
        if (o->idx[i] == idx) return sb_fail(err, "--lights %s: a light named twice", spec);
    if (o->count >= SB_MAX_LIGHTS) return sb_fail(err, "--lights %s: more than %d lights", spec, SB_MAX_LIGHTS);
    o->idx[o->count++] = (int16_t)idx;
    return true;
}

bool sb_scene_light_set(const sb_scene *s, const char *spec, bool has_sun, sb_light_set *out, sb_err *err) {
    int lamps = 0;
    sb_scene_point_light(s, 0, &lamps);
    memset(out, 0, sizeof *out);
    const char *p = spec;
    while (*p) {
        size_t n = strcspn(p, ",");
        char word[32];
        if (n == 0 || n >= sizeof word)
            return sb_fail(err, "--lights %s: expected sun, lamps, all, or sun and lamp numbers separated by commas", spec);
        memcpy(word, p, n);
        word[n] = 0;
        /* a lamp number is decimal digits alone ("01" is lamp 1; "+1" and " 1" are no number) */
        char *end = word;
        long k = -1;
        if (word[0] >= '0' && word[0] <= '9') k = strtol(word, &end, 10);
        bool sun = !strcmp(word, "sun") || (!strcmp(word, "all") && has_sun), every = !strcmp(word, "lamps") || !strcmp(word, "all");
        if (!strcmp(word, "sun") && !has_sun)
            return sb_fail(err, "--lights %s: the scene has no sun (no directional light; --sun AZ,EL adds one)", spec);
        if (sun && !light_add(out, SB_LIGHT_SUN, spec, err)) return false;
        if (every && !lamps && strcmp(word, "all"))
            return sb_fail(err, "--lights %s: the scene has no point or spot light", spec);
        for (int i = 0; every && i < lamps; i++)
            if (!light_add(out, i, spec, err)) return false;
        if (!sun && !every) {
            if (end == word || *end || k < 0)
                return sb_fail(err, "--lights %s: '%s' is not sun, lamps, all or a lamp number", spec, word);
            if (k >= lamps && !lamps) return sb_fail(err, "--lights %s: the scene has no point or spot light", spec);
            if (k >= lamps)
                return sb_fail(err, "--lights %s: the scene has no lamp %ld (its point and spot lights are 0..%d)", spec, k,
                               lamps - 1);
            if (!light_add(out, (int)k, spec, err)) return false;
        }
        p += n + (p[n] == ',');
        if (p[-1] == ',' && !*p) return sb_fail(err, "--lights %s: a comma at the end", spec);
    }
    if (!out->count) return sb_fail(err, "--lights %s: no light chosen", spec);
    /* one set, one order: the sun first, then the lamps by number (the same lights however they were listed) */
    for (int i = 1; i < out->count; i++)
        for (int j = i; j > 0 && out->idx[j - 1] > out->idx[j]; j--) {
            int16_t t = out->idx[j];
            out->idx[j] = out->idx[j - 1];
            out->idx[j - 1] = t;
        }
    return true;
}

void sb_light_set_text(const sb_scene *s, const sb_light_set *set, char *out, size_t len) {
    int lamps = 0, have = 0;
    bool sun = false;
    sb_scene_point_light(s, 0, &lamps);
    for (int i = 0; i < set->count; i++) {
        if (set->idx[i] == SB_LIGHT_SUN) sun = true;
        else have++;
    }
    out[0] = 0;
    if (have == lamps && lamps > 0) {   /* every lamp (the set holds each at most once) */
        snprintf(out, len, "%s", sun ? "all" : "lamps");
        return;
    }
    for (int i = 0; i < set->count; i++) {
        size_t l = strlen(out);
        if (set->idx[i] == SB_LIGHT_SUN) snprintf(out + l, len - l, "%ssun", l ? "," : "");
        else snprintf(out + l, len - l, "%s%d", l ? "," : "", set->idx[i]);
    }
}

/* Frees *p unless it points into the mapped cache entry. */
static void free_owned(const sb_scene *s, void *p) {
    const char *m = s->cache_map, *q = p;
    if (!m || q < m || q >= m + s->cache_map_len) free(p);
}

void sb_scene_free(sb_scene *s) {
    free(s->file);
    free_owned(s, s->vertices);
    free_owned(s, s->indices);
    free_owned(s, s->draws);
    free_owned(s, s->lights);
    free_owned(s, s->cameras);
    free(s->build_pos);
    free(s->build_rel);
    free_owned(s, s->materials);
    free_owned(s, s->textures);
    free_owned(s, s->texels);
    for (uint32_t i = 0; i < s->plane_count; i++) free_owned(s, s->planes[i].tris);
    sb_bvh_free(&s->bvh);
    sb_unmap_file(s->cache_map, s->cache_map_len);
    if (s->motion) s->motion_free(s->motion);
    memset(s, 0, sizeof *s);
}

/* ---- motion ---- */

/* The box of a draw over the vertices its triangles use, as they are now. */
static sb_aabb draw_box_now(const sb_scene *s, const sb_draw *d) {
    sb_aabb b = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
    for (uint32_t i = 0; i < d->index_count; i++) {
        const float *v = sb_vertex(s, s->indices[d->first_index + i]);
        sb_v3 p = sb_v3_make(v[0], v[1], v[2]);
        b.lo = sb_v3_min(b.lo, p), b.hi = sb_v3_max(b.hi, p);
    }
    return b;
}

void sb_scene_repose_prim(sb_scene *s, uint32_t first, uint32_t count, const double *pos, const double *nrm,
                          const uint32_t *draws, uint32_t ndraws, bool boxes) {
    for (uint32_t v = 0; v < count; v++) {
        float *o = sb_vertex(s, first + v);
        const double *p = pos + 3 * (size_t)v;
        o[0] = (float)(p[0] - s->origin.x);
        o[1] = (float)(p[1] - s->origin.y);
        o[2] = (float)(p[2] - s->origin.z);
        if (nrm) {
            sb_v3 n = sb_v3_norm(sb_v3_make(nrm[3 * (size_t)v], nrm[3 * (size_t)v + 1], nrm[3 * (size_t)v + 2]));
            o[3] = (float)n.x, o[4] = (float)n.y, o[5] = (float)n.z;
        } else {
            o[3] = o[4] = o[5] = 0;
        }
    }
    /* its draws (a primitive's chunks name all of its vertices): face normals where the file gave none, as at
       load, and their boxes */
    for (uint32_t k = 0; k < ndraws; k++) {
        sb_draw *dr = &s->draws[draws[k]];
        for (uint32_t i = 0; !nrm && i + 2 < dr->index_count; i += 3) {
            const uint32_t *t = s->indices + dr->first_index + i;
            const double *a = pos + 3 * (size_t)(t[0] - first), *b = pos + 3 * (size_t)(t[1] - first),
                         *c = pos + 3 * (size_t)(t[2] - first);
            sb_v3 n = sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                                  sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2]));
            for (int k = 0; k < 3; k++) {
                float *o = sb_vertex(s, t[k]);
                o[3] += (float)n.x, o[4] += (float)n.y, o[5] += (float)n.z;
            }
        }
        if (boxes) dr->box = draw_box_now(s, dr);
    }
    for (uint32_t v = 0; !nrm && v < count; v++) {
        float *o = sb_vertex(s, first + v);
        sb_v3 n = sb_v3_norm(sb_v3_make(o[3], o[4], o[5]));
        o[3] = (float)n.x, o[4] = (float)n.y, o[5] = (float)n.z;
    }
}

void sb_scene_info(const sb_scene *s, FILE *out) {
    const sb_scene_features *f = &s->features;
    uint32_t closed = 0;
    for (uint32_t i = 0; i < s->draw_count; i++) closed += s->draws[i].closed;
    sb_v3 e = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    fprintf(out, "scene: %s\ntriangles: %llu in %u draws (%u primitives, %u mesh nodes)\n", s->file,
            (unsigned long long)sb_scene_triangles(s), s->draw_count, f->prims, s->nodes_drawn);
    char parts[256];
    sb_scene_load_parts(s, parts, sizeof parts);
    fprintf(out, "loaded in: %.0f ms (%s)\n", s->load_ms, parts);
    sb_v3 lo = sb_v3_add(s->bounds.lo, s->origin), hi = sb_v3_add(s->bounds.hi, s->origin);
    fprintf(out, "size: %.6g x %.6g x %.6g\nbounds: %.9g %.9g %.9g .. %.9g %.9g %.9g (world)\nsun: %s\nlights: %u\n"
            "cameras: %u\n", e.x, e.y, e.z, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z,
            s->has_sun ? "from the file" : "none in the file (default or --sun)", s->light_count, s->camera_count);
    fprintf(out, "double-sided primitives: %u (back faces drawn and hit)\n", f->double_sided);
    fprintf(out, "single-sided draws: %u (back faces culled in every pass and not hit by rays; %u closed)\n",
            s->single_sided_draws, closed);
    fprintf(out, "alpha MASK primitives: %u (alpha-tested in every pass and by the rays; volumes extrudes them whole)\n",
            f->mask);
    fprintf(out, "alpha BLEND primitives: %u (--blend-casters %s: %s)\n", f->blend, sb_blend_policy_name(s->opts.blend),
            s->opts.blend == SB_BLEND_NONE ? "left out" : s->opts.blend == SB_BLEND_OPAQUE ? "opaque" : "alpha-tested at 0.5");
    fprintf(out, "alpha textures: %u decoded, %u not decodable (alpha factor alone); %u other images not decoded\n",
            f->textures_decoded, f->undecodable_alpha, f->textures_skipped);
    fprintf(out, "skins: %u (%u primitives skinned on the CPU, %s)\n", f->skins, f->skinned,
            f->posed ? "posed at --pose" : "in the nodes' own pose");
    fprintf(out, "instancing (EXT_mesh_gpu_instancing): %u nodes, %u instances (expanded)\n", f->instanced_nodes,
            f->instances);
    fprintf(out, "shared geometry: %u of %u draws repeat another's triangles under a rotation, uniform scale and "
            "translation (held once: on the CPU, the GPU and in the reference's BVH)\n", s->instance_draws, s->draw_count);
    fprintf(out, "Draco-compressed primitives: %u (decoded)\n", f->draco);
    fprintf(out, "vertex-colour alpha on alpha-tested primitives: %u (ignored)\n", f->vertex_alpha_ignored);
    fprintf(out, "degenerate: %s\n", s->degenerate[0] ? s->degenerate : "no");
    fprintf(out, "unused (left out, not refused): %s\n", s->unused[0] ? s->unused : "nothing");
}

/* ---- culling and rays over the draws' BVH ---- */

static sb_boxes draw_boxes(const sb_scene *s) {
    return (sb_boxes){s->draw_count ? &s->draws[0].box : NULL, sizeof(sb_draw), s->draw_count};
}

void sb_scene_build_bvh(sb_scene *s) { sb_bvh_build(&s->bvh, draw_boxes(s)); }
void sb_scene_refit_bvh(sb_scene *s) { sb_bvh_refit(&s->bvh, draw_boxes(s)); }

uint32_t sb_scene_cull(const sb_scene *s, const double (*planes)[4], int plane_count, sb_bvh_visit visit, void *user) {
    return sb_bvh_cull(&s->bvh, draw_boxes(s), planes, plane_count, visit, user);
}

typedef struct {
    uint32_t *out, n;
} collector;

static void collect(uint32_t d, void *user) {
    collector *c = user;
    c->out[c->n++] = d;
}

uint32_t sb_scene_collect(const sb_scene *s, const double (*planes)[4], int plane_count, uint32_t *out) {
    collector c = {out, 0};
    sb_scene_cull(s, planes, plane_count, collect, &c);
    return c.n;
}

/* Möller-Trumbore, both sides; t of the hit or INFINITY; *n the (unnormalised) front normal. */
static double ray_tri(const float *a, const float *b, const float *c, sb_v3 o, sb_v3 d, sb_v3 *n) {
    sb_v3 A = {a[0], a[1], a[2]}, e1 = sb_v3_sub(sb_v3_make(b[0], b[1], b[2]), A), e2 = sb_v3_sub(sb_v3_make(c[0], c[1], c[2]), A);
    sb_v3 p = sb_v3_cross(d, e2);
    double det = sb_v3_dot(e1, p);
    *n = sb_v3_make(0, 0, 0);
    if (fabs(det) < 1e-300) return INFINITY;
    sb_v3 s = sb_v3_sub(o, A), q = sb_v3_cross(s, e1);
    double u = sb_v3_dot(s, p) / det, v = sb_v3_dot(d, q) / det, t = sb_v3_dot(e2, q) / det;
    if (u < 0 || v < 0 || u + v > 1 || t <= 0) return INFINITY;
    *n = sb_v3_cross(e1, e2);
    return t;
}

double sb_scene_raycast(const sb_scene *s, sb_v3 o, sb_v3 d, double tmax, bool *backface) {
    double best = INFINITY;
    if (!s->bvh.node_count) return best;
    sb_v3 inv = sb_v3_make(1 / d.x, 1 / d.y, 1 / d.z);
    int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const sb_bvh_node *nd = &s->bvh.nodes[stack[--top]];
        if (!sb_ray_box(&nd->box, o, inv, best < tmax ? best : tmax)) continue;
        if (nd->left >= 0 && top + 2 <= 128) {
            stack[top++] = nd->left;
            stack[top++] = nd->right;
            continue;
        }
        for (uint32_t i = nd->first; i < nd->first + nd->count; i++) {
            const sb_draw *dr = &s->draws[s->bvh.items[i]];
            if (!sb_ray_box(&dr->box, o, inv, best < tmax ? best : tmax)) continue;
            for (uint32_t k = dr->first_index; k + 2 < dr->first_index + dr->index_count; k += 3) {
                sb_v3 n;
                float p[9];
                for (int c = 0; c < 3; c++) sb_draw_point(s, dr, s->indices[k + c], p + 3 * c);
                double t = ray_tri(p, p + 3, p + 6, o, d, &n);
                if (t < best && t < tmax) {
                    best = t;
                    if (backface) *backface = !dr->double_sided && dr->closed && sb_v3_dot(n, d) > 0;
                }
            }
        }
    }
    return best;
}
