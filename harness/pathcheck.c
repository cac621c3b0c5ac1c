/* pathcheck.c - a path's cameras checked against the scene (pathcheck.h). */
#include "pathcheck.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const sb_path_verdict_names[SB_PATH_VERDICTS] = {"clear", "near", "below", "inside"};

static const char *const verdict_text[SB_PATH_VERDICTS] = {
    "", "a surface is closer than the near plane", "the camera is below a surface that faces up",
    "the camera is inside closed geometry"};

#define SPHERE 32           /* directions for the inside test */
#define RAYS (SPHERE + 1 + 5)

typedef struct {
    uint32_t first_tri, draw;
} draw_start;

static int by_first(const void *a, const void *b) {
    const draw_start *x = a, *y = b;
    return x->first_tri < y->first_tri ? -1 : x->first_tri > y->first_tri;
}

/* The draw a triangle belongs to (the draws' ranges sorted by their first triangle). */
static const sb_draw *draw_of(const sb_scene *s, const draw_start *ds, const sb_ref_hit *h) {
    if (h->draw != UINT32_MAX) return &s->draws[h->draw];   /* the reference knew it (an instance's run is shared) */
    uint32_t tri = h->prim;
    size_t lo = 0, hi = s->draw_count;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (ds[mid].first_tri <= tri) lo = mid;
        else hi = mid;
    }
    return s->draw_count ? &s->draws[ds[lo].draw] : NULL;
}

int sb_path_check(const sb_reference *r, const sb_scene *s, const sb_path *p, int n, double aspect, sb_path_frame *out,
                  int threads) {
    return sb_path_check_frames(r, s, p, 0, n, n, aspect, out, threads);
}

int sb_path_check_frames(const sb_reference *r, const sb_scene *s, const sb_path *p, int first, int n, int of,
                         double aspect, sb_path_frame *out, int threads) {
    draw_start *ds = sb_xmalloc(sizeof *ds * (s->draw_count ? s->draw_count : 1));
    for (uint32_t d = 0; d < s->draw_count; d++) ds[d] = (draw_start){s->draws[d].first_index / 3, d};
    qsort(ds, s->draw_count, sizeof *ds, by_first);
    /* every frame's rays in one batch: n x RAYS */
    float(*from)[3] = sb_xmalloc(sizeof *from * (size_t)n * RAYS), (*to)[3] = sb_xmalloc(sizeof *to * (size_t)n * RAYS);
    double *reach = sb_xmalloc(sizeof(double) * (size_t)n * RAYS);   /* frustum rays: the near plane's distance */
    sb_v3 ext = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    double far = 4 * sb_v3_len(ext) + 1;
    for (int f = 0; f < n; f++) {
        sb_camera c = sb_path_camera(p, first + f, of, aspect, s);
        sb_v3 eye = sb_v3_sub(c.pos, s->origin);
        sb_v3 dirs[RAYS];
        for (int k = 0; k < SPHERE; k++) {   /* a Fibonacci sphere */
            double z = 1 - (2 * k + 1.0) / SPHERE, rad = sqrt(1 - z * z), a = k * 2.399963229728653;
            dirs[k] = sb_v3_make(rad * cos(a), z, rad * sin(a));
        }
        dirs[SPHERE] = sb_v3_make(0, 1, 0);
        double ty = tan(c.fov_deg * SB_PI / 360), tx = ty * c.aspect;
        const double corner[5][2] = {{0, 0}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
        for (int k = 0; k < 5; k++) {
            sb_v3 d = sb_v3_add(c.forward, sb_v3_add(sb_v3_scale(c.right, corner[k][0] * tx),
                                                     sb_v3_scale(c.up, corner[k][1] * ty)));
            double len = sb_v3_len(d);
            dirs[SPHERE + 1 + k] = sb_v3_scale(d, 1 / len);
            reach[(size_t)f * RAYS + SPHERE + 1 + k] = c.znear * len;   /* to the near plane along it */
        }
        for (int k = 0; k < RAYS; k++) {
            size_t i = (size_t)f * RAYS + k;
            sb_v3 e = sb_v3_add(eye, sb_v3_scale(dirs[k], far));
            from[i][0] = (float)eye.x, from[i][1] = (float)eye.y, from[i][2] = (float)eye.z;
            to[i][0] = (float)e.x, to[i][1] = (float)e.y, to[i][2] = (float)e.z;
        }
    }
    sb_ref_hit *hits = sb_xmalloc(sizeof *hits * (size_t)n * RAYS);
    sb_reference_rays_all_faces(r, (const float(*)[3])from, (const float(*)[3])to, n * RAYS, hits, threads);
    int flagged = 0;
    for (int f = 0; f < n; f++) {
        const sb_ref_hit *h = hits + (size_t)f * RAYS;
        sb_path_frame v = {SB_PATH_CLEAR, -1};
        int met = 0, backs = 0;
        int64_t back_node = -1;
        for (int k = 0; k < SPHERE; k++) {
            if (!isfinite(h[k].t)) continue;
            met++;
            const sb_draw *d = draw_of(s, ds, &h[k]);
            if (!h[k].front && d && !d->double_sided) backs++, back_node = d->node;
        }
        for (int k = 0; k < 5; k++) {
            const sb_ref_hit *q = &h[SPHERE + 1 + k];
            if (isfinite(q->t) && q->t < reach[(size_t)f * RAYS + SPHERE + 1 + k]) {
                const sb_draw *d = draw_of(s, ds, q);
                v = (sb_path_frame){SB_PATH_NEAR, d ? (int64_t)d->node : -1};
            }
        }
        const sb_ref_hit *up = &h[SPHERE];
        /* the ray meets the back of a surface: the surface's front, turned from the ray, faces up */
        if (isfinite(up->t) && !up->front) {
            const sb_draw *d = draw_of(s, ds, up);
            v = (sb_path_frame){SB_PATH_BELOW, d ? (int64_t)d->node : -1};
        }
        /* surrounded (3 of 4 directions meet something: not merely under a sheet of ground) and mostly by backs */
        if (4 * met >= 3 * SPHERE && 2 * backs > met) v = (sb_path_frame){SB_PATH_INSIDE, back_node};
        out[f] = v;
        flagged += v.verdict != SB_PATH_CLEAR;
    }
    free(hits);
    free(from);
    free(to);
    free(reach);
    free(ds);
    return flagged;
}

void sb_path_check_text(const sb_path_frame *f, int n, char *out, size_t len) {
    size_t used = 0;
    out[0] = 0;
    for (int i = 0; i < n;) {
        if (f[i].verdict == SB_PATH_CLEAR) {
            i++;
            continue;
        }
        int j = i;   /* a run of frames with the same verdict and surface */
        while (j + 1 < n && f[j + 1].verdict == f[i].verdict && f[j + 1].node == f[i].node) j++;
        char frames[48], node[32] = "";
        if (j > i) snprintf(frames, sizeof frames, "frames %d-%d", i, j);
        else snprintf(frames, sizeof frames, "frame %d", i);
        if (f[i].node >= 0) snprintf(node, sizeof node, " (node %lld)", (long long)f[i].node);
        if (used < len)
            used += (size_t)snprintf(out + used, len - used, "%s%s: %s%s", used ? "; " : "", frames,
                                     verdict_text[f[i].verdict], node);
        i = j + 1;
    }
}
