/* error.c - per-frame shadow error against the Embree reference, and the
 * check that rays and rasterizer see one geometry. */
#include "error.h"

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
    long wrong = 0, fshadow = 0, flit = 0;
    double mae = 0;
    for (int k = 0; k < m; k++) {
        int i = pix[k];
        double vv = vis[i] / 255.0;
        bool tech_shadow = vis[i] < 128, ref_shadow = ref[k] == 0;
        if (ref_out) ref_out[i] = ref_shadow ? 0 : 255;
        wrong += tech_shadow != ref_shadow;
        fshadow += tech_shadow && !ref_shadow;
        flit += !tech_shadow && ref_shadow;
        mae += fabs(vv - (ref_shadow ? 0.0 : 1.0));
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
    }
    out->res_err_mean = out->res_err_p95 = out->texel_px_p95 = NAN;
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
            const float *a = v->aux + 4 * (size_t)i;
            s->sky = a[0] * a[0] + a[1] * a[1] + a[2] * a[2] < 0.25f;
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
    for (int k = 0; k < np; k++) disagree += (exact[k] != 0) != (ref[which[k]] != 0);
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
    sb_error_metrics geo;      /* the geometry check's figures */
} ref_entry;

struct sb_ref_cache {
    ref_entry *e;
    int n, cap;
    size_t bytes, max_bytes;
    bool dirty;                /* answers added since it was made or loaded */
};

sb_ref_cache *sb_ref_cache_new(size_t max_bytes) {
    sb_ref_cache *c = sb_xcalloc(1, sizeof *c);
    c->max_bytes = max_bytes;
    return c;
}

void sb_ref_cache_free(sb_ref_cache *c) {
    if (!c) return;
    for (int i = 0; i < c->n; i++) free(c->e[i].ref);
    free(c->e);
    free(c);
}

static uint64_t mix64(uint64_t h) {
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    return h ^ (h >> 33);
}

/* Two independent 64-bit hashes of what determines the reference's answers. */
static void view_key(const sb_eval_view *v, uint64_t key[2]) {
    uint64_t h1 = 0x9e3779b97f4a7c15ULL ^ (uint64_t)v->w << 32 ^ (uint64_t)v->h, h2 = mix64(h1 + 1);
    double cam[16 + 4 + 3] = {0};
    if (v->inv_view_proj) memcpy(cam, v->inv_view_proj->m, sizeof(double) * 16);
    memcpy(cam + 16, v->light, sizeof(double) * 4);
    cam[20] = v->eye.x, cam[21] = v->eye.y, cam[22] = v->eye.z;
    for (size_t i = 0; i < sizeof cam / sizeof cam[0]; i++) {
        uint64_t w;
        memcpy(&w, &cam[i], 8);
        h1 = (h1 ^ w) * 0x100000001b3ULL;
        h2 = mix64(h2 ^ w);
    }
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
    key[0] = mix64(h1);
    key[1] = mix64(h2 ^ key[0]);
}

static const ref_entry *cache_find(sb_ref_cache *c, const uint64_t key[2], int m) {
    for (int i = 0; c && i < c->n; i++)
        if (c->e[i].key[0] == key[0] && c->e[i].key[1] == key[1] && c->e[i].m == m) return &c->e[i];
    return NULL;
}

static void cache_put(sb_ref_cache *c, const uint64_t key[2], int m, const unsigned char *ref,
                      const sb_error_metrics *geo) {
    if (!c || (size_t)m > c->max_bytes) return;
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
    c->bytes += (size_t)m;
    c->dirty = true;
}

/* ---- kept across processes ---- */

static const char ref_magic[8] = {'S', 'B', 'R', 'E', 'F', '0', '0', '1'};

bool sb_ref_cache_dirty(const sb_ref_cache *c) { return c && c->dirty; }

bool sb_ref_cache_save(sb_ref_cache *c, const char *path, uint64_t tag, sb_err *err) {
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
    sum = sb_hash_bytes(SB_FNV_SEED, b + head, size - head);
    memcpy(b + 8 + 2 * sizeof(uint64_t), &sum, sizeof sum);
    bool ok = sb_write_file_atomic(path, b, size, err);
    free(b);
    if (ok) c->dirty = false;
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
        if (!cache_find(c, key, m)) cache_put(c, key, m, b + at, &geo), loaded++;
        at += (size_t)m;
    }
    sb_unmap_file(b, size);
    c->dirty = false;
    return ok ? loaded : 0;
}

void sb_evaluate_frame(const sb_reference *r, sb_ref_cache *cache, const sb_eval_view *v, const unsigned char *vis,
                       unsigned char *ref_out, sb_error_metrics *out, int threads) {
    int n = v->w * v->h;
    double t0 = sb_now_ms();
    sb_ref_point *pts = sb_xmalloc(sizeof *pts * (size_t)(n > 0 ? n : 1));
    int *pix = sb_xmalloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
    if (ref_out) memset(ref_out, 128, (size_t)n);
    int m = sb_ref_points(r, v, pts, pix);
    unsigned char *ref = sb_xmalloc((size_t)(m > 0 ? m : 1));
    uint64_t key[2] = {0, 0};
    if (cache) view_key(v, key);
    const ref_entry *hit = cache_find(cache, key, m);
    /* the reference's answers and the geometry check's figures: cast, or kept from an earlier run */
    sb_error_metrics e = {0};
    e.geom_mismatch = e.err_floor = NAN;
    if (hit) {
        memcpy(ref, hit->ref, (size_t)m);
        e = hit->geo;
        e.rays = 0;
        e.reused = true;
    } else {
        e.rays = sb_reference_visibility_light(r, v->light, pts, m, ref, threads);
        if (v->inv_view_proj) {
            int *kof = sb_xmalloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
            for (int i = 0; i < n; i++) kof[i] = -1;
            for (int k = 0; k < m; k++) kof[pix[k]] = k;
            geometry_check(r, v, ref, kof, &e, threads);
            free(kof);
        }
        cache_put(cache, key, m, ref, &e);
    }
    compare(v, vis, ref, pix, m, ref_out, &e); /* the technique's own figures */
    e.ray_ms = sb_now_ms() - t0;
    *out = e;
    free(ref);
    free(pts);
    free(pix);
}
