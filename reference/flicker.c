/* flicker.c - the flicker figures of an evaluated frame and its twin (flicker.h). */
#include "flicker.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double sb_split_jitter(const sb_splits *a, const sb_splits *b) {
    if (a->count <= 0 || a->count != b->count) return NAN;
    double j = 0;
    for (int k = 0; k < a->count; k++)
        if (a->far[k] > 0) j = fmax(j, fabs(b->far[k] - a->far[k]) / a->far[k]);
    return j;
}

/* The reference at the twin's light and pose, for the frame's points (128: not evaluated); NULL when neither the
 * light nor the scene moved (every answer stands). */
static unsigned char *recast(const sb_reference *r, const sb_flicker_view *v, int threads) {
    if (!v->scene_moved && !memcmp(v->light, v->twin_light, 4 * sizeof *v->light)) return NULL;
    const size_t np = (size_t)v->w * v->h;
    sb_eval_view view = {v->w, v->h, v->pos, v->aux, v->eye, NULL, v->twin_light, 0, {0, 0, 0, 0}, NULL};   /* no geometry check */
    sb_ref_point *pts = sb_xmalloc(sizeof *pts * np);
    int *pix = sb_xmalloc(sizeof(int) * np);
    unsigned char *hit = sb_xmalloc(np), *out = sb_xmalloc(np);
    int k = sb_ref_points(r, &view, pts, pix);
    sb_reference_visibility_view(r, v->twin_light, pts, pix, k, v->w, v->h, hit, threads);
    memset(out, 128, np);
    for (int i = 0; i < k; i++) out[pix[i]] = hit[i];
    free(pts);
    free(pix);
    free(hit);
    return out;
}

/* Whether the twin's camera sees point p: inside its view and not behind what its depth holds there. */
static bool twin_sees(const sb_flicker_view *v, const sb_m4 *inv_proj, const float *p) {
    const double *vp = v->twin_view_proj.m;   /* column-major */
    double c[4];
    for (int r = 0; r < 4; r++) c[r] = vp[r] * p[0] + vp[4 + r] * p[1] + vp[8 + r] * p[2] + vp[12 + r];
    if (c[3] <= 0) return false;
    double x = c[0] / c[3], y = c[1] / c[3];
    if (fabs(x) >= 1 || fabs(y) >= 1) return false;
    int px = (int)((x * 0.5 + 0.5) * v->w), py = (int)((y * 0.5 + 0.5) * v->h);
    float d = v->twin_depth[(size_t)py * v->w + px];
    if (d >= 1.0f) return false;
    sb_v3 vz = sb_m4_point(*inv_proj, sb_v3_make(0, 0, 2.0 * d - 1.0));   /* the depth's view-space point */
    return c[3] <= -vz.z * 1.01;
}

typedef struct tally {
    long seen, steady, flipped, ref_changed;
    double dvis;
} tally;

static void count_point(const sb_flicker_view *v, const unsigned char *ref2, size_t i, tally *t) {
    t->seen++;
    if (ref2 && ref2[i] != 128 && (ref2[i] < 128) != (v->ref[i] < 128)) {
        t->ref_changed++;
        return;
    }
    t->steady++;
    bool a = v->vis[i] < 128, z = v->twin_vis[i] < 128;
    t->dvis += fabs((double)v->vis[i] - v->twin_vis[i]) / 255.0;
    t->flipped += a != z;
    if (!v->image) return;
    unsigned char *o = v->image + 3 * i;
    if (a == z) o[0] = o[1] = o[2] = a ? 60 : 160;
    else if (z) o[0] = 255;
    else o[2] = 255, o[1] = 80;
}

bool sb_evaluate_flicker(const sb_reference *r, const sb_flicker_view *v, sb_error_metrics *m, int threads) {
    m->flicker_rate = m->flicker_vis = m->ref_flicker = NAN;
    m->flicker_points = 0;
    m->split_jitter = sb_split_jitter(&v->splits, &v->twin_splits);
    sb_m4 inv_proj;
    if (!v->looked_up || !sb_m4_invert(v->twin_proj, &inv_proj)) return false;
    const size_t np = (size_t)v->w * v->h;
    unsigned char *ref2 = recast(r, v, threads);
    if (v->image) memset(v->image, 0, 3 * np);
    tally t = {0};
    for (size_t i = 0; i < np; i++) {
        if (v->ref[i] == 128) continue;   /* not an evaluated point */
        const float *p = v->pos + 4 * i;
        if (memcmp(p, v->twin_pos + 4 * i, 3 * sizeof(float))) continue;   /* the lookup drew another surface here */
        if (twin_sees(v, &inv_proj, p)) count_point(v, ref2, i, &t);
    }
    free(ref2);
    m->flicker_points = t.seen;
    if (t.seen) {
        m->ref_flicker = (double)t.ref_changed / t.seen;
        m->flicker_rate = t.steady ? (double)t.flipped / t.steady : NAN;
        m->flicker_vis = t.steady ? t.dvis / t.steady : NAN;
    }
    return true;
}
