/* scene.c - building the flat scene model, re-basing, chunking, bundled names. */
#include "scene.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>


bool sb_gltf_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err); /* gltf_load.cc */

static void *grow(void *p, uint32_t *cap, uint32_t need, size_t elem) {
    if (need <= *cap) return p;
    uint32_t c = *cap ? *cap : 1024;
    while (c < need) c *= 2;
    *cap = c;
    return sb_xrealloc(p, (size_t)c * elem);
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

bool sb_blend_policy_parse(const char *v, sb_blend_policy *out) {
    for (int p = SB_BLEND_MASK; p <= SB_BLEND_NONE; p++)
        if (!strcmp(v, sb_blend_policy_name((sb_blend_policy)p))) return *out = (sb_blend_policy)p, true;
    return false;
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

static int cmp_u64(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

typedef struct {
    double p[3];
    uint32_t v;
} weld_key;

static int cmp_weld(const void *a, const void *b) {
    const weld_key *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->p[k] != y->p[k]) return x->p[k] < y->p[k] ? -1 : 1;
    return x->v < y->v ? -1 : x->v > y->v;
}

/* Whether the primitive is a closed surface with consistent winding: with
 * vertices welded by position, every directed edge a->b appears once and so
 * does b->a. Then each ray from outside crossing it leaves through a face
 * turned its way, so back faces can be culled without changing any answer. */
static bool prim_closed(const sb_prim_desc *p) {
    uint32_t nv = p->vertex_count, nt = p->index_count / 3;
    if (nt < 4) return false;
    weld_key *k = sb_xmalloc(sizeof *k * nv);
    uint32_t *id = sb_xmalloc(sizeof(uint32_t) * nv);
    for (uint32_t v = 0; v < nv; v++) memcpy(k[v].p, p->positions + 3 * (size_t)v, sizeof k[v].p), k[v].v = v;
    qsort(k, nv, sizeof *k, cmp_weld);
    for (uint32_t i = 0, w = 0; i < nv; i++) {
        if (i > 0 && memcmp(k[i].p, k[i - 1].p, sizeof k[i].p)) w = i;
        id[k[i].v] = w;
    }
    uint64_t *e = sb_xmalloc(sizeof(uint64_t) * 3 * nt);
    bool closed = true;
    for (uint32_t t = 0; t < nt && closed; t++)
        for (int j = 0; j < 3; j++) {
            uint32_t a = id[p->indices[3 * t + j]], b = id[p->indices[3 * t + (j + 1) % 3]];
            closed &= a != b;
            e[3 * t + j] = (uint64_t)a << 32 | b;
        }
    if (closed) qsort(e, 3 * (size_t)nt, sizeof *e, cmp_u64);
    for (size_t i = 0; closed && i < 3 * (size_t)nt; i++) {
        uint64_t rev = e[i] << 32 | e[i] >> 32;
        closed = (i + 1 == 3 * (size_t)nt || e[i + 1] != e[i]) && bsearch(&rev, e, 3 * (size_t)nt, sizeof *e, cmp_u64);
    }
    free(e);
    free(id);
    free(k);
    return closed;
}

void sb_scene_add_prim(sb_scene *s, const sb_prim_desc *p) {
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

    s->draws = grow(s->draws, &s->draw_cap, s->draw_count + 1, sizeof(sb_draw));
    sb_draw *d = &s->draws[s->draw_count++];
    memset(d, 0, sizeof *d);
    d->first_index = first;
    d->index_count = p->index_count;
    memcpy(d->color, p->color, sizeof d->color);
    d->double_sided = p->double_sided;
    d->closed = !p->double_sided && prim_closed(p);
    d->material = p->material;
    d->node = p->node;
}

/* ---- chunking: split a draw's triangles at the centroid median until small ---- */

/* A triangle's sort key: three times its centroid on the split axis, then its
 * number (equal centroids keep their order: the sort is stable). */
typedef struct {
    double key;
    uint32_t tri;
} tri_key;

static int cmp_tri(const void *a, const void *b) {
    const tri_key *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->tri < y->tri ? -1 : x->tri > y->tri;
}

static sb_aabb tri_range_box(const sb_scene *s, uint32_t first_index, uint32_t count) {
    sb_aabb b = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
    for (uint32_t i = first_index; i < first_index + count; i++) {
        const double *p = s->build_pos + 3 * (size_t)s->indices[i];
        sb_v3 v = {p[0], p[1], p[2]};
        b.lo = sb_v3_min(b.lo, v);
        b.hi = sb_v3_max(b.hi, v);
    }
    return b;
}

typedef struct {
    uint32_t *first, *count;
    uint32_t n, cap;
} leaf_list;

/* Orders triangles [tri_first, tri_first+n) of the index array spatially (median
 * splits on the longest axis) and records each final run as a leaf. */
static void split_order(sb_scene *s, tri_key *order, uint32_t tri_first, uint32_t n, leaf_list *out) {
    if (n <= SB_CHUNK_TRIS) {
        uint32_t c1 = out->cap, c2 = out->cap;
        out->first = grow(out->first, &c1, out->n + 1, sizeof(uint32_t));
        out->count = grow(out->count, &c2, out->n + 1, sizeof(uint32_t));
        out->cap = c1;
        out->first[out->n] = tri_first;
        out->count[out->n++] = n;
        return;
    }
    sb_aabb b = tri_range_box(s, tri_first * 3, n * 3);
    sb_v3 e = sb_v3_sub(b.hi, b.lo);
    int axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
    tri_key *k = order;
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t *t = s->indices + 3 * (size_t)(tri_first + i);
        const double *p = s->build_pos;
        k[i] = (tri_key){p[3 * (size_t)t[0] + axis] + p[3 * (size_t)t[1] + axis] + p[3 * (size_t)t[2] + axis],
                         tri_first + i};
    }
    qsort(k, n, sizeof *k, cmp_tri);
    uint32_t *tmp = sb_xmalloc((size_t)n * 3 * sizeof(uint32_t));
    for (uint32_t i = 0; i < n; i++) memcpy(tmp + 3 * (size_t)i, s->indices + 3 * (size_t)k[i].tri, 12);
    memcpy(s->indices + 3 * (size_t)tri_first, tmp, (size_t)n * 12);
    free(tmp);
    uint32_t half = n / 2;
    split_order(s, order, tri_first, half, out);
    split_order(s, order, tri_first + half, n - half, out);
}

static void chunk_draws(sb_scene *s) {
    uint32_t n = s->draw_count;
    for (uint32_t di = 0; di < n; di++) {
        sb_draw d = s->draws[di];
        uint32_t tris = d.index_count / 3;
        if (tris <= SB_CHUNK_TRIS) continue;
        tri_key *order = sb_xmalloc(tris * sizeof *order);
        leaf_list leaves = {0};
        split_order(s, order, d.first_index / 3, tris, &leaves);
        free(order);
        for (uint32_t c = 0; c < leaves.n; c++) {
            sb_draw nd = d;
            nd.first_index = 3 * leaves.first[c];
            nd.index_count = 3 * leaves.count[c];
            if (c == 0) {
                s->draws[di] = nd;
            } else {
                s->draws = grow(s->draws, &s->draw_cap, s->draw_count + 1, sizeof(sb_draw));
                s->draws[s->draw_count++] = nd;
            }
        }
        free(leaves.first);
        free(leaves.count);
    }
}

bool sb_scene_finish(sb_scene *s, sb_err *err) {
    if (s->index_count == 0) {
        free(s->build_pos);
        s->build_pos = NULL;
        return sb_fail(err, "%s: the scene has no triangles reachable from its scene graph", s->file);
    }
    double t0 = sb_now_ms();
    chunk_draws(s);
    for (uint32_t i = 0; i < s->draw_count; i++) {
        s->alpha_tested_draws += s->draws[i].material != 0;
        s->single_sided_draws += !s->draws[i].double_sided;
    }
    sb_aabb all = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
    for (uint32_t i = 0; i < s->draw_count; i++) {
        s->draws[i].box = tri_range_box(s, s->draws[i].first_index, s->draws[i].index_count);
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
                 "at one point)", s->index_count / 3);
    free(s->build_pos);
    s->build_pos = NULL;
    double t1 = sb_now_ms();
    sb_bvh_build(s);
    double t2 = sb_now_ms();
    sb_scene_find_planes(s);
    s->load_part_ms[SB_LOAD_DRAWS] = t1 - t0;
    s->load_part_ms[SB_LOAD_BVH] = t2 - t1;
    s->load_part_ms[SB_LOAD_PLANES] = sb_now_ms() - t2;
    return true;
}

const char *const sb_load_part_names[SB_LOAD_PARTS] = {"parse", "flatten", "draws", "bvh", "planes"};

void sb_scene_load_parts(const sb_scene *s, char *out, size_t len) {
    size_t n = 0;
    out[0] = 0;
    for (int i = 0; i < SB_LOAD_PARTS && n < len; i++)
        n += (size_t)snprintf(out + n, len - n, "%s%s %.0f", i ? ", " : "", sb_load_part_names[i], s->load_part_ms[i]);
}

typedef struct {
    int64_t key[4];     /* quantised plane */
    uint32_t tri;
    double area;
} plane_tri;

static int cmp_plane_tri(const void *a, const void *b) {
    const plane_tri *x = a, *y = b;
    for (int k = 0; k < 4; k++)
        if (x->key[k] != y->key[k]) return x->key[k] < y->key[k] ? -1 : 1;
    return x->tri < y->tri ? -1 : x->tri > y->tri;
}

void sb_scene_find_planes(sb_scene *s) {
    uint32_t ntri = s->index_count / 3;
    sb_v3 ext = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    double face = fmax(ext.x * ext.y, fmax(ext.y * ext.z, ext.x * ext.z)), diag = sb_v3_len(ext);
    if (ntri == 0 || face <= 0) return;
    plane_tri *pt = sb_xmalloc(sizeof *pt * ntri);
    uint32_t m = 0;
    for (uint32_t t = 0; t < ntri; t++) {
        const float *a = sb_vertex(s, s->indices[3 * t]), *b = sb_vertex(s, s->indices[3 * t + 1]),
                    *c = sb_vertex(s, s->indices[3 * t + 2]);
        sb_v3 n = sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                              sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2]));
        double area = 0.5 * sb_v3_len(n);
        if (area <= 0) continue;
        n = sb_v3_norm(n);
        double d = -(n.x * a[0] + n.y * a[1] + n.z * a[2]);
        pt[m++] = (plane_tri){{llround(n.x * 1e3), llround(n.y * 1e3), llround(n.z * 1e3), llround(d / diag * 1e4)},
                              t, area};
    }
    qsort(pt, m, sizeof *pt, cmp_plane_tri);
    for (uint32_t i = 0; i < m;) {
        uint32_t j = i;
        double area = 0;
        while (j < m && !memcmp(pt[j].key, pt[i].key, sizeof pt[i].key)) area += pt[j++].area;
        if (area >= 0.1 * face) {
            /* keep the largest SB_MAX_PLANES */
            int slot = -1;
            if (s->plane_count < SB_MAX_PLANES) slot = (int)s->plane_count++;
            else
                for (int k = 0; k < SB_MAX_PLANES; k++)
                    if (s->planes[k].area < area && (slot < 0 || s->planes[k].area < s->planes[slot].area)) slot = k;
            if (slot >= 0) {
                sb_plane *p = &s->planes[slot];
                free(p->tris);
                const uint32_t t0 = pt[i].tri;
                const float *a = sb_vertex(s, s->indices[3 * t0]), *b = sb_vertex(s, s->indices[3 * t0 + 1]),
                            *c = sb_vertex(s, s->indices[3 * t0 + 2]);
                sb_v3 n = sb_v3_norm(sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                                                 sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2])));
                p->n[0] = n.x;
                p->n[1] = n.y;
                p->n[2] = n.z;
                p->d = -(n.x * a[0] + n.y * a[1] + n.z * a[2]);
                p->area = area;
                p->tri_count = j - i;
                p->tris = sb_xmalloc(sizeof(uint32_t) * p->tri_count);
                for (uint32_t k = i; k < j; k++) p->tris[k - i] = pt[k].tri;
            }
        }
        i = j;
    }
    free(pt);
}

uint64_t sb_scene_triangles(const sb_scene *s) { return s->index_count / 3; }

const sb_light *sb_scene_point_light(const sb_scene *s, int index, int *count) {
    const sb_light *found = NULL;
    int k = 0;
    for (uint32_t i = 0; i < s->light_count; i++)
        if (s->lights[i].type != SB_LIGHT_DIRECTIONAL && k++ == index) found = &s->lights[i];
    if (count) *count = k;
    return found;
}

static bool exe_dir(char *out, size_t len) {
    char buf[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
    if (n <= 0) return false;
    buf[n] = 0;
    char *slash = strrchr(buf, '/');
    if (!slash) return false;
    *slash = 0;
    if (strlen(buf) >= len) return false;
    memcpy(out, buf, strlen(buf) + 1);
    return true;
}

bool sb_resolve_bundled(const char *name, const char *ext, char *out, size_t outlen) {
    if (strchr(name, '/') || strchr(name, '.')) return false;
    char dirs[3][PATH_MAX];
    int nd = 0;
    const char *env = getenv("SB_DATA_DIR");
    if (env) snprintf(dirs[nd++], PATH_MAX, "%s", env);
    char ed[PATH_MAX - 64];
    if (exe_dir(ed, sizeof ed)) {
        snprintf(dirs[nd++], PATH_MAX, "%s", ed);
        snprintf(dirs[nd++], PATH_MAX, "%s/../share/shadowbench", ed);
    }
    for (int i = 0; i < nd; i++) {
        snprintf(out, outlen, "%s/%s%s", dirs[i], name, ext);
        if (access(out, R_OK) == 0) return true;
    }
    return false;
}

bool sb_scene_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err) {
    char resolved[PATH_MAX];
    if (sb_resolve_bundled(path, ".glb", resolved, sizeof resolved)) path = resolved;
    double t0 = sb_now_ms();
    sb_scene_begin(s);
    s->file = sb_strdup(path);
    if (opts) s->opts = *opts;
    if (!sb_gltf_load(s, path, opts, err)) {
        sb_scene_free(s);
        return false;
    }
    if (!sb_scene_finish(s, err)) {
        sb_scene_free(s);
        return false;
    }
    /* options that change what is drawn change the run ids (the defaults leave them as they were) */
    if (s->opts.blend != SB_BLEND_MASK && s->features.blend)
        s->content_hash = sb_fnv1a(s->content_hash, &s->opts.blend, sizeof s->opts.blend);
    if (s->opts.pose) s->content_hash = sb_fnv1a(s->content_hash, &s->opts.pose_time, sizeof s->opts.pose_time);
    s->load_ms = sb_now_ms() - t0;
    return true;
}

void sb_scene_free(sb_scene *s) {
    free(s->file);
    free(s->vertices);
    free(s->indices);
    free(s->draws);
    free(s->lights);
    free(s->cameras);
    free(s->build_pos);
    free(s->materials);
    free(s->textures);
    free(s->texels);
    for (uint32_t i = 0; i < s->plane_count; i++) free(s->planes[i].tris);
    sb_bvh_free(&s->bvh);
    memset(s, 0, sizeof *s);
}

void sb_scene_info(const sb_scene *s, FILE *out) {
    const sb_scene_features *f = &s->features;
    uint32_t closed = 0;
    for (uint32_t i = 0; i < s->draw_count; i++) closed += s->draws[i].closed;
    sb_v3 e = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    fprintf(out, "scene: %s\ntriangles: %llu in %u draws (%u primitives, %u mesh nodes)\n", s->file,
            (unsigned long long)sb_scene_triangles(s), s->draw_count, f->prims, s->nodes_drawn);
    fprintf(out, "size: %.6g x %.6g x %.6g\nsun: %s\nlights: %u\ncameras: %u\n", e.x, e.y, e.z,
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
    fprintf(out, "Draco-compressed primitives: %u (decoded)\n", f->draco);
    fprintf(out, "vertex-colour alpha on alpha-tested primitives: %u (ignored)\n", f->vertex_alpha_ignored);
    fprintf(out, "degenerate: %s\n", s->degenerate[0] ? s->degenerate : "no");
}
