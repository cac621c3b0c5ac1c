/* reference.c - Embree occlusion rays toward the sun. */
#include "reference.h"

#include <embree3/rtcore.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

bool sb_reference_build(sb_reference *r, const sb_scene *s, sb_err *err) {
    memset(r, 0, sizeof *r);
    double t0 = sb_now_ms();
    RTCDevice dev = rtcNewDevice(NULL);
    if (!dev) return sb_fail(err, "embree: cannot create a device (error %d)", (int)rtcGetDeviceError(NULL));
    RTCScene scene = rtcNewScene(dev);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    /* positions are the first 3 floats of each 24-byte vertex; the normal after
       them keeps Embree's 16-byte reads of the last vertex inside the buffer */
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s->vertices, 0, 6 * sizeof(float),
                               s->vertex_count);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s->indices, 0, 3 * sizeof(uint32_t),
                               s->index_count / 3);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    rtcCommitScene(scene);
    enum RTCError e = rtcGetDeviceError(dev);
    if (e != RTC_ERROR_NONE) {
        rtcReleaseScene(scene);
        rtcReleaseDevice(dev);
        return sb_fail(err, "embree: building the scene failed (error %d)", (int)e);
    }
    r->device = dev;
    r->scene = scene;
    sb_v3 ext = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    r->eps_scene = (float)(sb_v3_len(ext) * 1e-6);
    r->build_ms = sb_now_ms() - t0;
    return true;
}

void sb_reference_free(sb_reference *r) {
    if (r->scene) rtcReleaseScene(r->scene);
    if (r->device) rtcReleaseDevice(r->device);
    memset(r, 0, sizeof *r);
}

float sb_ref_position_eps(const sb_reference *r, const float p[3], float dist) {
    /* float positions relative to the origin are exact to ~1e-7 of their size;
       the rasterizer's interpolation adds a few ulps of the camera distance */
    float mag = fmaxf(fmaxf(fabsf(p[0]), fabsf(p[1])), fabsf(p[2]));
    return 1.6e-5f * (mag + dist) + r->eps_scene;
}

typedef struct {
    const sb_reference *r;
    float sun[3];
    bool point;                 /* sun holds a point light's position */
    const sb_ref_point *pts;
    unsigned char *vis;
    int first, count;
} job;

static void *work(void *arg) {
    job *j = arg;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int i = j->first; i < j->first + j->count; i++) {
        const sb_ref_point *q = &j->pts[i];
        float eps = q->eps;
        float L[3] = {j->sun[0], j->sun[1], j->sun[2]}, far = INFINITY;
        if (j->point) {
            float d[3] = {j->sun[0] - q->p[0], j->sun[1] - q->p[1], j->sun[2] - q->p[2]};
            float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (len <= 0) {
                j->vis[i] = 1;
                continue;
            }
            for (int k = 0; k < 3; k++) L[k] = d[k] / len;
            far = len - 2 * eps;
        }
        struct RTCRay ray;
        ray.org_x = q->p[0] + (q->n[0] + L[0]) * eps;
        ray.org_y = q->p[1] + (q->n[1] + L[1]) * eps;
        ray.org_z = q->p[2] + (q->n[2] + L[2]) * eps;
        ray.dir_x = L[0];
        ray.dir_y = L[1];
        ray.dir_z = L[2];
        ray.tnear = 0;
        ray.tfar = far > 0 ? far : 0;
        ray.time = 0;
        ray.mask = 0xffffffffu;
        ray.id = 0;
        ray.flags = 0;
        rtcOccluded1((RTCScene)j->r->scene, &ctx, &ray);
        j->vis[i] = ray.tfar == -INFINITY ? 0 : 1;
    }
    return NULL;
}

uint64_t sb_reference_visibility(const sb_reference *r, sb_v3 sun, const sb_ref_point *pts, int n,
                                 unsigned char *vis, int threads) {
    const double light[4] = {sun.x, sun.y, sun.z, 0};
    return sb_reference_visibility_light(r, light, pts, n, vis, threads);
}

uint64_t sb_reference_visibility_light(const sb_reference *r, const double light[4], const sb_ref_point *pts, int n,
                                       unsigned char *vis, int threads) {
    if (threads < 1) threads = 1;
    if (threads > n) threads = n > 0 ? n : 1;   /* no idle threads on a small frame */
    pthread_t *th = sb_xmalloc(sizeof *th * (size_t)threads);
    job *jobs = sb_xmalloc(sizeof *jobs * (size_t)threads);
    int per = (n + threads - 1) / threads;
    for (int t = 0; t < threads; t++) {
        jobs[t] = (job){r, {(float)light[0], (float)light[1], (float)light[2]}, light[3] > 0.5, pts, vis, t * per, 0};
        int end = (t + 1) * per < n ? (t + 1) * per : n;
        jobs[t].count = end > jobs[t].first ? end - jobs[t].first : 0;
        if (t > 0) pthread_create(&th[t], NULL, work, &jobs[t]);
    }
    work(&jobs[0]);
    for (int t = 1; t < threads; t++) pthread_join(th[t], NULL);
    free(th);
    free(jobs);
    return (uint64_t)n;
}
