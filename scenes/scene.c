/* scene.c - building the flat scene model, re-basing, chunking, bundled names. */
#include "scene.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define SB_CHUNK_TRIS 4096u

bool sb_gltf_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err); /* gltf_load.cc */

void sb_scene_begin(sb_scene *s) {
    memset(s, 0, sizeof *s);
}

static void *grow(void *p, uint32_t *cap, uint32_t need, size_t elem) {
    if (need <= *cap) return p;
    uint32_t c = *cap ? *cap : 1024;
    while (c < need) c *= 2;
    *cap = c;
    return sb_xrealloc(p, (size_t)c * elem);
}

void sb_scene_add_prim(sb_scene *s, const sb_prim_desc *p) {
    uint32_t base = s->vertex_count;
    uint32_t cap = s->build_cap;
    s->build_pos = grow(s->build_pos, &cap, base + p->vertex_count, 3 * sizeof(double));
    s->vertices = grow(s->vertices, &s->vertex_cap, base + p->vertex_count, 6 * sizeof(float));
    s->build_cap = cap;
    for (uint32_t v = 0; v < p->vertex_count; v++) {
        memcpy(s->build_pos + 3 * (size_t)(base + v), p->positions + 3 * (size_t)v, 3 * sizeof(double));
        float *out = s->vertices + 6 * (size_t)(base + v);
        out[3] = out[4] = out[5] = 0;
        if (p->normals) {
            sb_v3 n = sb_v3_norm(sb_v3_make(p->normals[3 * v], p->normals[3 * v + 1], p->normals[3 * v + 2]));
            out[3] = (float)n.x;
            out[4] = (float)n.y;
            out[5] = (float)n.z;
        }
    }
    if (!p->normals) { /* area-weighted vertex normals from the faces */
        for (uint32_t i = 0; i + 2 < p->index_count; i += 3) {
            const double *a = p->positions + 3 * (size_t)p->indices[i];
            const double *b = p->positions + 3 * (size_t)p->indices[i + 1];
            const double *c = p->positions + 3 * (size_t)p->indices[i + 2];
            sb_v3 n = sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                                  sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2]));
            for (int k = 0; k < 3; k++) {
                float *out = s->vertices + 6 * (size_t)(base + p->indices[i + k]);
                out[3] += (float)n.x;
                out[4] += (float)n.y;
                out[5] += (float)n.z;
            }
        }
        for (uint32_t v = 0; v < p->vertex_count; v++) {
            float *out = s->vertices + 6 * (size_t)(base + v);
            sb_v3 n = sb_v3_norm(sb_v3_make(out[3], out[4], out[5]));
            out[3] = (float)n.x;
            out[4] = (float)n.y;
            out[5] = (float)n.z;
        }
    }
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
    d->alpha_mask = p->alpha_mask;
    d->alpha_cutoff = p->alpha_cutoff;
    d->node = p->node;
    if (p->alpha_mask) s->alpha_mask_draws++;
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
    chunk_draws(s);
    sb_aabb all = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
    for (uint32_t i = 0; i < s->draw_count; i++) {
        s->draws[i].box = tri_range_box(s, s->draws[i].first_index, s->draws[i].index_count);
        all.lo = sb_v3_min(all.lo, s->draws[i].box.lo);
        all.hi = sb_v3_max(all.hi, s->draws[i].box.hi);
    }
    s->origin = sb_v3_scale(sb_v3_add(all.lo, all.hi), 0.5);
    for (uint32_t v = 0; v < s->vertex_count; v++) {
        const double *p = s->build_pos + 3 * (size_t)v;
        float *o = s->vertices + 6 * (size_t)v;
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
    sb_bvh_build(s);
    sb_scene_find_planes(s);
    return true;
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
        const float *a = s->vertices + 6 * (size_t)s->indices[3 * t], *b = s->vertices + 6 * (size_t)s->indices[3 * t + 1],
                    *c = s->vertices + 6 * (size_t)s->indices[3 * t + 2];
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
                const float *a = s->vertices + 6 * (size_t)s->indices[3 * t0], *b = s->vertices + 6 * (size_t)s->indices[3 * t0 + 1],
                            *c = s->vertices + 6 * (size_t)s->indices[3 * t0 + 2];
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
    for (uint32_t i = 0; i < s->plane_count; i++) free(s->planes[i].tris);
    sb_bvh_free(&s->bvh);
    memset(s, 0, sizeof *s);
}
