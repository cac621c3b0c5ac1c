/* raycast.c - ray-cast shadows (the Zagreb thesis), exact: a camera pass
 * writes every pixel's position and geometric normal (the evaluation
 * targets), then an Embree occlusion ray is cast from each toward the light
 * (offset from the surface by an epsilon that grows with distance, and limited
 * to the scene; the thesis's version had neither), and the camera pass reads
 * the result. The points are built exactly as the reference builds them
 * (sb_ref_points), so its error against the reference is zero up to the
 * rasterizer repeating itself; how exact that reference is, is the run's
 * err_floor. It has a cost of its own: the position pass is its `zpass`, the
 * readback and rays its `rays` stage. On a scene lit only by point lights it
 * casts toward the first of them (or the one `light` names), so the
 * point-light techniques have their reference row too. With --lights it
 * casts toward every light named (the sun, lamps within their range) and adds
 * each light in a camera pass of its own. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"
#include "render.h"
#include "reference.h"
#include "shaders.h"

/* Its own stage: the readback of the position pass and the rays. */
static const sb_stage_def stage_rays = {.name = "rays", .doc = "CPU ray casting (raycast)"};

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
    GLuint tex;
    int threads;
    bool point;             /* toward a point light, not the sun */
    sb_v3 lamp;
    int lamp_index;
    const sb_light_set *lights; /* --lights (NULL: the one light above) */
    float *pos, *aux;           /* the position pass's targets */
    sb_ref_point *pts;
    int *pix;
    unsigned char *hits, *vis;  /* vis: a frame's worth a light */
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
        s->lamp_index = want;
    }
    size_t n = (size_t)g->width * g->height;
    s->pos = sb_xmalloc(sizeof(float) * 4 * n);
    s->aux = sb_xmalloc(sizeof(float) * 4 * n);
    s->pts = sb_xmalloc(sizeof(sb_ref_point) * n);
    s->pix = sb_xmalloc(sizeof(int) * n);
    s->lights = rc->lights;
    s->hits = sb_xmalloc(n);
    s->vis = sb_xmalloc(n * (rc->lights ? (size_t)rc->lights->count : 1));
    s->tex = sb_cpu_vis_texture(g);
    if (!sb_final_prog_create(&s->fp, rc->gpu, "raycast", sb_shader_vis_cpu_glsl, NULL, err)) return false;
    return sb_gl_check("raycast", err);
}

/* Light i of the frame: the run's --lights, or the one light of before. */
static void shade(const raycast_state *s, sb_frame *f, int i) {
    if (s->lights) sb_frame_shade_light_of(f, s->lights->idx[i]);
    else if (s->point) sb_frame_shade_light_of(f, s->lamp_index);   /* its range too */
}

static void raycast_frame(void *state, sb_frame *f) {
    raycast_state *s = state;
    const sb_gpu *g = f->gpu;
    const int w = g->width, h = g->height;
    const size_t np = (size_t)w * h;
    /* every light, or the one an evaluation pass scores */
    int first, end;
    sb_frame_light_range(f, s->lights ? s->lights->count : 1, &first, &end);
    shade(s, f, first);

    /* the camera pass with the evaluation targets: positions and normals. Its
       depth test is the final pass's (LEQUAL: of equal depths the last drawn
       wins), so both passes put the same triangle in every pixel. */
    sb_stage_begin(f, &sb_stage_zpass);
    bool eval = f->eval;
    f->eval = true;
    glUseProgram(s->fp.prog);
    sb_gbuffer_pass(f, &s->fp);
    f->eval = eval;
    sb_stage_end(f, &sb_stage_zpass);

    sb_stage_begin(f, &stage_rays);
    sb_gpu_readback_eval(g, s->pos, s->aux);
    for (int i = first; i < end; i++) {
        shade(s, f, i);
        unsigned char *vis = s->vis + (size_t)(i - first) * np;
        sb_eval_view view = {w, h, s->pos, s->aux, sb_frame_eye(f), NULL, f->shade_light, f->shade_range,
                             {f->shade_spot[0], f->shade_spot[1], f->shade_spot[2], f->shade_spot[3]}, NULL};
        int m = sb_ref_points(s->ref, &view, s->pts, s->pix);
        memset(vis, 255, np);
        sb_reference_visibility_view(s->ref, f->shade_light, s->pts, s->pix, m, w, h, s->hits, s->threads);
        for (int k = 0; k < m; k++) vis[s->pix[k]] = s->hits[k];   /* 255 lit, 0 shadowed; a sized light between */
    }
    sb_cpu_vis_bind(s->tex, g, s->vis);   /* the first light's */
    sb_stage_end(f, &stage_rays);

    sb_stage_begin(f, &sb_stage_final);
    for (int i = first; i < end; i++) {   /* the first clears and lays the ambient, each further one adds its light */
        shade(s, f, i);
        glUseProgram(s->fp.prog);
        sb_cpu_vis_bind(s->tex, g, i > first ? s->vis + (size_t)(i - first) * np : NULL);
        if (i == first) sb_final_pass(f, &s->fp, true);
        else sb_final_pass_add(f, &s->fp);
    }
    sb_stage_end(f, &sb_stage_final);
}

static void raycast_destroy(void *state) {
    raycast_state *s = state;
    sb_final_prog_free(&s->fp);
    if (s->tex) glDeleteTextures(1, &s->tex);
    free(s->pos);
    free(s->aux);
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
    SB_STAGES(&sb_stage_zpass, &stage_rays, &sb_stage_final),
    .needs = SB_NEEDS_REFERENCE,
    .traits = SB_TRAIT_EXACT,
    .lights = SB_LIGHTS_ANY,
    .pixel_cost = 20,
    .stress = "",
    .state_size = sizeof(raycast_state),
    .supported = raycast_supported,
    .create = raycast_create,
    .frame = raycast_frame,
    .destroy = raycast_destroy,
};
