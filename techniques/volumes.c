/* volumes.c - stencil shadow volumes (Crow 1977; z-pass, and z-fail as in
 * Carmack's reverse). Silhouette edges are found on the CPU once per light
 * direction (the sun is fixed for a run): welded positions give each edge its
 * two triangles, and an edge between a light-facing and a back-facing
 * triangle (or an open edge of a light-facing one) is extruded to infinity
 * away from the light. z-fail also draws the light caps (the light-facing
 * triangles); for a directional light the dark cap collapses to a point at
 * infinity. Depth clamping keeps the geometry at infinity.
 *
 * Stages: zpass (depth and stencil cleared), volumes (stencil counts), final
 * (the camera pass drawn twice: stencil 0 lit, else shadowed).
 * mode=zpass counts where the depth test passes (wrong with the camera inside
 * a volume), zfail where it fails (needs closed casters), auto uses z-fail only
 * when a ray from the camera toward the sun is blocked (the camera is in a
 * volume). Casters that are not closed are reported once at creation. */
#include <stdlib.h>
#include <string.h>


#include "motion.h"
#include "render.h"
#include "reference.h"
#include "shaders.h"

typedef struct volumes_desc {
    int mode;
} volumes_desc;

enum { MODE_ZPASS, MODE_ZFAIL, MODE_AUTO };

static const sb_param_def volumes_params[] = {
    SB_PARAM_E(volumes_desc, mode, auto, "zpass|zfail|auto",
               "stencil counting: depth pass, depth fail, or z-fail when the camera is in shadow"),
};

/* What a scene's volumes are, for its sun: made once per scene (load). */
typedef struct volumes_geo {
    GLuint vao, vbo;
    GLuint prog;
    GLint u_view, u_proj;
    sb_final_prog fp;
    GLint u_lit;
    /* per scene draw: its silhouette quads, then its light caps (in vertices) */
    uint32_t *side_first, *side_count, *cap_first, *cap_count;
    uint32_t open_edges;
} volumes_geo;

typedef struct {
    int mode;
    const volumes_geo *geo;
    const sb_reference *ref;
} volumes_state;

typedef struct {
    uint32_t a, b;      /* welded vertex ids, a < b */
    uint32_t tri;       /* triangle (index of its first index / 3) */
} edge;

static int cmp_edge(const void *x, const void *y) {
    const edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->tri < q->tri ? -1 : p->tri > q->tri;
}

typedef struct {
    float p[3];
    uint32_t v;
} weld_key;

static const float *flat_vertex(const sb_scene_flat *f, uint32_t i) {
    return f->vertices + (size_t)SB_VERTEX_FLOATS * i;
}

static int cmp_weld(const void *x, const void *y) {
    const weld_key *p = x, *q = y;
    int c = memcmp(p->p, q->p, sizeof p->p);
    return c ? c : p->v < q->v ? -1 : p->v > q->v;
}

/* Welded ids: vertices with equal coordinates share one (meshes split vertices per face). */
static uint32_t *weld(const sb_scene_flat *sc) {
    uint32_t nv = sc->vertex_count;
    weld_key *k = sb_xmalloc(sizeof *k * (nv ? nv : 1));
    uint32_t *id = sb_xmalloc(sizeof(uint32_t) * (nv ? nv : 1));
    for (uint32_t i = 0; i < nv; i++) {
        memcpy(k[i].p, flat_vertex(sc, i), sizeof k[i].p);
        k[i].v = i;
    }
    qsort(k, nv, sizeof *k, cmp_weld);
    for (uint32_t i = 0; i < nv; i++)
        id[k[i].v] = i > 0 && !memcmp(k[i].p, k[i - 1].p, sizeof k[i].p) ? id[k[i - 1].v] : k[i].v;
    free(k);
    return id;
}

/* Per triangle edge slot, 1 where the volume gets a side quad: an edge between
 * a lit and an unlit triangle, or an open edge of a lit one. */
static uint8_t *silhouettes(const sb_scene_flat *sc, const uint32_t *wid, const uint8_t *lit, uint32_t *open_edges) {
    uint32_t ntri = sc->index_count / 3;
    edge *edges = sb_xmalloc(sizeof(edge) * 3 * (size_t)(ntri ? ntri : 1));
    for (uint32_t t = 0; t < ntri; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = wid[sc->indices[3 * (size_t)t + k]], v = wid[sc->indices[3 * (size_t)t + (k + 1) % 3]];
            edges[3 * (size_t)t + k] = (edge){u < v ? u : v, u < v ? v : u, t};
        }
    qsort(edges, 3 * (size_t)ntri, sizeof(edge), cmp_edge);
    uint8_t *sil = sb_xcalloc(3 * (size_t)(ntri ? ntri : 1), 1);
    for (size_t i = 0; i < 3 * (size_t)ntri;) {
        size_t j = i;
        while (j < 3 * (size_t)ntri && edges[j].a == edges[i].a && edges[j].b == edges[i].b) j++;
        size_t count = j - i;
        if (count != 2) (*open_edges)++;
        for (size_t k = i; k < j; k++) {
            uint32_t t = edges[k].tri;
            if (!lit[t]) continue;
            bool dark_neighbour = count == 1; /* open edge of a lit triangle */
            for (size_t m = i; m < j; m++)
                if (m != k && !lit[edges[m].tri]) dark_neighbour = true;
            if (!dark_neighbour) continue;
            const uint32_t *ix = sc->indices + 3 * (size_t)t; /* the slot of this edge in triangle t */
            for (int e = 0; e < 3; e++) {
                uint32_t u = wid[ix[e]], v = wid[ix[(e + 1) % 3]];
                if ((u == edges[k].a && v == edges[k].b) || (u == edges[k].b && v == edges[k].a)) sil[3 * (size_t)t + e] = 1;
            }
        }
        i = j;
    }
    free(edges);
    return sil;
}

typedef struct {
    float *v;
    size_t n, cap;
} vbuf;

static void push4(vbuf *b, const float *p, float w, const float *off) {
    if (b->n + 4 > b->cap) {
        b->cap = b->cap ? b->cap * 2 : 4096;
        b->v = sb_xrealloc(b->v, b->cap * sizeof(float));
    }
    b->v[b->n++] = p[0] + off[0];
    b->v[b->n++] = p[1] + off[1];
    b->v[b->n++] = p[2] + off[2];
    b->v[b->n++] = w;
}

/* Per scene draw: the sides (from the lit triangle's edge, extruded to infinity), then the light caps. */
static void build_geometry(volumes_geo *geo, const sb_scene *scene, const sb_scene_flat *sc, sb_v3 sun,
                           const uint8_t *lit, const uint8_t *sil, vbuf *vb) {
    const float L[3] = {(float)sun.x, (float)sun.y, (float)sun.z};
    float eps = (float)(sb_v3_len(sb_v3_sub(scene->bounds.hi, scene->bounds.lo)) * 1e-5);
    const float off[3] = {-L[0] * eps, -L[1] * eps, -L[2] * eps}, away[3] = {-L[0], -L[1], -L[2]}, zero[3] = {0, 0, 0};
    uint32_t nd = scene->draw_count;
    geo->side_first = sb_xcalloc(nd + 1, sizeof(uint32_t));
    geo->side_count = sb_xcalloc(nd + 1, sizeof(uint32_t));
    geo->cap_first = sb_xcalloc(nd + 1, sizeof(uint32_t));
    geo->cap_count = sb_xcalloc(nd + 1, sizeof(uint32_t));
    for (uint32_t d = 0; d < nd; d++) {
        const sb_draw *dr = &scene->draws[d];
        uint32_t t0 = sc->first[d] / 3, t1 = (sc->first[d] + dr->index_count) / 3;
        geo->side_first[d] = (uint32_t)(vb->n / 4);
        for (uint32_t t = t0; t < t1; t++) {
            const uint32_t *ix = sc->indices + 3 * (size_t)t;
            for (int e = 0; e < 3; e++) {
                if (!sil[3 * (size_t)t + e]) continue;
                const float *a = flat_vertex(sc, ix[e]), *b = flat_vertex(sc, ix[(e + 1) % 3]);
                /* the side is the lit triangle's neighbour across a -> b: it runs b -> a */
                push4(vb, b, 1, off);
                push4(vb, a, 1, off);
                push4(vb, away, 0, zero);
                push4(vb, b, 1, off);
                push4(vb, away, 0, zero);
                push4(vb, away, 0, zero);
            }
        }
        geo->side_count[d] = (uint32_t)(vb->n / 4) - geo->side_first[d];
        geo->cap_first[d] = (uint32_t)(vb->n / 4);
        for (uint32_t t = t0; t < t1; t++) {
            if (!lit[t]) continue;
            const uint32_t *ix = sc->indices + 3 * (size_t)t;
            for (int k = 0; k < 3; k++) push4(vb, flat_vertex(sc, ix[k]), 1, off);
        }
        geo->cap_count[d] = (uint32_t)(vb->n / 4) - geo->cap_first[d];
    }
}

static void volumes_unload(void *data) {
    volumes_geo *geo = data;
    if (!geo) return;
    sb_final_prog_free(&geo->fp);
    if (geo->prog) glDeleteProgram(geo->prog);
    if (geo->vbo) glDeleteBuffers(1, &geo->vbo);
    if (geo->vao) glDeleteVertexArrays(1, &geo->vao);
    free(geo->side_first);
    free(geo->side_count);
    free(geo->cap_first);
    free(geo->cap_count);
    free(geo);
}

/* Silhouettes for the session's sun, their vertex buffer and the programs: once per scene. */
static bool volumes_load(const sb_gpu *g, void **data, sb_err *err) {
    const sb_scene *scene = g->scene;
    volumes_geo *geo = sb_xcalloc(1, sizeof *geo);
    *data = geo;
    sb_scene_sync_vertices(scene);   /* the silhouettes of the pose the scene holds */
    sb_scene_flat flat, *sc = &flat;   /* every triangle as placed: an instance's silhouette is its own */
    sb_scene_flatten(scene, NULL, &flat);
    uint32_t ntri = sc->index_count / 3, *wid = weld(sc);
    uint8_t *lit = sb_xcalloc(ntri ? ntri : 1, 1);
    for (uint32_t t = 0; t < ntri; t++) {
        const uint32_t *ix = sc->indices + 3 * (size_t)t;
        const float *a = flat_vertex(sc, ix[0]), *b = flat_vertex(sc, ix[1]), *c = flat_vertex(sc, ix[2]);
        sb_v3 n = sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                              sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2]));
        lit[t] = sb_v3_dot(n, g->sun) > 0;
    }
    uint8_t *sil = silhouettes(sc, wid, lit, &geo->open_edges);
    vbuf vb = {0};
    build_geometry(geo, scene, sc, g->sun, lit, sil, &vb);
    free(sil);
    free(lit);
    free(wid);
    sb_scene_flat_free(&flat);
    glGenVertexArrays(1, &geo->vao);
    glBindVertexArray(geo->vao);
    glGenBuffers(1, &geo->vbo);
    glBindBuffer(GL_ARRAY_BUFFER, geo->vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(vb.n * sizeof(float)), vb.v, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 16, (void *)0);
    free(vb.v);
    if (geo->open_edges)
        sb_log("volumes: %u edge(s) of the casters are open or shared by more than two triangles: the casters are "
               "not closed, so counts can be wrong where a volume is open (z-fail most of all)",
               geo->open_edges);
    const char *vs[] = {sb_shader_volume_vert};
    const char *fs[] = {sb_shader_depth_frag};
    /* extruded silhouettes have no texture coordinates: no alpha test (README: volumes on alpha-tested scenes) */
    if (!(geo->prog = sb_gpu_program("volumes", "#define SB_NO_ALPHA\n", vs, 1, fs, 1, err))) return false;
    geo->u_view = glGetUniformLocation(geo->prog, "u_view");
    geo->u_proj = glGetUniformLocation(geo->prog, "u_proj");
    if (!sb_final_prog_create(&geo->fp, g, "volumes", sb_shader_vis_volumes_glsl, NULL, err)) return false;
    geo->u_lit = glGetUniformLocation(geo->fp.prog, "u_lit");
    return sb_gl_check("volumes", err);
}

static bool volumes_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    (void)err;
    volumes_state *s = state;
    s->mode = ((const volumes_desc *)desc)->mode;
    s->geo = rc->scene_data;
    s->ref = rc->reference;
    return true;
}

/* Is the camera inside a shadow volume? A ray from it toward the sun is blocked. */
static bool camera_in_shadow(const volumes_state *s, const sb_frame *f) {
    const sb_gpu *g = f->gpu;
    sb_v3 eye = sb_v3_sub(f->cam.pos, g->scene->origin);
    sb_ref_point q = {{(float)eye.x, (float)eye.y, (float)eye.z}, {0, 0, 0}, (float)(f->cam.znear * 0.5)};
    unsigned char vis;
    sb_reference_visibility(s->ref, g->sun, &q, 1, &vis, 1);
    return vis < 128;   /* the centre ray's answer, or a sized sun's: more than half of it hidden */
}

static void volumes_frame(void *state, sb_frame *f) {
    volumes_state *s = state;
    const volumes_geo *geo = s->geo;
    const sb_gpu *g = f->gpu;
    const sb_scene *sc = g->scene;

    sb_stage_begin(f, &sb_stage_zpass);
    sb_zpass(f);
    sb_stage_end(f, &sb_stage_zpass);

    sb_stage_begin(f, &sb_stage_volumes);
    bool zfail = s->mode == MODE_ZFAIL || (s->mode == MODE_AUTO && camera_in_shadow(s, f));
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
    glDrawBuffer(GL_NONE);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_CLAMP);
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_ALWAYS, 0, 0xff);
    if (zfail) {
        glStencilOpSeparate(GL_BACK, GL_KEEP, GL_INCR_WRAP, GL_KEEP);
        glStencilOpSeparate(GL_FRONT, GL_KEEP, GL_DECR_WRAP, GL_KEEP);
    } else {
        glStencilOpSeparate(GL_FRONT, GL_KEEP, GL_KEEP, GL_INCR_WRAP);
        glStencilOpSeparate(GL_BACK, GL_KEEP, GL_KEEP, GL_DECR_WRAP);
    }
    glUseProgram(geo->prog);
    sb_set_camera_uniforms(f, geo->u_view, geo->u_proj);
    glBindVertexArray(geo->vao);
    for (uint32_t d = 0; d < sc->draw_count; d++) {
        /* z-pass needs the sides only; z-fail closes the volume with the light cap */
        uint32_t first = geo->side_first[d], count = geo->side_count[d] + (zfail ? geo->cap_count[d] : 0);
        if (!count) continue;
        glDrawArrays(GL_TRIANGLES, (GLint)first, (GLsizei)count);
        sb_count_draw(f, count / 3, 1);
    }
    glDisable(GL_DEPTH_CLAMP);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    f->counters.cascades_rendered = 0;
    sb_stage_end(f, &sb_stage_volumes);

    sb_stage_begin(f, &sb_stage_final);
    sb_final_pass_stencil(f, &geo->fp, geo->u_lit, 0xff);
    sb_stage_end(f, &sb_stage_final);
}

static void volumes_destroy(void *state) { (void)state; /* everything is the scene's (load) */ }

const sb_technique sb_technique_volumes = {
    .name = "volumes",
    .summary = "stencil shadow volumes from CPU silhouettes (Crow 1977; z-pass, z-fail, auto)",
    .params = volumes_params,
    .param_count = (int)SB_COUNT(volumes_params),
    .desc_size = sizeof(volumes_desc),
    SB_STAGES(&sb_stage_zpass, &sb_stage_volumes, &sb_stage_final),
    .needs = SB_NEEDS_SUN | SB_NEEDS_CLOSED | SB_NEEDS_REFERENCE,
    .state_size = sizeof(volumes_state),
    .load = volumes_load,
    .unload = volumes_unload,
    .create = volumes_create,
    .frame = volumes_frame,
    .destroy = volumes_destroy,
};
