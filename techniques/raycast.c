/* raycast.c - ray-cast shadows (the Zagreb thesis), exact: a depth pre-pass,
 * then for every pixel the world position is reconstructed in double and an
 * Embree occlusion ray is cast toward the sun (offset from the surface by an
 * epsilon that grows with distance, and limited to the scene; the thesis's
 * version had neither), and the camera pass reads the result. It is the
 * reference every technique is measured against, with a cost of its own:
 * its readback and rays are the `rays` stage. On a scene lit only by point
 * lights it casts toward the first of them (or the one `light` names), so the
 * point-light techniques have their reference row too. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gpu.h"
#include "reference.h"
#include "shaders.h"

typedef struct raycast_desc {
    int threads, light;
} raycast_desc;

static const sb_param_def raycast_params[] = {
    SB_PARAM_I(raycast_desc, threads, 0, 0, 1024, "ray-casting threads (0: all cores)"),
    SB_PARAM_I(raycast_desc, light, -1, -1, 64,
               "-1: the sun (a scene lit only by point lights: its first point light); K: the K-th point or spot light"),
};

typedef struct {
    const sb_reference *ref;
    sb_final_prog fp;
    GLint u_rays;
    GLuint tex;
    int threads;
    bool point;             /* toward a point light, not the sun */
    sb_v3 lamp;
    float *depth;
    sb_ref_point *pts;
    int *pix;
    unsigned char *hits, *vis;
} raycast_state;

/* The point light the rays go to (light=K, or the first lamp of a scene without a sun), or -1: the sun. */
static int lamp_of(const sb_gpu *g, const raycast_desc *d) {
    if (d->light >= 0) return d->light;
    return !g->has_sun && sb_scene_point_light(g->scene, 0, NULL) ? 0 : -1;
}

static bool raycast_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    int want = lamp_of(rc->gpu, desc);
    return want < 0 || sb_lamp_supported(rc->gpu, want, "raycast", why);
}

static bool raycast_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    raycast_state *s = state;
    const sb_gpu *g = rc->gpu;
    const raycast_desc *d = desc;
    s->ref = rc->reference;
    s->threads = d->threads;
    if (s->threads == 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        s->threads = n > 0 ? (int)n : 1;
    }
    int want = lamp_of(g, d);
    if (want >= 0) {
        s->point = true;
        s->lamp = sb_scene_point_light(g->scene, want, NULL)->position;
    }
    size_t n = (size_t)g->width * g->height;
    s->depth = sb_xmalloc(sizeof(float) * n);
    s->pts = sb_xmalloc(sizeof(sb_ref_point) * n);
    s->pix = sb_xmalloc(sizeof(int) * n);
    s->hits = sb_xmalloc(n);
    s->vis = sb_xmalloc(n);
    glGenTextures(1, &s->tex);
    glBindTexture(GL_TEXTURE_2D, s->tex);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_R8, g->width, g->height);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    if (!sb_final_prog_create(&s->fp, "raycast", sb_shader_vis_raycast_glsl, NULL, err)) return false;
    s->u_rays = glGetUniformLocation(s->fp.prog, "u_rays");
    return sb_gl_check("raycast", err);
}

static void raycast_frame(void *state, sb_frame *f) {
    raycast_state *s = state;
    const sb_gpu *g = f->gpu;
    const int w = g->width, h = g->height;
    if (s->point) sb_frame_shade_point(f, s->lamp);

    sb_stage_begin(f, SB_STAGE_ZPASS);
    sb_zpass(f);
    sb_stage_end(f, SB_STAGE_ZPASS);

    sb_stage_begin(f, SB_STAGE_RAYS);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, g->fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, s->depth);
    sb_m4 inv;
    sb_m4_invert(f->view_proj, &inv);
    sb_v3 eye = sb_v3_sub(f->cam.pos, g->scene->origin);
    int m = 0;
    memset(s->vis, 255, (size_t)w * h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float d = s->depth[y * w + x];
            if (d >= 1.0f) continue;
#define SB_AT(px, py, dd) sb_m4_point(inv, sb_v3_make(2 * ((px) + 0.5) / w - 1, 2 * ((py) + 0.5) / h - 1, 2 * (double)(dd) - 1))
            sb_v3 p = SB_AT(x, y, d);
            /* normal from the neighbours whose depth is closest (never across an edge) */
            int xo = x + 1 < w ? 1 : -1, yo = y + 1 < h ? 1 : -1;
            if (x > 0 && x + 1 < w && fabsf(s->depth[y * w + x - 1] - d) < fabsf(s->depth[y * w + x + 1] - d)) xo = -1;
            if (y > 0 && y + 1 < h && fabsf(s->depth[(y - 1) * w + x] - d) < fabsf(s->depth[(y + 1) * w + x] - d)) yo = -1;
            sb_v3 px = SB_AT(x + xo, y, s->depth[y * w + x + xo]), py = SB_AT(x, y + yo, s->depth[(y + yo) * w + x]);
#undef SB_AT
            sb_v3 n = sb_v3_norm(sb_v3_cross(sb_v3_sub(px, p), sb_v3_sub(py, p)));
            if (sb_v3_dot(n, sb_v3_sub(eye, p)) < 0) n = sb_v3_scale(n, -1);
            sb_ref_point *q = &s->pts[m];
            q->p[0] = (float)p.x;
            q->p[1] = (float)p.y;
            q->p[2] = (float)p.z;
            q->n[0] = (float)n.x;
            q->n[1] = (float)n.y;
            q->n[2] = (float)n.z;
            /* a depth-buffer position is off along the view ray by up to
               z^2 (f-n)/(n f) per unit of depth: a few ulps of d */
            double z = sb_v3_dot(sb_v3_sub(p, eye), f->cam.forward), zn = f->cam.znear, zf = f->cam.zfar;
            double depth_err = z * z * (zf - zn) / (zn * zf) * ldexp(1.0, -22);
            q->eps = fmaxf(sb_ref_position_eps(s->ref, q->p, (float)z), (float)depth_err);
            s->pix[m++] = y * w + x;
        }
    sb_reference_visibility_light(s->ref, f->shade_light, s->pts, m, s->hits, s->threads);
    for (int k = 0; k < m; k++) s->vis[s->pix[k]] = s->hits[k] ? 255 : 0;
    glBindTexture(GL_TEXTURE_2D, s->tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RED, GL_UNSIGNED_BYTE, s->vis);
    sb_stage_end(f, SB_STAGE_RAYS);

    sb_stage_begin(f, SB_STAGE_FINAL);
    glUseProgram(s->fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, s->tex);
    glUniform1i(s->u_rays, 0);
    sb_final_pass(f, &s->fp, true);
    sb_stage_end(f, SB_STAGE_FINAL);
}

static void raycast_destroy(void *state) {
    raycast_state *s = state;
    sb_final_prog_free(&s->fp);
    if (s->tex) glDeleteTextures(1, &s->tex);
    free(s->depth);
    free(s->pts);
    free(s->pix);
    free(s->hits);
    free(s->vis);
}

const sb_technique sb_technique_raycast = {
    .name = "raycast",
    .summary = "exact ray-cast shadows on the CPU (Embree), shaded on the GPU: the reference row",
    .params = raycast_params,
    .param_count = (int)SB_COUNT(raycast_params),
    .desc_size = sizeof(raycast_desc),
    .stages = SB_STAGE_BIT(SB_STAGE_ZPASS) | SB_STAGE_BIT(SB_STAGE_RAYS) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_REFERENCE,
    .state_size = sizeof(raycast_state),
    .supported = raycast_supported,
    .create = raycast_create,
    .frame = raycast_frame,
    .destroy = raycast_destroy,
};
