/* bvh.c - a bounding volume hierarchy over boxes, and exact AABB-versus-planes
 * culling over it (bvh.h). */
#include "bvh.h"

#include <stdlib.h>
#include <string.h>

#include "util.h"

#define SB_BVH_LEAF 2

typedef struct {
    sb_boxes boxes;
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

static void sort_items(sb_boxes boxes, uint32_t *items, uint32_t count, int axis) {
    draw_key *k = sb_xmalloc(sizeof *k * count);
    for (uint32_t i = 0; i < count; i++) k[i] = (draw_key){centre(sb_boxes_at(boxes, items[i]), axis), i, items[i]};
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
    sb_aabb box = *sb_boxes_at(bd->boxes, b->items[first]);
    sb_v3 clo = {1e300, 1e300, 1e300}, chi = {-1e300, -1e300, -1e300};
    for (uint32_t i = first; i < first + count; i++) {
        const sb_aabb *db = sb_boxes_at(bd->boxes, b->items[i]);
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
    sort_items(bd->boxes, b->items + first, count, axis);
    uint32_t half = count / 2;
    int32_t l = build(bd, first, half);
    int32_t r = build(bd, first + half, count - half);
    b->nodes[idx].left = l;
    b->nodes[idx].right = r;
    return idx;
}

void sb_bvh_build(sb_bvh *b, sb_boxes boxes) {
    sb_bvh_free(b);
    if (boxes.count == 0) return;
    b->items = sb_xmalloc(boxes.count * sizeof(uint32_t));
    for (uint32_t i = 0; i < boxes.count; i++) b->items[i] = i;
    builder bd = {boxes, b, 0};
    build(&bd, 0, boxes.count);
}

void sb_bvh_refit(sb_bvh *b, sb_boxes boxes) {
    for (uint32_t n = b->node_count; n-- > 0;) {
        sb_bvh_node *node = &b->nodes[n];
        if (node->left < 0) {
            node->box = *sb_boxes_at(boxes, b->items[node->first]);
            for (uint32_t i = node->first + 1; i < node->first + node->count; i++) {
                const sb_aabb *db = sb_boxes_at(boxes, b->items[i]);
                node->box.lo = sb_v3_min(node->box.lo, db->lo);
                node->box.hi = sb_v3_max(node->box.hi, db->hi);
            }
        } else {
            const sb_aabb *l = &b->nodes[node->left].box, *r = &b->nodes[node->right].box;
            node->box = (sb_aabb){sb_v3_min(l->lo, r->lo), sb_v3_max(l->hi, r->hi)};
        }
    }
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

static uint32_t cull(const sb_bvh *b, sb_boxes boxes, int32_t n, const double (*planes)[4], int pc,
                     sb_bvh_visit visit, void *user) {
    const sb_bvh_node *node = &b->nodes[n];
    for (int i = 0; i < pc; i++)
        if (sb_aabb_outside_plane(&node->box, planes[i])) return 0;
    if (node->left < 0) {
        uint32_t hits = 0;
        for (uint32_t i = node->first; i < node->first + node->count; i++) {
            uint32_t d = b->items[i];
            bool out = false;
            for (int k = 0; k < pc && !out; k++) out = sb_aabb_outside_plane(sb_boxes_at(boxes, d), planes[k]);
            if (out) continue;
            visit(d, user);
            hits++;
        }
        return hits;
    }
    return cull(b, boxes, node->left, planes, pc, visit, user) + cull(b, boxes, node->right, planes, pc, visit, user);
}

uint32_t sb_bvh_cull(const sb_bvh *b, sb_boxes boxes, const double (*planes)[4], int plane_count, sb_bvh_visit visit,
                     void *user) {
    if (!b->node_count) return 0;
    return cull(b, boxes, 0, planes, plane_count, visit, user);
}

bool sb_ray_box(const sb_aabb *b, sb_v3 o, sb_v3 inv, double tmax) {
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
