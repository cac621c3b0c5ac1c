/* reference.c - Embree rays: occlusion toward a light (the reference every
 * technique is measured against, and `raycast`) and first hits of camera rays
 * (the evaluation's check that rays and rasterizer see one geometry). */
#include "reference.h"
#include "motion.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* The intersect context handed to the filter: which way a single-sided
 * triangle must face to count. */
typedef struct ray_ctx {
    struct RTCIntersectContext ctx; /* first: Embree passes this pointer to the filter */
    bool camera;                    /* a camera ray: front faces face the ray's origin; else the ray's end (the light) */
    bool all_faces;                 /* both faces of a single-sided triangle count (the path check) */
} ray_ctx;

/* A geometry's filter data: the reference and the scene triangle its primID 0 is. */
typedef struct sb_ref_geo {
    const sb_reference *r;
    uint32_t first;
} sb_ref_geo;

/* Embree's packet layout (rtcore_ray.h, whose accessors are C++ only):
 * structure-of-arrays of N lanes. */
static float ray_dir(const struct RTCFilterFunctionNArguments *a, int axis, unsigned i) {
    return ((const float *)a->ray)[(4 + axis) * a->N + i];
}
static float hit_f(const struct RTCFilterFunctionNArguments *a, int field, unsigned i) {
    return ((const float *)a->hit)[field * a->N + i]; /* 3: u, 4: v */
}
static unsigned hit_prim(const struct RTCFilterFunctionNArguments *a, unsigned i) {
    return ((const unsigned *)a->hit)[5 * a->N + i];
}

/* Rejects hits the rasterizer would not draw: the back of an open
 * single-sided triangle, the uncovered part of an alpha-tested one. */
static void filter(const struct RTCFilterFunctionNArguments *args) {
    const sb_ref_geo *geo = args->geometryUserPtr;
    const sb_reference *r = geo->r;
    const ray_ctx *rc = (const ray_ctx *)args->context;
    const sb_scene *s = r->src;
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1) continue;
        /* an instance's ray is in its proto's space: the proto's triangle, which it repeats, answers */
        uint32_t prim = geo->first + hit_prim(args, i);
        uint8_t flags = r->tri[prim];
        if (!flags) continue;
        const uint32_t *ix = s->indices + 3 * (size_t)prim;
        const float *a = sb_vertex(s, ix[0]), *b = sb_vertex(s, ix[1]), *c = sb_vertex(s, ix[2]);
        if ((flags & SB_REF_SINGLE_SIDED) && !rc->all_faces) {
            float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            float d = n[0] * ray_dir(args, 0, i) + n[1] * ray_dir(args, 1, i) + n[2] * ray_dir(args, 2, i);
            if (rc->camera ? d >= 0 : d <= 0) {
                args->valid[i] = 0;
                continue;
            }
        }
        if (flags & SB_REF_ALPHA) {
            float u = hit_f(args, 3, i), v = hit_f(args, 4, i), w = 1 - u - v;
            uint32_t mat;
            memcpy(&mat, a + 8, 4);
            if (!sb_material_covers(s, mat, w * a[6] + u * b[6] + v * c[6], w * a[7] + u * b[7] + v * c[7]))
                args->valid[i] = 0;
        }
    }
}

/* Per triangle: what the filter must check (NULL when nothing needs it). */
static uint8_t *triangle_flags(const sb_scene *s) {
    uint8_t *f = sb_xcalloc((size_t)s->index_count / 3 + 1, 1);
    bool any = false;
    for (uint32_t d = 0; d < s->draw_count; d++) {
        const sb_draw *dr = &s->draws[d];
        uint8_t x = (uint8_t)((!dr->double_sided && !dr->closed ? SB_REF_SINGLE_SIDED : 0) |
                              (dr->material ? SB_REF_ALPHA : 0));
        if (!x) continue;
        any = true;
        memset(f + dr->first_index / 3, x, dr->index_count / 3);
    }
    if (!any) {
        free(f);
        return NULL;
    }
    return f;
}

void sb_reference_set_light_size(sb_reference *r, double sun_size_deg, double lamp_radius, int samples) {
    r->sun_size_deg = sun_size_deg > 0 ? sun_size_deg : 0;
    r->sun_tan = r->sun_size_deg > 0 ? tan(r->sun_size_deg * SB_PI / 360) : 0;   /* half the diameter */
    r->lamp_radius = lamp_radius > 0 ? (float)lamp_radius : 0;
    r->samples = samples > 0 ? samples : 64;
}

/* A triangle geometry of the scene's triangles [first, first + count) (their indices shared, not copied). */
static RTCGeometry tri_geometry(sb_reference *r, RTCDevice dev, const sb_scene *s, uint32_t first, uint32_t count,
                                sb_ref_geo *geo, bool moving) {
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (moving) rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);   /* its vertices move: refit, not rebuild */
    /* positions are the first 3 floats of each vertex; what follows them keeps
       Embree's 16-byte reads of the last vertex inside the buffer */
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s->vertices, 0, SB_VERTEX_BYTES,
                               s->vertex_count);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s->indices,
                               (size_t)first * 3 * sizeof(uint32_t), 3 * sizeof(uint32_t), count);
    if (r->tri) {
        *geo = (sb_ref_geo){r, first};
        rtcSetGeometryUserData(g, geo);
        rtcSetGeometryOccludedFilterFunction(g, filter);
        rtcSetGeometryIntersectFilterFunction(g, filter);
    }
    rtcCommitGeometry(g);
    return g;
}

static void commit_scene(RTCScene sc, bool dynamic) {
    /* watertight: no ray slips through a shared edge or corner; a top level whose geometry moves is committed
       again every pose: built for that */
    rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST | (dynamic ? RTC_SCENE_FLAG_DYNAMIC : 0));
    rtcSetSceneBuildQuality(sc, dynamic ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_HIGH);
    rtcCommitScene(sc);
}

/* The key of the pose the scene holds (0: a still scene, whose kept answers keep their keys). */
static uint64_t pose_key(const sb_scene *s) {
    if (!sb_scene_moves(s) || isnan(s->pose_time)) return 0;
    uint64_t t;
    memcpy(&t, &s->pose_time, sizeof t);
    return sb_mix64(t ^ 0x6a09e667f3bcc909ULL);
}

/* Shared geometry: a draw others repeat becomes a scene of its own, built once, and it and every repeat an
 * instance of it under the draw's transform (the transform the GPU draws it with); any other draw a triangle
 * geometry of its own triangles. */
static void attach_draws(sb_reference *r, RTCDevice dev, RTCScene top, const sb_scene *s) {
    uint32_t n = s->draw_count;
    r->geom_first = sb_xcalloc(n + 1, sizeof(uint32_t));
    r->protos = sb_xcalloc(n + 1, sizeof(void *));
    r->geo = sb_xcalloc(n + 1, sizeof(sb_ref_geo));
    uint8_t *repeated = sb_xcalloc(n + 1, 1);
    for (uint32_t d = 0; d < n; d++) repeated[s->draws[d].proto] |= s->draws[d].proto != d;
    for (uint32_t d = 0; d < n; d++) {
        const sb_draw *dr = &s->draws[d];
        uint32_t p = dr->proto, first = dr->first_index / 3;
        RTCGeometry g;
        if (!repeated[p]) {
            g = tri_geometry(r, dev, s, first, dr->index_count / 3, &r->geo[d], dr->motion != SB_DRAW_STILL);
        } else {
            if (!r->protos[p]) {
                RTCScene ps = rtcNewScene(dev);
                RTCGeometry pg = tri_geometry(r, dev, s, s->draws[p].first_index / 3, dr->index_count / 3, &r->geo[p],
                                              false);
                rtcAttachGeometry(ps, pg);
                rtcReleaseGeometry(pg);
                commit_scene(ps, false);
                r->protos[p] = ps;
            }
            g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(g, (RTCScene)r->protos[p]);
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, p == d ? sb_xform_identity : dr->xform);
            rtcCommitGeometry(g);
        }
        unsigned gid = rtcAttachGeometry(top, g);
        rtcReleaseGeometry(g);
        if (gid < n) r->geom_first[gid] = first;
        if (dr->motion != SB_DRAW_STILL) {
            r->moving_geoms = sb_xrealloc(r->moving_geoms, sizeof(uint32_t) * (r->moving_count + 1));
            r->moving_geoms[r->moving_count++] = gid;
        }
    }
    free(repeated);
}

void sb_reference_update(sb_reference *r) {
    const sb_scene *s = r->src;
    if (!r->moving_count || r->pose_serial == s->pose_serial) return;
    double t0 = sb_now_ms();
    sb_scene_sync_vertices(s);   /* the CPU's vertices at the pose (the GPU poses its own copy) */
    for (uint32_t i = 0; i < r->moving_count; i++) {
        RTCGeometry g = rtcGetGeometry((RTCScene)r->scene, r->moving_geoms[i]);
        rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(g);
    }
    rtcCommitScene((RTCScene)r->scene);
    r->pose_serial = s->pose_serial;
    r->pose_key = pose_key(s);
    r->refit_ms += sb_now_ms() - t0;
    r->refits++;
}

bool sb_reference_build(sb_reference *r, const sb_scene *s, sb_err *err) {
    memset(r, 0, sizeof *r);
    double t0 = sb_now_ms();
    sb_scene_sync_vertices(s);   /* its triangles as the scene is posed now (the GPU may have posed it since) */
    RTCDevice dev = rtcNewDevice(NULL);
    if (!dev) return sb_fail(err, "embree: cannot create a device (error %d)", (int)rtcGetDeviceError(NULL));
    r->src = s;
    r->tri = triangle_flags(s);
    RTCScene scene = rtcNewScene(dev);
    if (s->instance_draws || sb_scene_moves(s)) {
        attach_draws(r, dev, scene, s);
    } else {
        r->geo = sb_xcalloc(1, sizeof(sb_ref_geo));
        RTCGeometry g = tri_geometry(r, dev, s, 0, s->index_count / 3, r->geo, false);
        rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
    }
    commit_scene(scene, sb_scene_moves(s));
    r->pose_serial = s->pose_serial;
    r->pose_key = pose_key(s);
    r->device = dev;
    r->scene = scene;
    enum RTCError e = rtcGetDeviceError(dev);
    if (e != RTC_ERROR_NONE) {
        sb_reference_free(r);
        return sb_fail(err, "embree: building the scene failed (error %d)", (int)e);
    }
    sb_v3 ext = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    r->eps_scene = (float)(sb_v3_len(ext) * 1e-6);
    r->build_ms = sb_now_ms() - t0;
    return true;
}

void sb_reference_free(sb_reference *r) {
    if (r->scene) rtcReleaseScene(r->scene);
    if (r->protos)
        for (uint32_t d = 0; d < r->src->draw_count; d++)
            if (r->protos[d]) rtcReleaseScene(r->protos[d]);
    free(r->protos);
    free(r->moving_geoms);
    free(r->geom_first);
    free(r->geo);
    if (r->device) rtcReleaseDevice(r->device);
    free(r->tri);
    memset(r, 0, sizeof *r);
}

float sb_ref_position_eps(const sb_reference *r, const float p[3], float dist) {
    /* float positions relative to the origin are exact to ~1e-7 of their size;
       the rasterizer's interpolation adds a few ulps of the camera distance */
    float mag = fmaxf(fmaxf(fabsf(p[0]), fabsf(p[1])), fabsf(p[2]));
    return 1.6e-5f * (mag + dist) + r->eps_scene;
}

/* Work split over threads: items [first, first + count) of a job. */
typedef struct job {
    const sb_reference *r;
    float sun[3];
    bool point;                 /* sun holds a point light's position */
    const sb_ref_point *pts;
    unsigned char *vis;
    const float (*from)[3];     /* camera rays: from from[i] toward to[i] */
    const float (*to)[3];
    sb_ref_hit *hits;
    int first, count;
    uint64_t rays;              /* cast by this part (occlusion) */
    const int *idx;             /* occlusion: the points to answer (NULL: all) */
    bool all_faces;             /* first hits: both faces of every triangle */
    bool hard;                  /* the centre ray alone */
    bool known;                 /* vis holds the centre rays' answers */
} job;

/* Whether the ray from point q toward light direction L (unit; a point light: toward target, `far` away)
 * reaches it: 1 lit, 0 blocked. */
static int lit_toward(const job *j, ray_ctx *rc, const sb_ref_point *q, const float L[3], float far) {
    float eps = q->eps;
    struct RTCRay ray = {.org_x = q->p[0] + (q->n[0] + L[0]) * eps, .org_y = q->p[1] + (q->n[1] + L[1]) * eps,
                         .org_z = q->p[2] + (q->n[2] + L[2]) * eps, .dir_x = L[0], .dir_y = L[1], .dir_z = L[2],
                         .tnear = 0, .tfar = far > 0 ? far : 0, .mask = 0xffffffffu};
    rtcOccluded1((RTCScene)j->r->scene, &rc->ctx, &ray);
    return ray.tfar == -INFINITY ? 0 : 1;
}

/* The light's sample (x, y) on its unit disc, seen from q: the direction (and for a lamp the distance) of the
 * ray toward it. The sun's disc is the cone of tan(half angle) around L; a lamp's is its sphere's disc facing q. */
static float sample_dir(const job *j, const sb_ref_point *q, const float c[3], const float t[3], const float b[3],
                        float x, float y, float L[3]) {
    float far = INFINITY;
    if (j->point) {
        float d[3];
        for (int k = 0; k < 3; k++) d[k] = c[k] + j->r->lamp_radius * (x * t[k] + y * b[k]) - q->p[k];
        float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int k = 0; k < 3; k++) L[k] = len > 0 ? d[k] / len : 0;
        return len - 2 * q->eps;
    }
    float k_ = (float)j->r->sun_tan;
    for (int k = 0; k < 3; k++) L[k] = c[k] + k_ * (x * t[k] + y * b[k]);
    float len = sqrtf(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
    for (int k = 0; k < 3; k++) L[k] /= len;
    return far;
}

/* One point's answer: its centre ray, known (lit) or cast here (lit < 0); then, toward a sized light unless
 * `hard`, the 8 rim points (agreeing: full light or umbra) and else the N spiral points. *rays += what it cast. */
static unsigned char point_answer(const job *j, ray_ctx *rc, const sb_ref_point *q, int lit, bool hard,
                                  uint64_t *rays) {
    const sb_reference *r = j->r;
    float L[3] = {j->sun[0], j->sun[1], j->sun[2]}, far = INFINITY;
    if (j->point) {
        float d[3] = {j->sun[0] - q->p[0], j->sun[1] - q->p[1], j->sun[2] - q->p[2]};
        float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (len <= 0) return 255;
        for (int k = 0; k < 3; k++) L[k] = d[k] / len;
        far = len - 2 * q->eps;
    }
    if (lit < 0) {
        lit = lit_toward(j, rc, q, L, far);
        ++*rays;
    }
    if (hard || !(j->point ? r->lamp_radius > 0 : r->sun_tan > 0)) return lit ? 255 : 0;
    /* the light's disc, perpendicular to the direction toward its centre */
    float t[3], b[3], c[3] = {j->sun[0], j->sun[1], j->sun[2]};
    float up[3] = {fabsf(L[1]) < 0.9f ? 0.0f : 1.0f, fabsf(L[1]) < 0.9f ? 1.0f : 0.0f, 0};
    t[0] = up[1] * L[2] - up[2] * L[1], t[1] = up[2] * L[0] - up[0] * L[2], t[2] = up[0] * L[1] - up[1] * L[0];
    float tl = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int k = 0; k < 3; k++) t[k] /= tl;
    b[0] = L[1] * t[2] - L[2] * t[1], b[1] = L[2] * t[0] - L[0] * t[2], b[2] = L[0] * t[1] - L[1] * t[0];
    bool agree = true;
    for (int k = 0; k < 8 && agree; k++) {
        float a = (float)(k * SB_PI / 4), D[3];
        float fr = sample_dir(j, q, c, t, b, cosf(a), sinf(a), D);
        agree = lit_toward(j, rc, q, D, fr) == lit;
        ++*rays;
    }
    if (agree) return lit ? 255 : 0;
    /* a penumbra: N points of a golden-angle spiral over the disc, equal area each */
    int n = r->samples, on = 0;
    for (int k = 0; k < n; k++) {
        float rad = sqrtf((k + 0.5f) / n), a = (float)(k * 2.399963229728653), D[3];
        float fr = sample_dir(j, q, c, t, b, rad * cosf(a), rad * sinf(a), D);
        on += lit_toward(j, rc, q, D, fr);
    }
    *rays += (uint64_t)n;
    int v = (int)lrintf(255.0f * on / n);
    if (v == 128) v = 129;   /* 128 is "not evaluated" in the reference images */
    return (unsigned char)v;
}

/* Items [first, first + count): points idx[i] (or i), each point_answer's (from the centre answers vis already
 * holds when `known`; the centre ray alone when `hard`). */
static void occlusion(job *j) {
    ray_ctx rc;
    rtcInitIntersectContext(&rc.ctx);
    rc.camera = false;
    rc.all_faces = false;
    uint64_t rays = 0;
    for (int i = j->first; i < j->first + j->count; i++) {
        int k = j->idx ? j->idx[i] : i;
        const sb_ref_point *q = &j->pts[k];
        j->vis[k] = point_answer(j, &rc, q, j->known ? j->vis[k] >= 128 : -1, j->hard, &rays);
    }
    j->rays = rays;
}

static void first_hits(job *j) {
    ray_ctx rc;
    rtcInitIntersectContext(&rc.ctx);
    rc.camera = true;
    rc.all_faces = j->all_faces;
    for (int i = j->first; i < j->first + j->count; i++) {
        const float *o = j->from[i];
        float d[3] = {j->to[i][0] - o[0], j->to[i][1] - o[1], j->to[i][2] - o[2]};
        float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        sb_ref_hit *h = &j->hits[i];
        h->t = INFINITY;
        h->front = false;
        h->draw = UINT32_MAX;
        memset(h->n, 0, sizeof h->n);
        if (!(len > 0)) continue;
        struct RTCRayHit rh = {.ray = {.org_x = o[0], .org_y = o[1], .org_z = o[2], .dir_x = d[0] / len,
                                       .dir_y = d[1] / len, .dir_z = d[2] / len, .tnear = 0, .tfar = INFINITY,
                                       .mask = 0xffffffffu},
                               .hit = {.geomID = RTC_INVALID_GEOMETRY_ID}};
        rtcIntersect1((RTCScene)j->r->scene, &rc.ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        h->t = rh.ray.tfar;
        /* the scene's triangle: a draw's own (world) copy, also where the ray met a repeat of another's */
        unsigned gid = rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rh.hit.instID[0] : rh.hit.geomID;
        h->prim = (j->r->geom_first ? j->r->geom_first[gid] : 0) + rh.hit.primID;
        h->draw = j->r->geom_first ? gid : UINT32_MAX;   /* attached a geometry a draw, in draw order */
        /* the front face from the triangle's own winding (counter-clockwise, as glTF and GL say), as placed */
        const sb_scene *sc = j->r->src;
        const uint32_t *ix = sc->indices + 3 * (size_t)h->prim;
        float a[3], b[3], c[3];
        if (h->draw != UINT32_MAX) {
            const sb_draw *dr = &sc->draws[h->draw];
            sb_draw_point(sc, dr, ix[0], a), sb_draw_point(sc, dr, ix[1], b), sb_draw_point(sc, dr, ix[2], c);
        } else {
            memcpy(a, sb_vertex(sc, ix[0]), sizeof a), memcpy(b, sb_vertex(sc, ix[1]), sizeof b);
            memcpy(c, sb_vertex(sc, ix[2]), sizeof c);
        }
        float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        float nl = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        h->front = n[0] * d[0] + n[1] * d[1] + n[2] * d[2] < 0;
        float s = h->front ? 1.0f : -1.0f; /* the normal returned faces the ray's origin */
        for (int k = 0; k < 3 && nl > 0; k++) h->n[k] = s * n[k] / nl;
    }
}

static void *work(void *arg) {
    job *j = arg;
    if (j->from) first_hits(j);
    else occlusion(j);
    return NULL;
}

/* Runs `proto` over n items on up to `threads` threads; the rays the parts cast. */
static uint64_t run_jobs(const job *proto, int n, int threads) {
    if (threads < 1) threads = 1;
    if (threads > n) threads = n > 0 ? n : 1; /* no idle threads on a small frame */
    pthread_t *th = sb_xmalloc(sizeof *th * (size_t)threads);
    job *jobs = sb_xmalloc(sizeof *jobs * (size_t)threads);
    int per = (n + threads - 1) / threads;
    for (int t = 0; t < threads; t++) {
        jobs[t] = *proto;
        jobs[t].first = t * per;
        int end = (t + 1) * per < n ? (t + 1) * per : n;
        jobs[t].count = end > jobs[t].first ? end - jobs[t].first : 0;
        if (t > 0) pthread_create(&th[t], NULL, work, &jobs[t]);
    }
    work(&jobs[0]);
    for (int t = 1; t < threads; t++) pthread_join(th[t], NULL);
    uint64_t rays = 0;
    for (int t = 0; t < threads; t++) rays += jobs[t].rays;
    free(th);
    free(jobs);
    return rays;
}

uint64_t sb_reference_visibility(const sb_reference *r, sb_v3 sun, const sb_ref_point *pts, int n,
                                 unsigned char *vis, int threads) {
    const double light[4] = {sun.x, sun.y, sun.z, 0};
    return sb_reference_visibility_light(r, light, pts, n, vis, threads);
}

uint64_t sb_reference_visibility_light(const sb_reference *r, const double light[4], const sb_ref_point *pts, int n,
                                       unsigned char *vis, int threads) {
    job proto = {.r = r, .sun = {(float)light[0], (float)light[1], (float)light[2]}, .point = light[3] > 0.5,
                 .pts = pts, .vis = vis};   /* point_answer: one ray a point toward a light of no size */
    return run_jobs(&proto, n, threads);
}

uint64_t sb_reference_visibility_view(const sb_reference *r, const double light[4], const sb_ref_point *pts,
                                      const int *pix, int n, int w, int h, unsigned char *vis, int threads) {
    job proto = {.r = r, .sun = {(float)light[0], (float)light[1], (float)light[2]}, .point = light[3] > 0.5,
                 .pts = pts, .vis = vis, .hard = true};
    uint64_t rays = run_jobs(&proto, n, threads);   /* every point's centre ray */
    bool sized = proto.point ? r->lamp_radius > 0 : r->sun_tan > 0;
    if (!sized || n == 0) return rays;
    /* the penumbra from the centre rays' edges: a point whose screen neighbour's centre ray answers otherwise
       is answered over the light; one found inside a penumbra hands its neighbours on, until none is */
    int *kof = sb_xmalloc(sizeof(int) * (size_t)w * h);
    for (size_t i = 0; i < (size_t)w * h; i++) kof[i] = -1;
    for (int k = 0; k < n; k++) kof[pix[k]] = k;
    unsigned char *seen = sb_xcalloc((size_t)n, 1);
    int *batch = sb_xmalloc(sizeof(int) * (size_t)n), *next = sb_xmalloc(sizeof(int) * (size_t)n), nb = 0;
    for (int k = 0; k < n; k++) {
        int x = pix[k] % w, y = pix[k] / w;
        bool edge = false;
        for (int dy = -1; dy <= 1 && !edge; dy++)
            for (int dx = -1; dx <= 1 && !edge; dx++) {
                int xx = x + dx, yy = y + dy;
                if ((dx || dy) && xx >= 0 && yy >= 0 && xx < w && yy < h && kof[yy * w + xx] >= 0)
                    edge = vis[kof[yy * w + xx]] != vis[k];
            }
        if (edge) seen[k] = 1, batch[nb++] = k;
    }
    while (nb > 0) {
        job soft = proto;
        soft.hard = false;
        soft.known = true;
        soft.idx = batch;
        rays += run_jobs(&soft, nb, threads);
        int nn = 0;
        for (int i = 0; i < nb; i++) {
            int k = batch[i];
            if (vis[k] == 0 || vis[k] == 255) continue;   /* full light or umbra: the band ends here */
            int x = pix[k] % w, y = pix[k] / w;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int xx = x + dx, yy = y + dy, q;
                    if (xx < 0 || yy < 0 || xx >= w || yy >= h || (q = kof[yy * w + xx]) < 0 || seen[q]) continue;
                    seen[q] = 1;
                    next[nn++] = q;
                }
        }
        int *tmp = batch;
        batch = next, next = tmp, nb = nn;
    }
    free(kof);
    free(seen);
    free(batch);
    free(next);
    return rays;
}

void sb_reference_rays(const sb_reference *r, const float (*from)[3], const float (*to)[3], int n, sb_ref_hit *out,
                       int threads) {
    job proto = {.r = r, .from = from, .to = to, .hits = out};
    run_jobs(&proto, n, threads);
}

void sb_reference_rays_all_faces(const sb_reference *r, const float (*from)[3], const float (*to)[3], int n,
                                 sb_ref_hit *out, int threads) {
    job proto = {.r = r, .from = from, .to = to, .hits = out, .all_faces = true};
    run_jobs(&proto, n, threads);
}
