/* bvh.c - a bounding volume hierarchy over the scene's draws, and exact
 * AABB-versus-planes culling over it. */
#include <stdlib.h>
#include <string.h>

#include "scene.h"

#define SB_BVH_LEAF 2

typedef struct {
    sb_scene *s;
    sb_bvh *b;
    uint32_t cap;
} builder;

static double centre(const sb_aabb *b, int axis) {
    const double *lo = &b->lo.x, *hi = &b->hi.x;
    return 0.5 * (lo[axis] + hi[axis]);
}

/* A draw's sort key: its box centre on the split axis, then its place before
 * the sort (so equal centres keep their order: the sort is stable). */
typedef struct {
    double key;
    uint32_t pos, draw;
} draw_key;

static int cmp_draw(const void *a, const void *b) {
    const draw_key *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->pos < y->pos ? -1 : x->pos > y->pos;
}

static void sort_items(const sb_scene *s, uint32_t *items, uint32_t count, int axis) {
    draw_key *k = sb_xmalloc(sizeof *k * count);
    for (uint32_t i = 0; i < count; i++) k[i] = (draw_key){centre(&s->draws[items[i]].box, axis), i, items[i]};
    qsort(k, count, sizeof *k, cmp_draw);
    for (uint32_t i = 0; i < count; i++) items[i] = k[i].draw;
    free(k);
}

static int32_t build(builder *bd, uint32_t first, uint32_t count) {
    sb_bvh *b = bd->b;
    if (b->node_count == bd->cap) {
        bd->cap = bd->cap ? bd->cap * 2 : 64;
        b->nodes = sb_xrealloc(b->nodes, bd->cap * sizeof *b->nodes);
    }
    int32_t idx = (int32_t)b->node_count++;
    sb_aabb box = bd->s->draws[b->items[first]].box;
    sb_v3 clo = {1e300, 1e300, 1e300}, chi = {-1e300, -1e300, -1e300};
    for (uint32_t i = first; i < first + count; i++) {
        const sb_aabb *db = &bd->s->draws[b->items[i]].box;
        box.lo = sb_v3_min(box.lo, db->lo);
        box.hi = sb_v3_max(box.hi, db->hi);
        sb_v3 c = sb_v3_scale(sb_v3_add(db->lo, db->hi), 0.5);
        clo = sb_v3_min(clo, c);
        chi = sb_v3_max(chi, c);
    }
    b->nodes[idx].box = box;
    b->nodes[idx].first = first;
    b->nodes[idx].count = count;
    b->nodes[idx].left = b->nodes[idx].right = -1;
    if (count <= SB_BVH_LEAF) return idx;
    sb_v3 ext = sb_v3_sub(chi, clo);
    int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    sort_items(bd->s, b->items + first, count, axis);
    uint32_t half = count / 2;
    int32_t l = build(bd, first, half);
    int32_t r = build(bd, first + half, count - half);
    b->nodes[idx].left = l;
    b->nodes[idx].right = r;
    return idx;
}

void sb_bvh_build(sb_scene *s) {
    sb_bvh_free(&s->bvh);
    if (s->draw_count == 0) return;
    s->bvh.items = sb_xmalloc(s->draw_count * sizeof(uint32_t));
    for (uint32_t i = 0; i < s->draw_count; i++) s->bvh.items[i] = i;
    builder bd = {s, &s->bvh, 0};
    build(&bd, 0, s->draw_count);
}

void sb_bvh_free(sb_bvh *b) {
    free(b->nodes);
    free(b->items);
    memset(b, 0, sizeof *b);
}

bool sb_aabb_outside_plane(const sb_aabb *b, const double p[4]) {
    /* the box corner farthest along the plane normal */
    double x = p[0] >= 0 ? b->hi.x : b->lo.x;
    double y = p[1] >= 0 ? b->hi.y : b->lo.y;
    double z = p[2] >= 0 ? b->hi.z : b->lo.z;
    return p[0] * x + p[1] * y + p[2] * z + p[3] < 0;
}

static uint32_t cull(const sb_scene *s, int32_t n, const double (*planes)[4], int pc,
                     sb_draw_visit visit, void *user) {
    const sb_bvh_node *node = &s->bvh.nodes[n];
    for (int i = 0; i < pc; i++)
        if (sb_aabb_outside_plane(&node->box, planes[i])) return 0;
    if (node->left < 0) {
        uint32_t hits = 0;
        for (uint32_t i = node->first; i < node->first + node->count; i++) {
            uint32_t d = s->bvh.items[i];
            bool out = false;
            for (int k = 0; k < pc && !out; k++) out = sb_aabb_outside_plane(&s->draws[d].box, planes[k]);
            if (out) continue;
            visit(d, user);
            hits++;
        }
        return hits;
    }
    return cull(s, node->left, planes, pc, visit, user) + cull(s, node->right, planes, pc, visit, user);
}

uint32_t sb_bvh_cull(const sb_scene *s, const double (*planes)[4], int plane_count,
                     sb_draw_visit visit, void *user) {
    if (!s->bvh.node_count) return 0;
    return cull(s, 0, planes, plane_count, visit, user);
}

typedef struct {
    uint32_t *out, n;
} collector;

static void collect(uint32_t d, void *user) {
    collector *c = user;
    c->out[c->n++] = d;
}

uint32_t sb_bvh_collect(const sb_scene *s, const double (*planes)[4], int plane_count, uint32_t *out) {
    collector c = {out, 0};
    sb_bvh_cull(s, planes, plane_count, collect, &c);
    return c.n;
}

/* ---- CPU ray casting (auto paths: is a camera outside the model?) ---- */

static bool ray_box(const sb_aabb *b, sb_v3 o, sb_v3 inv, double tmax) {
    const double *lo = &b->lo.x, *hi = &b->hi.x, *oo = &o.x, *iv = &inv.x;
    double t0 = 0, t1 = tmax;
    for (int k = 0; k < 3; k++) {
        double a = (lo[k] - oo[k]) * iv[k], c = (hi[k] - oo[k]) * iv[k];
        if (a > c) {
            double t = a;
            a = c, c = t;
        }
        t0 = a > t0 ? a : t0;
        t1 = c < t1 ? c : t1;
        if (t0 > t1) return false;
    }
    return true;
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
        if (!ray_box(&nd->box, o, inv, best < tmax ? best : tmax)) continue;
        if (nd->left >= 0 && top + 2 <= 128) {
            stack[top++] = nd->left;
            stack[top++] = nd->right;
            continue;
        }
        for (uint32_t i = nd->first; i < nd->first + nd->count; i++) {
            const sb_draw *dr = &s->draws[s->bvh.items[i]];
            if (!ray_box(&dr->box, o, inv, best < tmax ? best : tmax)) continue;
            for (uint32_t k = dr->first_index; k + 2 < dr->first_index + dr->index_count; k += 3) {
                sb_v3 n;
                double t = ray_tri(sb_vertex(s, s->indices[k]), sb_vertex(s, s->indices[k + 1]),
                                   sb_vertex(s, s->indices[k + 2]), o, d, &n);
                if (t < best && t < tmax) {
                    best = t;
                    if (backface) *backface = !dr->double_sided && dr->closed && sb_v3_dot(n, d) > 0;
                }
            }
        }
    }
    return best;
}
