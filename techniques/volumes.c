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


#include "gpu.h"
#include "reference.h"
#include "shaders.h"

static const sb_param_def volumes_params[] = {
    {"mode", SB_PARAM_ENUM, "auto", 0, 0, "zpass|zfail|auto", "stencil counting: depth pass, depth fail, or z-fail when the camera is in shadow"},
};

enum { MODE_ZPASS, MODE_ZFAIL, MODE_AUTO };

typedef struct {
    int mode;
    GLuint vao, vbo;
    GLuint prog;
    GLint u_view, u_proj;
    sb_final_prog fp;
    GLint u_lit;
    /* per scene draw: its silhouette quads, then its light caps (in vertices) */
    uint32_t *side_first, *side_count, *cap_first, *cap_count;
    uint32_t open_edges;
} volumes_state;

typedef struct {
    uint32_t a, b;      /* welded vertex ids, a < b */
    uint32_t tri;       /* triangle (index of its first index / 3) */
    uint8_t forward;    /* the triangle traverses the edge a -> b */
} edge;

static int cmp_edge(const void *x, const void *y) {
    const edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->tri < q->tri ? -1 : p->tri > q->tri;
}

static const float *g_v;
static int cmp_pos(const void *x, const void *y) {
    const float *p = g_v + 6 * (size_t)*(const uint32_t *)x, *q = g_v + 6 * (size_t)*(const uint32_t *)y;
    return memcmp(p, q, 12);
}

typedef struct {
    float *v;
    size_t n, cap;
} vbuf;

static void push4(vbuf *b, const float *p, float w, const float *off) {
    if (b->n + 4 > b->cap) {
        b->cap = b->cap ? b->cap * 2 : 4096;
        b->v = realloc(b->v, b->cap * sizeof(float));
    }
    b->v[b->n++] = p[0] + off[0];
    b->v[b->n++] = p[1] + off[1];
    b->v[b->n++] = p[2] + off[2];
    b->v[b->n++] = w;
}

static bool volumes_create(void *state, sb_gpu *g, const sb_params *p, sb_err *err) {
    volumes_state *s = state;
    s->mode = sb_param_choice(p, "mode");
    const sb_scene *sc = g->scene;
    /* weld positions: equal coordinates share an id (meshes split vertices per face) */
    uint32_t nv = sc->vertex_count, *order = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    uint32_t *weld = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    for (uint32_t i = 0; i < nv; i++) order[i] = i;
    g_v = sc->vertices;
    qsort(order, nv, sizeof(uint32_t), cmp_pos);
    for (uint32_t i = 0; i < nv; i++)
        weld[order[i]] = i > 0 && cmp_pos(&order[i], &order[i - 1]) == 0 ? weld[order[i - 1]] : order[i];
    free(order);
    uint32_t ntri = sc->index_count / 3;
    uint8_t *lit = calloc(ntri ? ntri : 1, 1);
    edge *edges = malloc(sizeof(edge) * 3 * (size_t)(ntri ? ntri : 1));
    const float L[3] = {(float)g->sun.x, (float)g->sun.y, (float)g->sun.z};
    for (uint32_t t = 0; t < ntri; t++) {
        const uint32_t *ix = sc->indices + 3 * (size_t)t;
        const float *a = sc->vertices + 6 * (size_t)ix[0], *b = sc->vertices + 6 * (size_t)ix[1],
                    *c = sc->vertices + 6 * (size_t)ix[2];
        sb_v3 n = sb_v3_cross(sb_v3_make(b[0] - a[0], b[1] - a[1], b[2] - a[2]),
                              sb_v3_make(c[0] - a[0], c[1] - a[1], c[2] - a[2]));
        lit[t] = n.x * L[0] + n.y * L[1] + n.z * L[2] > 0;
        for (int k = 0; k < 3; k++) {
            uint32_t u = weld[ix[k]], v = weld[ix[(k + 1) % 3]];
            edges[3 * (size_t)t + k] = (edge){u < v ? u : v, u < v ? v : u, t, (uint8_t)(u < v)};
        }
    }
    qsort(edges, 3 * (size_t)ntri, sizeof(edge), cmp_edge);
    /* silhouette edges, per triangle edge slot: 1 where the volume gets a side quad */
    uint8_t *sil = calloc(3 * (size_t)(ntri ? ntri : 1), 1);
    for (size_t i = 0; i < 3 * (size_t)ntri;) {
        size_t j = i;
        while (j < 3 * (size_t)ntri && edges[j].a == edges[i].a && edges[j].b == edges[i].b) j++;
        size_t count = j - i;
        if (count != 2) s->open_edges++;
        for (size_t k = i; k < j; k++) {
            uint32_t t = edges[k].tri;
            if (!lit[t]) continue;
            bool dark_neighbour = count == 1; /* open edge of a lit triangle */
            for (size_t m = i; m < j; m++)
                if (m != k && !lit[edges[m].tri]) dark_neighbour = true;
            if (!dark_neighbour) continue;
            /* mark the slot of this edge in triangle t */
            const uint32_t *ix = sc->indices + 3 * (size_t)t;
            for (int e = 0; e < 3; e++) {
                uint32_t u = weld[ix[e]], v = weld[ix[(e + 1) % 3]];
                if ((u == edges[k].a && v == edges[k].b) || (u == edges[k].b && v == edges[k].a)) sil[3 * (size_t)t + e] = 1;
            }
        }
        i = j;
    }
    free(edges);
    /* geometry per scene draw: sides (a, b from the lit triangle, extruded), then light caps */
    sb_v3 ext = sb_v3_sub(sc->bounds.hi, sc->bounds.lo);
    float eps = (float)(sb_v3_len(ext) * 1e-5);
    const float off[3] = {-L[0] * eps, -L[1] * eps, -L[2] * eps}, away[3] = {-L[0], -L[1], -L[2]}, zero[3] = {0, 0, 0};
    uint32_t nd = sc->draw_count;
    s->side_first = calloc(nd + 1, sizeof(uint32_t));
    s->side_count = calloc(nd + 1, sizeof(uint32_t));
    s->cap_first = calloc(nd + 1, sizeof(uint32_t));
    s->cap_count = calloc(nd + 1, sizeof(uint32_t));
    vbuf vb = {0};
    for (uint32_t d = 0; d < nd; d++) {
        const sb_draw *dr = &sc->draws[d];
        s->side_first[d] = (uint32_t)(vb.n / 4);
        for (uint32_t t = dr->first_index / 3; t < (dr->first_index + dr->index_count) / 3; t++) {
            const uint32_t *ix = sc->indices + 3 * (size_t)t;
            for (int e = 0; e < 3; e++) {
                if (!sil[3 * (size_t)t + e]) continue;
                const float *a = sc->vertices + 6 * (size_t)ix[e], *b = sc->vertices + 6 * (size_t)ix[(e + 1) % 3];
                /* the side is the lit triangle's neighbour across a -> b: it runs b -> a */
                push4(&vb, b, 1, off);
                push4(&vb, a, 1, off);
                push4(&vb, away, 0, zero);
                push4(&vb, b, 1, off);
                push4(&vb, away, 0, zero);
                push4(&vb, away, 0, zero);
            }
        }
        s->side_count[d] = (uint32_t)(vb.n / 4) - s->side_first[d];
        s->cap_first[d] = (uint32_t)(vb.n / 4);
        for (uint32_t t = dr->first_index / 3; t < (dr->first_index + dr->index_count) / 3; t++) {
            if (!lit[t]) continue;
            const uint32_t *ix = sc->indices + 3 * (size_t)t;
            for (int k = 0; k < 3; k++) push4(&vb, sc->vertices + 6 * (size_t)ix[k], 1, off);
        }
        s->cap_count[d] = (uint32_t)(vb.n / 4) - s->cap_first[d];
    }
    free(sil);
    free(lit);
    free(weld);
    glGenVertexArrays(1, &s->vao);
    glBindVertexArray(s->vao);
    glGenBuffers(1, &s->vbo);
    glBindBuffer(GL_ARRAY_BUFFER, s->vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(vb.n * sizeof(float)), vb.v, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 16, (void *)0);
    free(vb.v);
    if (s->open_edges)
        sb_log("volumes: %u edge(s) of the casters are open or shared by more than two triangles: the casters are "
               "not closed, so counts can be wrong where a volume is open (z-fail most of all)",
               s->open_edges);
    const char *vs[] = {sb_shader_volume_vert};
    const char *fs[] = {sb_shader_depth_frag};
    s->prog = sb_gpu_program("volumes", NULL, vs, 1, fs, 1, err);
    if (!s->prog) return false;
    s->u_view = glGetUniformLocation(s->prog, "u_view");
    s->u_proj = glGetUniformLocation(s->prog, "u_proj");
    if (!sb_final_prog_create(&s->fp, "volumes", sb_shader_vis_volumes_glsl, NULL, err)) return false;
    s->u_lit = glGetUniformLocation(s->fp.prog, "u_lit");
    if (s->mode != MODE_ZPASS && !sb_gpu_reference(g, err)) return false;
    return sb_gl_check("volumes", err);
}

/* Is the camera inside a shadow volume? A ray from it toward the sun is blocked. */
static bool camera_in_shadow(const sb_frame *f) {
    sb_gpu *g = f->gpu;
    sb_v3 eye = sb_v3_sub(f->cam.pos, g->scene->origin);
    sb_ref_point q = {{(float)eye.x, (float)eye.y, (float)eye.z}, {0, 0, 0}, (float)(f->cam.znear * 0.5)};
    unsigned char vis;
    sb_reference_visibility(g->ref, g->sun, &q, 1, &vis, 1);
    return vis == 0;
}

static void volumes_frame(void *state, sb_frame *f) {
    volumes_state *s = state;
    sb_gpu *g = f->gpu;
    const sb_scene *sc = g->scene;

    sb_stage_begin(f, SB_STAGE_ZPASS);
    sb_zpass(f);
    sb_stage_end(f, SB_STAGE_ZPASS);

    sb_stage_begin(f, SB_STAGE_VOLUMES);
    bool zfail = s->mode == MODE_ZFAIL || (s->mode == MODE_AUTO && camera_in_shadow(f));
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
    glUseProgram(s->prog);
    sb_set_camera_uniforms(f, s->u_view, s->u_proj);
    glBindVertexArray(s->vao);
    for (uint32_t d = 0; d < sc->draw_count; d++) {
        /* z-pass needs the sides only; z-fail closes the volume with the light cap */
        uint32_t first = s->side_first[d], count = s->side_count[d] + (zfail ? s->cap_count[d] : 0);
        if (!count) continue;
        glDrawArrays(GL_TRIANGLES, (GLint)first, (GLsizei)count);
        sb_count_draw(f, count / 3, 1);
    }
    glDisable(GL_DEPTH_CLAMP);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    f->counters.cascades_rendered = 0;
    sb_stage_end(f, SB_STAGE_VOLUMES);

    sb_stage_begin(f, SB_STAGE_FINAL);
    sb_final_pass_stencil(f, &s->fp, s->u_lit, 0xff);
    sb_stage_end(f, SB_STAGE_FINAL);
}

static void volumes_destroy(void *state, sb_gpu *g) {
    (void)g;
    volumes_state *s = state;
    sb_final_prog_free(&s->fp);
    if (s->prog) glDeleteProgram(s->prog);
    if (s->vbo) glDeleteBuffers(1, &s->vbo);
    if (s->vao) glDeleteVertexArrays(1, &s->vao);
    free(s->side_first);
    free(s->side_count);
    free(s->cap_first);
    free(s->cap_count);
}

const sb_technique sb_technique_volumes = {
    .name = "volumes",
    .summary = "stencil shadow volumes from CPU silhouettes (Crow 1977; z-pass, z-fail, auto)",
    .params = volumes_params,
    .param_count = (int)SB_COUNT(volumes_params),
    .stages = SB_STAGE_BIT(SB_STAGE_ZPASS) | SB_STAGE_BIT(SB_STAGE_VOLUMES) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_SUN | SB_NEEDS_CLOSED,
    .state_size = sizeof(volumes_state),
    .create = volumes_create,
    .frame = volumes_frame,
    .destroy = volumes_destroy,
};
