/* error.c - per-frame shadow error against the Embree reference, and the
 * check that rays and rasterizer see one geometry. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* SCHED_IDLE */
#endif
#include "error.h"

#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>

#include "stats.h"

int sb_ref_points(const sb_reference *r, const sb_eval_view *v, sb_ref_point *pts, int *pix) {
    int n = v->w * v->h, m = 0;
    for (int i = 0; i < n; i++) {
        const float *a = v->aux + 4 * (size_t)i, *p = v->pos + 4 * (size_t)i;
        double nl = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        if (nl < 0.5) continue; /* sky */
        double L[3] = {v->light[0], v->light[1], v->light[2]};
        if (v->light[3] > 0.5)
            for (int k = 0; k < 3; k++) L[k] -= p[k];
        if (a[0] * L[0] + a[1] * L[1] + a[2] * L[2] <= 0) continue; /* facing away from the light */
        double dist = sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
        if (v->range > 0 && v->light[3] > 0.5 && dist > v->range) continue;
        if (v->spot[3] > 0 && v->light[3] > 0.5 &&   /* outside a spot's cone: L points from the point to the light */
            -(L[0] * v->spot[0] + L[1] * v->spot[1] + L[2] * v->spot[2]) < (1 - v->spot[3]) * dist)
            continue;
        sb_ref_point *q = &pts[m];
        memcpy(q->p, p, sizeof q->p);
        memcpy(q->n, a, sizeof q->n);
        q->eps = sb_ref_position_eps(r, q->p, (float)sb_v3_len(sb_v3_sub(sb_v3_make(p[0], p[1], p[2]), v->eye)));
        pix[m++] = i;
    }
    return m;
}

/* The metrics from the technique's visibility and the reference's. */
static void compare(const sb_eval_view *v, const unsigned char *vis, const unsigned char *ref, const int *pix, int m,
                    unsigned char *ref_out, sb_error_metrics *out) {
    double *res_err = sb_xmalloc(sizeof(double) * (size_t)(m > 0 ? m : 1));
    double *texel = sb_xmalloc(sizeof(double) * (size_t)(m > 0 ? m : 1));
    int nres = 0;
    long wrong = 0, fshadow = 0, flit = 0, pen = 0;
    double mae = 0, pen_err = 0;
    for (int k = 0; k < m; k++) {
        int i = pix[k];
        double vv = vis[i] / 255.0, rv = ref[k] / 255.0;   /* a light with a size: the reference is fractional */
        bool tech_shadow = vis[i] < 128, ref_shadow = ref[k] < 128;
        if (ref_out) ref_out[i] = ref[k];
        wrong += tech_shadow != ref_shadow;
        fshadow += tech_shadow && !ref_shadow;
        flit += !tech_shadow && ref_shadow;
        mae += fabs(vv - rv);
        if (ref[k] != 0 && ref[k] != 255) {   /* strictly inside the penumbra */
            pen++;
            pen_err += fabs(vv - rv);
        }
        float d = v->pos[4 * (size_t)i + 3];
        if (d > 0) {
            texel[nres] = d;
            res_err[nres++] = fmax(-log2(d), 0.0);
        }
    }
    out->pixels = m;
    if (m > 0) {
        out->err_rate = (double)wrong / m;
        out->false_shadow = (double)fshadow / m;
        out->false_lit = (double)flit / m;
        out->vis_mae = mae / m;
        out->penumbra_px = (double)pen / m;
    }
    out->penumbra_err = pen ? pen_err / pen : NAN;
    out->res_err_mean = out->res_err_p95 = out->texel_px_p95 = NAN;
    out->stale_px = NAN;   /* eval.c measures it where a cache and motion meet */
    if (nres > 0) {
        double sum = 0;
        for (int k = 0; k < nres; k++) sum += res_err[k];
        out->res_err_mean = sum / nres;
        out->res_err_p95 = sb_percentile_select(res_err, nres, 0.95);
        out->texel_px_p95 = sb_percentile_select(texel, nres, 0.95);
    }
    free(res_err);
    free(texel);
}

/* The ray through a point of the pixel grid (x, y in pixels, the pixel's
 * centre at +0.5): its points on the near and the far plane. */
static void pixel_ray(const sb_eval_view *v, double x, double y, float near_out[3], float far_out[3]) {
    double nx = 2 * x / v->w - 1, ny = 2 * y / v->h - 1;
    sb_v3 a = sb_m4_point(*v->inv_view_proj, sb_v3_make(nx, ny, -1)), b = sb_m4_point(*v->inv_view_proj, sb_v3_make(nx, ny, 1));
    near_out[0] = (float)a.x, near_out[1] = (float)a.y, near_out[2] = (float)a.z;
    far_out[0] = (float)b.x, far_out[1] = (float)b.y, far_out[2] = (float)b.z;
}

static float dist3(const float *a, const float *b) {
    float d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* The rasterizer's own precision, within which a camera ray and the raster
 * still see one surface: vertices are snapped to 1/256 pixel (8 sub-pixel
 * bits, llvmpipe's and the GL minimum's 4 bits are coarser only in theory),
 * so a ray up to that far from the pixel centre is the same sample; and two
 * surfaces closer than a few units in the last place of the float depth
 * buffer (values near 1: 2^-24) are the same to the depth test. */
#define SB_SUBPIXEL (1.0 / 256)
#define SB_DEPTH_ULPS (4.0 / 16777216.0)

typedef struct geo_sample {
    int pixel;
    bool sky;
    float from[3], to[3]; /* the ray: near-plane point to the rasterized position (sky: to the far plane) */
} geo_sample;

typedef struct geo_ctx {
    const sb_reference *r;
    const sb_eval_view *v;
    sb_m4 view_proj; /* origin-relative world -> clip */
} geo_ctx;

static double window_depth(const geo_ctx *g, const float p[3]) {
    return 0.5 * sb_m4_point(g->view_proj, sb_v3_make(p[0], p[1], p[2])).z + 0.5;
}

/* Whether ray from->through (whose length is len) with first hit h sees the
 * sample's rasterized surface: sky stays sky; a surface hit lies on the plane
 * of the rasterized position (the distance measured across the plane, within
 * the position's error bound: along a grazing ray that error grows without
 * bound), or in front of it by no more than the depth buffer resolves. */
static bool sees_raster(const geo_ctx *g, const geo_sample *s, const float from[3], const float through[3], float len,
                        const sb_ref_hit *h) {
    if (s->sky) return !(h->t < len);
    if (!(h->t < INFINITY)) return false;
    float q[3], off = 0;
    for (int c = 0; c < 3; c++) q[c] = from[c] + (through[c] - from[c]) * (h->t / len);
    for (int c = 0; c < 3; c++) off += (s->to[c] - q[c]) * h->n[c];
    float d = dist3(s->to, s->from);
    if (fabsf(off) <= 4 * sb_ref_position_eps(g->r, s->to, d)) return true;
    return h->t < d && window_depth(g, s->to) - window_depth(g, q) <= SB_DEPTH_ULPS;
}

/* Samples whose centre ray does not see the raster, again through 8 points a
 * sub-pixel snap away: a sample is a mismatch when none of them does. */
static long retry_subpixel(const geo_ctx *g, const geo_sample *smp, const int *bad, int nbad, int threads) {
    static const int ox[8] = {-1, 0, 1, -1, 1, -1, 0, 1}, oy[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
    int n = 8 * nbad;
    float (*from)[3] = sb_xmalloc(sizeof *from * (size_t)(n ? n : 1)), (*to)[3] = sb_xmalloc(sizeof *to * (size_t)(n ? n : 1));
    sb_ref_hit *hits = sb_xmalloc(sizeof *hits * (size_t)(n ? n : 1));
    for (int b = 0; b < nbad; b++) {
        int px = smp[bad[b]].pixel;
        for (int j = 0; j < 8; j++)
            pixel_ray(g->v, px % g->v->w + 0.5 + ox[j] * SB_SUBPIXEL, px / g->v->w + 0.5 + oy[j] * SB_SUBPIXEL,
                      from[8 * b + j], to[8 * b + j]);
    }
    sb_reference_rays(g->r, from, to, n, hits, threads);
    long mism = 0;
    for (int b = 0; b < nbad; b++) {
        bool seen = false;
        for (int j = 0; j < 8 && !seen; j++) {
            int k = 8 * b + j;
            seen = sees_raster(g, &smp[bad[b]], from[k], to[k], dist3(to[k], from[k]), &hits[k]);
        }
        mism += !seen;
    }
    free(hits);
    free(to);
    free(from);
    return mism;
}

/* The geometry check and the floor on every 2nd pixel of every 2nd row. ref[k]
 * is the reference at pix[k]; kof[i] the k of pixel i (-1: not evaluated). */
static void geometry_check(const sb_reference *r, const sb_eval_view *v, const unsigned char *ref, const int *kof,
                           sb_error_metrics *out, int threads) {
    geo_ctx g = {r, v, sb_m4_identity()};
    sb_m4_invert(*v->inv_view_proj, &g.view_proj);
    int ns = 0, cap = ((v->w + 1) / 2) * ((v->h + 1) / 2);
    cap = cap ? cap : 1;
    geo_sample *smp = sb_xmalloc(sizeof *smp * (size_t)cap);
    float (*from)[3] = sb_xmalloc(sizeof *from * (size_t)cap), (*to)[3] = sb_xmalloc(sizeof *to * (size_t)cap);
    for (int y = 0; y < v->h; y += 2)
        for (int x = 0; x < v->w; x += 2) {
            int i = y * v->w + x;
            geo_sample *s = &smp[ns];
            s->pixel = i;
            pixel_ray(v, x + 0.5, y + 0.5, s->from, to[ns]);
            s->sky = !sb_eval_has_geometry(v->aux, (size_t)i);
            if (!s->sky) memcpy(s->to, v->pos + 4 * (size_t)i, sizeof s->to);
            else memcpy(s->to, to[ns], sizeof s->to);
            memcpy(from[ns], s->from, sizeof from[ns]);
            memcpy(to[ns], s->to, sizeof to[ns]);
            ns++;
        }
    sb_ref_hit *hits = sb_xmalloc(sizeof *hits * (size_t)cap);
    sb_reference_rays(r, from, to, ns, hits, threads);
    sb_ref_point *pts = sb_xmalloc(sizeof *pts * (size_t)cap);
    int *which = sb_xmalloc(sizeof(int) * (size_t)cap), *bad = sb_xmalloc(sizeof(int) * (size_t)cap), np = 0, nbad = 0;
    for (int k = 0; k < ns; k++) {
        float d = dist3(smp[k].to, smp[k].from);
        if (!sees_raster(&g, &smp[k], smp[k].from, smp[k].to, d, &hits[k])) {
            bad[nbad++] = k;
            continue;
        }
        int kr = kof[smp[k].pixel];
        if (smp[k].sky || kr < 0) continue;
        /* the reference again from the exact hit point and normal */
        sb_ref_point *q = &pts[np];
        for (int c = 0; c < 3; c++) q->p[c] = smp[k].from[c] + (smp[k].to[c] - smp[k].from[c]) * (hits[k].t / d);
        memcpy(q->n, hits[k].n, sizeof q->n);
        q->eps = sb_ref_position_eps(r, q->p, dist3(q->p, (float[3]){(float)v->eye.x, (float)v->eye.y, (float)v->eye.z}));
        which[np++] = kr;
    }
    long mism = retry_subpixel(&g, smp, bad, nbad, threads);
    unsigned char *exact = sb_xmalloc((size_t)(np ? np : 1));
    sb_reference_visibility_light(r, v->light, pts, np, exact, threads);
    long disagree = 0;
    for (int k = 0; k < np; k++) disagree += (exact[k] < 128) != (ref[which[k]] < 128);
    out->geom_samples = ns;
    out->geom_mismatches = mism;
    out->floor_samples = np;
    out->floor_disagree = disagree;
    out->geom_mismatch = ns ? (double)mism / ns : NAN;
    out->err_floor = np ? (double)disagree / np : NAN;
    out->rays += (uint64_t)(ns + 8 * nbad + np);
    free(exact);
    free(bad);
    free(which);
    free(pts);
    free(from);
    free(to);
    free(hits);
    free(smp);
}

/* ---- the cache ---- */

typedef struct ref_entry {
    uint64_t key[2];
    int m;                     /* evaluated pixels */
    unsigned char *ref;        /* their reference, m bytes */
    sb_error_metrics geo;      /* the geometry check's figures (rays: how many the cast took) */
    bool fresh;                /* cast in the background and not yet used by an evaluation */
} ref_entry;

/* A frame queued for the background: its view, copied. */
typedef struct ref_job {
    uint64_t key[2];
    bool casting;              /* taken by the background (else queued) */
    int w, h;
    float *pos, *aux;
    sb_v3 eye;
    bool have_inv;
    sb_m4 inv;
    double light[4];
    struct ref_job *next;
} ref_job;

struct sb_ref_cache {
    ref_entry *e;
    int n, cap;
    size_t bytes, max_bytes;
    bool dirty;                /* answers added since it was made or loaded */
    pthread_mutex_t mu;        /* everything here: the background adds answers while evaluations read them */
    pthread_cond_t cv;         /* a job was queued, finished, or the background was told to stop */
    /* the background (sb_ref_background_start) */
    const sb_reference *r;
    int threads;
    bool bg, stop;
    pthread_t thread;
    ref_job *jobs;             /* oldest first */
    size_t queued_bytes;       /* their copied targets */
    sb_ref_background_stats stats;
    double *iv;                /* intervals [t0, t1) on sb_now_ms: casting (kind 0) and timed frames (kind 1) */
    int *iv_kind, niv, iv_cap;
    double timed_since;        /* the timed frames now rendering began (NAN: none are) */
};

static void add_interval(sb_ref_cache *c, int kind, double t0, double t1) {
    if (c->niv == c->iv_cap) {
        c->iv_cap = c->iv_cap ? 2 * c->iv_cap : 32;
        c->iv = sb_xrealloc(c->iv, sizeof(double) * 2 * (size_t)c->iv_cap);
        c->iv_kind = sb_xrealloc(c->iv_kind, sizeof(int) * (size_t)c->iv_cap);
    }
    c->iv[2 * c->niv] = t0, c->iv[2 * c->niv + 1] = t1;
    c->iv_kind[c->niv++] = kind;
}

/* Time in both casting and timed frames. */
static double overlap_ms(const sb_ref_cache *c) {
    double ms = 0;
    for (int i = 0; i < c->niv; i++)
        for (int j = 0; c->iv_kind[i] == 0 && j < c->niv; j++)
            if (c->iv_kind[j] == 1)
                ms += fmax(0, fmin(c->iv[2 * i + 1], c->iv[2 * j + 1]) - fmax(c->iv[2 * i], c->iv[2 * j]));
    return ms;
}

sb_ref_cache *sb_ref_cache_new(size_t max_bytes) {
    sb_ref_cache *c = sb_xcalloc(1, sizeof *c);
    c->max_bytes = max_bytes;
    c->timed_since = NAN;
    pthread_mutex_init(&c->mu, NULL);
    pthread_cond_init(&c->cv, NULL);
    return c;
}

void sb_ref_cache_free(sb_ref_cache *c) {
    if (!c) return;
    sb_ref_background_stop(c);
    for (int i = 0; i < c->n; i++) free(c->e[i].ref);
    free(c->e);
    free(c->iv);
    free(c->iv_kind);
    pthread_cond_destroy(&c->cv);
    pthread_mutex_destroy(&c->mu);
    free(c);
}

void sb_eval_view_pixels_key(const sb_eval_view *v, uint64_t key[2]) {
    uint64_t h1 = 0x243f6a8885a308d3ULL, h2 = 0x13198a2e03707344ULL;
    size_t n = (size_t)v->w * v->h;
    for (size_t i = 0; i < n; i++) {
        uint32_t w[6];
        memcpy(w, v->pos + 4 * i, 12); /* xyz: the position; w (texels per pixel) is the technique's */
        memcpy(w + 3, v->aux + 4 * i, 12);
        uint64_t a = (uint64_t)w[0] | (uint64_t)w[1] << 32, b = (uint64_t)w[2] | (uint64_t)w[3] << 32,
                 c = (uint64_t)w[4] | (uint64_t)w[5] << 32;
        h1 = ((h1 ^ a) * 0x9fb21c651e98df25ULL ^ b) * 0xc2b2ae3d27d4eb4fULL ^ c;
        h1 = h1 << 29 | h1 >> 35;
        h2 = (h2 + a * 0x165667b19e3779f9ULL) ^ (b + (c << 7 | c >> 57));
        h2 = (h2 << 31 | h2 >> 33) * 0x27d4eb2f165667c5ULL;
    }
    key[0] = h1, key[1] = h2;
}

/* Two independent 64-bit hashes of what determines the reference's answers: the view's camera, light and
 * pose, then its pixels' (sb_eval_view_pixels_key, or the view's pixels_key where its caller has it). */
static void view_key(const sb_reference *r, const sb_eval_view *v, uint64_t key[2]) {
    uint64_t h1 = 0x9e3779b97f4a7c15ULL ^ (uint64_t)v->w << 32 ^ (uint64_t)v->h, h2 = sb_mix64(h1 + 1);
    if (r && r->pose_key) h1 ^= r->pose_key, h2 = sb_mix64(h2 ^ h1);   /* a moving scene: the pose decides too */
    if (r && (r->sun_size_deg > 0 || r->lamp_radius > 0)) {   /* the light's size and samples decide the answers too */
        double size[3] = {r->sun_size_deg, r->lamp_radius, r->samples};
        uint64_t w[3];
        memcpy(w, size, sizeof w);
        h1 ^= sb_hash_words(w, 3);
        h2 = sb_mix64(h2 ^ h1);
    }
    double cam[16 + 4 + 3] = {0};
    if (v->inv_view_proj) memcpy(cam, v->inv_view_proj->m, sizeof(double) * 16);
    memcpy(cam + 16, v->light, sizeof(double) * 4);
    cam[20] = v->eye.x, cam[21] = v->eye.y, cam[22] = v->eye.z;
    if (v->range > 0) {   /* a range leaves points out: other answers (0, as before ranges, keeps every key) */
        uint64_t w;
        memcpy(&w, &v->range, 8);
        h1 ^= sb_mix64(w + 7), h2 = sb_mix64(h2 ^ h1);
    }
    for (int k = 0; v->spot[3] > 0 && k < 4; k++) {   /* so does a cone */
        uint64_t w;
        memcpy(&w, &v->spot[k], 8);
        h1 ^= sb_mix64(w + 11 + (uint64_t)k), h2 = sb_mix64(h2 ^ h1);
    }
    for (size_t i = 0; i < sizeof cam / sizeof cam[0]; i++) {
        uint64_t w;
        memcpy(&w, &cam[i], 8);
        h1 = (h1 ^ w) * 0x100000001b3ULL;
        h2 = sb_mix64(h2 ^ w);
    }
    uint64_t px[2];
    if (v->pixels_key) px[0] = v->pixels_key[0], px[1] = v->pixels_key[1];
    else sb_eval_view_pixels_key(v, px);
    h1 = sb_mix64(h1 ^ px[0]), h2 = sb_mix64(h2 ^ px[1]);
    key[0] = sb_mix64(h1);
    key[1] = sb_mix64(h2 ^ key[0]);
}

/* cache_find and cache_put: with the lock held. find: m < 0 matches any
 * number of evaluated pixels. put: the first answers for a key are kept (NULL
 * when there were some, or they do not fit). */
static ref_entry *cache_find(sb_ref_cache *c, const uint64_t key[2], int m) {
    for (int i = 0; c && i < c->n; i++)
        if (c->e[i].key[0] == key[0] && c->e[i].key[1] == key[1] && (m < 0 || c->e[i].m == m)) return &c->e[i];
    return NULL;
}

static ref_entry *cache_put(sb_ref_cache *c, const uint64_t key[2], int m, const unsigned char *ref,
                            const sb_error_metrics *geo) {
    if (!c || (size_t)m > c->max_bytes || cache_find(c, key, m)) return NULL;
    while (c->n && c->bytes + (size_t)m > c->max_bytes) { /* the oldest go first */
        c->bytes -= (size_t)c->e[0].m;
        free(c->e[0].ref);
        memmove(c->e, c->e + 1, sizeof *c->e * (size_t)--c->n);
    }
    if (c->n == c->cap) {
        c->cap = c->cap ? 2 * c->cap : 16;
        c->e = sb_xrealloc(c->e, sizeof *c->e * (size_t)c->cap);
    }
    ref_entry *e = &c->e[c->n++];
    e->key[0] = key[0], e->key[1] = key[1];
    e->m = m;
    e->ref = sb_xmalloc((size_t)(m ? m : 1));
    memcpy(e->ref, ref, (size_t)m);
    e->geo = *geo;
    e->fresh = false;
    c->bytes += (size_t)m;
    c->dirty = true;
    return e;
}

/* ---- kept across processes ---- */

static const char ref_magic[8] = {'S', 'B', 'R', 'E', 'F', '0', '0', '2'};   /* 002: keys hash the pixels apart */

bool sb_ref_cache_dirty(sb_ref_cache *c) {
    if (!c) return false;
    pthread_mutex_lock(&c->mu);
    bool dirty = c->dirty;
    pthread_mutex_unlock(&c->mu);
    return dirty;
}

bool sb_ref_cache_save(sb_ref_cache *c, const char *path, uint64_t tag, sb_err *err) {
    pthread_mutex_lock(&c->mu);
    size_t size = 8 + 3 * sizeof(uint64_t), at = 0;
    for (int i = 0; i < c->n; i++) size += 2 * sizeof(uint64_t) + sizeof(int) + sizeof(sb_error_metrics) + (size_t)c->e[i].m;
    unsigned char *b = sb_xmalloc(size);
#define PUT(p, n) (memcpy(b + at, (p), (n)), at += (n))
    uint64_t count = (uint64_t)c->n, sum = 0;
    PUT(ref_magic, 8);
    PUT(&tag, sizeof tag);
    PUT(&count, sizeof count);
    PUT(&sum, sizeof sum);   /* the checksum, written below */
    for (int i = 0; i < c->n; i++) {
        PUT(c->e[i].key, 2 * sizeof(uint64_t));
        PUT(&c->e[i].m, sizeof(int));
        PUT(&c->e[i].geo, sizeof(sb_error_metrics));
        PUT(c->e[i].ref, (size_t)c->e[i].m);
    }
#undef PUT
    size_t head = 8 + 3 * sizeof(uint64_t);
    pthread_mutex_unlock(&c->mu);
    sum = sb_hash_bytes(SB_FNV_SEED, b + head, size - head);
    memcpy(b + 8 + 2 * sizeof(uint64_t), &sum, sizeof sum);
    bool ok = sb_write_cache_file_atomic(path, b, size, "the reference's answers");
    if (!ok) sb_fail(err, "%s: not written", path);
    free(b);
    pthread_mutex_lock(&c->mu);
    if (ok) c->dirty = false; /* (answers the background added meanwhile are in the next save) */
    pthread_mutex_unlock(&c->mu);
    return ok;
}

int sb_ref_cache_load(sb_ref_cache *c, const char *path, uint64_t tag) {
    size_t size = 0;
    unsigned char *b = sb_map_file(path, &size, false);
    size_t head = 8 + 3 * sizeof(uint64_t), at = head;
    uint64_t h[3];
    bool ok = b && size >= head && !memcmp(b, ref_magic, 8);
    if (ok) memcpy(h, b + 8, sizeof h);
    ok = ok && h[0] == tag && h[2] == sb_hash_bytes(SB_FNV_SEED, b + head, size - head);
    int loaded = 0;
    pthread_mutex_lock(&c->mu);
    for (uint64_t i = 0; ok && i < h[1]; i++) {
        uint64_t key[2];
        int m;
        sb_error_metrics geo;
        ok = size - at >= sizeof key + sizeof m + sizeof geo;
        if (!ok) break;
        memcpy(key, b + at, sizeof key);
        memcpy(&m, b + at + sizeof key, sizeof m);
        memcpy(&geo, b + at + sizeof key + sizeof m, sizeof geo);
        at += sizeof key + sizeof m + sizeof geo;
        ok = m >= 0 && size - at >= (size_t)m;
        if (!ok) break;
        loaded += cache_put(c, key, m, b + at, &geo) != NULL;
        at += (size_t)m;
    }
    c->dirty = false;
    pthread_mutex_unlock(&c->mu);
    sb_unmap_file(b, size);
    return ok ? loaded : 0;
}

/* The view's evaluated points (sb_ref_points) in arrays of its size; how many. */
static int view_points(const sb_reference *r, const sb_eval_view *v, sb_ref_point **pts, int **pix) {
    size_t n = (size_t)v->w * v->h;
    *pts = sb_xmalloc(sizeof **pts * (n ? n : 1));
    *pix = sb_xmalloc(sizeof **pix * (n ? n : 1));
    return sb_ref_points(r, v, *pts, *pix);
}

/* Casts the reference's answers for a view: ref (m bytes) and the geometry
 * check's figures in *e. */
static void cast_frame(const sb_reference *r, const sb_eval_view *v, const sb_ref_point *pts, const int *pix, int m,
                       unsigned char *ref, sb_error_metrics *e, int threads) {
    int n = v->w * v->h;
    memset(e, 0, sizeof *e);
    e->geom_mismatch = e->err_floor = NAN;
    e->rays = sb_reference_visibility_view(r, v->light, pts, pix, m, v->w, v->h, ref, threads);
    if (v->inv_view_proj) {
        int *kof = sb_xmalloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
        for (int i = 0; i < n; i++) kof[i] = -1;
        for (int k = 0; k < m; k++) kof[pix[k]] = k;
        geometry_check(r, v, ref, kof, e, threads);
        free(kof);
    }
}

static ref_job *job_find(sb_ref_cache *c, const uint64_t key[2], ref_job ***link) {
    for (ref_job **l = &c->jobs; *l; l = &(*l)->next)
        if ((*l)->key[0] == key[0] && (*l)->key[1] == key[1]) {
            if (link) *link = l;
            return *l;
        }
    return NULL;
}

static void job_free(sb_ref_cache *c, ref_job *j) {
    c->queued_bytes -= 2 * sizeof(float) * 4 * (size_t)j->w * j->h;
    free(j->pos);
    free(j->aux);
    free(j);
}

/* The cached answers for key into ref and *e: true when found. A frame the
 * background is casting is waited for; one it has queued is taken back (the
 * caller casts it). */
static bool cache_take(sb_ref_cache *c, const uint64_t key[2], int m, unsigned char *ref, sb_error_metrics *e) {
    pthread_mutex_lock(&c->mu);
    ref_entry *hit;
    ref_job *j, **link;
    while (!(hit = cache_find(c, key, m)) && (j = job_find(c, key, &link)) != NULL) {
        if (!j->casting) { /* not started: cast here, now, with every thread */
            *link = j->next;
            job_free(c, j);
            c->stats.taken_back++;
            break;
        }
        c->stats.waited++;
        pthread_cond_wait(&c->cv, &c->mu);
    }
    if (hit) {
        memcpy(ref, hit->ref, (size_t)m);
        *e = hit->geo;
        /* the first run to use background answers counts their rays as its own (not reused) */
        e->background = hit->fresh;
        e->reused = !hit->fresh;
        if (!hit->fresh) e->rays = 0;
        hit->fresh = false;
    }
    pthread_mutex_unlock(&c->mu);
    return hit != NULL;
}

void sb_evaluate_frame(const sb_reference *r, sb_ref_cache *cache, const sb_eval_view *v, const unsigned char *vis,
                       unsigned char *ref_out, sb_error_metrics *out, int threads) {
    double t0 = sb_now_ms();
    if (ref_out) memset(ref_out, 128, (size_t)v->w * v->h);
    sb_ref_point *pts;
    int *pix, m = view_points(r, v, &pts, &pix);
    unsigned char *ref = sb_xmalloc((size_t)(m > 0 ? m : 1));
    uint64_t key[2] = {0, 0};
    if (cache) view_key(r, v, key);
    /* the reference's answers and the geometry check's figures: kept from an earlier run or the background, or cast */
    sb_error_metrics e;
    if (!cache || !cache_take(cache, key, m, ref, &e)) {
        cast_frame(r, v, pts, pix, m, ref, &e, threads);
        if (cache) {
            pthread_mutex_lock(&cache->mu);
            cache_put(cache, key, m, ref, &e);
            pthread_mutex_unlock(&cache->mu);
        }
    }
    compare(v, vis, ref, pix, m, ref_out, &e); /* the technique's own figures */
    e.ray_ms = sb_now_ms() - t0;
    *out = e;
    free(ref);
    free(pts);
    free(pix);
}

/* A share of n items, weighted: sum += share * n (NaN shares add nothing). */
static void add_share(double *sum, double share, double n) {
    if (!isnan(share)) *sum += share * n;
}

void sb_error_metrics_add(sb_error_metrics *acc, const sb_error_metrics *e, bool first) {
    if (first) {
        *acc = *e;
        return;
    }
    double a = (double)acc->pixels, b = (double)e->pixels, n = a + b;
    double pen_a = acc->penumbra_px * a, pen_b = e->penumbra_px * b;
    double *shares[] = {&acc->err_rate, &acc->false_shadow, &acc->false_lit, &acc->vis_mae, &acc->penumbra_px};
    const double adds[] = {e->err_rate, e->false_shadow, e->false_lit, e->vis_mae, e->penumbra_px};
    for (size_t k = 0; k < SB_COUNT(shares); k++) {
        double sum = 0;
        add_share(&sum, *shares[k], a);
        add_share(&sum, adds[k], b);
        *shares[k] = n > 0 ? sum / n : NAN;
    }
    double pen_err = 0;
    add_share(&pen_err, acc->penumbra_err, isnan(pen_a) ? 0 : pen_a);
    add_share(&pen_err, e->penumbra_err, isnan(pen_b) ? 0 : pen_b);
    double pens = (isnan(pen_a) ? 0 : pen_a) + (isnan(pen_b) ? 0 : pen_b);
    acc->penumbra_err = pens > 0 ? pen_err / pens : NAN;
    double res = 0, res_n = (isnan(acc->res_err_mean) ? 0 : a) + (isnan(e->res_err_mean) ? 0 : b);
    add_share(&res, acc->res_err_mean, a);
    add_share(&res, e->res_err_mean, b);
    acc->res_err_mean = res_n > 0 ? res / res_n : NAN;   /* over the lights that have a map resolution */
    acc->res_err_p95 = fmax(acc->res_err_p95, e->res_err_p95);      /* the worse light's (fmax skips NaN) */
    acc->texel_px_p95 = fmin(acc->texel_px_p95, e->texel_px_p95);
    acc->stale_px = isnan(acc->stale_px) ? e->stale_px : fmax(acc->stale_px, e->stale_px);
    acc->pixels += e->pixels;
    acc->rays += e->rays;
    acc->ray_ms += e->ray_ms;
    acc->reused = acc->reused && e->reused;
    acc->background = acc->background || e->background;
}

/* ---- the background ---- */

static void *background(void *arg) {
    sb_ref_cache *c = arg;
    pthread_mutex_lock(&c->mu);
    for (;;) {
        ref_job *j = c->jobs;
        while (j && j->casting) j = j->next;
        if (c->stop) break;
        if (!j) {
            pthread_cond_wait(&c->cv, &c->mu);
            continue;
        }
        j->casting = true;
        pthread_mutex_unlock(&c->mu);
        sb_eval_view v = {j->w, j->h, j->pos, j->aux, j->eye, j->have_inv ? &j->inv : NULL, j->light, 0, {0, 0, 0, 0}, NULL};
        sb_ref_point *pts;
        int *pix, m = view_points(c->r, &v, &pts, &pix);
        unsigned char *ref = sb_xmalloc((size_t)(m > 0 ? m : 1));
        sb_error_metrics e;
        double t0 = sb_now_ms();
        cast_frame(c->r, &v, pts, pix, m, ref, &e, c->threads);
        double ms = sb_now_ms() - t0;
        pthread_mutex_lock(&c->mu);
        ref_entry *put = cache_put(c, j->key, m, ref, &e);
        if (put) put->fresh = true;
        c->stats.frames++;
        c->stats.rays += e.rays;
        c->stats.ms += ms;
        add_interval(c, 0, t0, t0 + ms);
        ref_job **link;
        if (job_find(c, j->key, &link) == j) *link = j->next;
        job_free(c, j);
        pthread_cond_broadcast(&c->cv);
        free(ref);
        free(pix);
        free(pts);
    }
    pthread_mutex_unlock(&c->mu);
    return NULL;
}

bool sb_ref_background_start(sb_ref_cache *c, const sb_reference *r, int threads) {
    if (c->bg) return true;
#ifdef SCHED_IDLE
    c->r = r;
    c->threads = threads;
    c->stop = false;
    if (pthread_create(&c->thread, NULL, background, c)) return false;
    /* SCHED_IDLE for it and, inherited, the threads it casts on; it casts nothing before a frame is queued */
    struct sched_param sp = {0};
    if (pthread_setschedparam(c->thread, SCHED_IDLE, &sp)) {
        pthread_mutex_lock(&c->mu);
        c->stop = true;
        pthread_cond_broadcast(&c->cv);
        pthread_mutex_unlock(&c->mu);
        pthread_join(c->thread, NULL);
        return false;
    }
    c->bg = true;
    return true;
#else
    (void)r, (void)threads;
    return false; /* no priority below every other thread: casting in the background would slow timed frames */
#endif
}

int sb_ref_background_add(sb_ref_cache *c, const sb_eval_view *v) {
    uint64_t key[2];
    view_key(c->r, v, key);
    size_t bytes = sizeof(float) * 4 * (size_t)v->w * v->h;
    pthread_mutex_lock(&c->mu);
    bool add = c->bg && !job_find(c, key, NULL) && !cache_find(c, key, -1);
    bool full = add && c->queued_bytes + 2 * bytes > SB_REF_BACKGROUND_BYTES;
    if (add && !full) {
        ref_job *j = sb_xcalloc(1, sizeof *j), **l = &c->jobs;
        memcpy(j->key, key, sizeof j->key);
        j->w = v->w, j->h = v->h;
        j->pos = sb_xmalloc(bytes ? bytes : 1);
        j->aux = sb_xmalloc(bytes ? bytes : 1);
        memcpy(j->pos, v->pos, bytes);
        memcpy(j->aux, v->aux, bytes);
        j->eye = v->eye;
        j->have_inv = v->inv_view_proj != NULL;
        if (j->have_inv) j->inv = *v->inv_view_proj;
        memcpy(j->light, v->light, sizeof j->light);
        while (*l) l = &(*l)->next;
        *l = j;
        c->queued_bytes += 2 * bytes;
        c->stats.queued++;
        pthread_cond_broadcast(&c->cv);
    }
    pthread_mutex_unlock(&c->mu);
    return full ? -1 : add;
}

static void mark_timed(sb_ref_cache *c, bool on) {
    double now = sb_now_ms();
    if (on && isnan(c->timed_since)) c->timed_since = now;
    if (!on && !isnan(c->timed_since)) add_interval(c, 1, c->timed_since, now), c->timed_since = NAN;
}

sb_ref_background_stats sb_ref_background_stop(sb_ref_cache *c) {
    pthread_mutex_lock(&c->mu);
    bool running = c->bg;
    c->stop = true;
    /* queued frames are dropped; the one being cast finishes */
    for (ref_job **l = &c->jobs; *l;) {
        ref_job *j = *l;
        if (j->casting) {
            l = &j->next;
            continue;
        }
        *l = j->next;
        job_free(c, j);
        c->stats.dropped++;
    }
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->mu);
    if (running) pthread_join(c->thread, NULL);
    pthread_mutex_lock(&c->mu);
    c->bg = false;
    mark_timed(c, false);
    c->stats.timed_ms = overlap_ms(c);
    sb_ref_background_stats st = c->stats;
    memset(&c->stats, 0, sizeof c->stats);
    c->niv = 0;
    pthread_mutex_unlock(&c->mu);
    return st;
}

void sb_ref_background_timed(sb_ref_cache *c, bool on) {
    if (!c) return;
    pthread_mutex_lock(&c->mu);
    if (c->bg) mark_timed(c, on);
    pthread_mutex_unlock(&c->mu);
}
