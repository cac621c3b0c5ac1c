/* lamp.c - the point-light techniques' shared machinery (lamp.h). */
#include "lamp.h"

#include "shaders.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const sb_stage_def sb_stage_clusters = {
    .name = "clusters",
    .doc = "lamps found by cluster: the light grid (each screen tile and depth slice's lamps) built on the CPU and "
           "sent (atlas grid=on)"};

const sb_counter_def sb_lamp_counters[1] = {SB_GRID_ITEMS_COUNTER};

/* grid=on with more than one light: the lamps' maps in one texture, their pass through the light grid */
static bool one_pass(const sb_lamp_desc *d, int count) { return d->grid && count > 1; }

static GLenum array_target(const sb_lamp_kind *k) {
    return k->target == GL_TEXTURE_CUBE_MAP ? GL_TEXTURE_CUBE_MAP_ARRAY : GL_TEXTURE_2D_ARRAY;
}

double sb_lamp_technique_shadow_bytes(const sb_technique *t, const void *desc) {
    const sb_lamp_kind *k = t->impl;
    const sb_lamp_desc *d = desc;
    return (double)d->res * d->res * k->maps * 4;   /* 32F layers */
}

bool sb_lamp_technique_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    const sb_lamp_kind *k = rc->tech->impl;
    const sb_lamp_desc *d = desc;
    const char *name = rc->tech->name;
    if (!rc->lights && !sb_lamp_supported(rc->gpu, d->light, name, why)) return false;   /* --lights: read at load */
    if (k->layered && !sb_layered_supported(rc->gpu->ctx, d->layered, name, why)) return false;
    int count = rc->lights ? rc->lights->count : 1;   /* a map set a light */
    if (!sb_lamp_maps_fit(rc->gpu, name, d->res, count * sb_lamp_technique_shadow_bytes(rc->tech, desc),
                          k->target == GL_TEXTURE_CUBE_MAP, why))
        return false;
    int fit = 0;
    if (one_pass(d, count) && !sb_gl_allocates(GL_DEPTH_COMPONENT32F, d->res, d->res, count * k->maps, &fit))
        return sb_fail(why, "%s:res=%d:grid=on: the %d lamps' %d maps in one texture exceed what %s allocates (%d "
                       "layers); grid=off keeps a texture a lamp", name, d->res, count, count * k->maps,
                       rc->gpu->ctx->renderer, fit);
    return true;
}

/* Its maps: a texture of its own, or a view of its layers of the lamps' one texture (array). */
static bool make_targets(sb_lamp_state *s, GLuint array, const char *name, sb_err *err) {
    const sb_lamp_kind *k = s->kind;
    if (array) {
        glGenTextures(1, &s->tex);
        glTextureView(s->tex, k->target, array, GL_DEPTH_COMPONENT32F, 0, 1, (GLuint)(s->index * k->maps),
                      (GLuint)k->maps);
        glBindTexture(k->target, s->tex);
        sb_shadow_texture_params(k->target, s->d->filter != 0);
    } else {
        s->tex = sb_shadow_texture(k->target, GL_DEPTH_COMPONENT32F, s->d->res, s->d->res, k->maps, s->d->filter != 0);
    }
    glGenFramebuffers(1, &s->fbo_all);
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo_all);
    glFramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, s->tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return sb_fail(err, "%s:res=%d: layered framebuffer is incomplete", name, s->d->res);
    glGenFramebuffers(k->maps, s->fbo);
    for (int i = 0; i < k->maps; i++) {
        glBindFramebuffer(GL_FRAMEBUFFER, s->fbo[i]);
        if (k->target == GL_TEXTURE_CUBE_MAP)
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_CUBE_MAP_POSITIVE_X + i, s->tex, 0);
        else
            glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, s->tex, 0, i);
        glDrawBuffer(GL_NONE);
        glReadBuffer(GL_NONE);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return sb_fail(err, "%s:res=%d: framebuffer of map %d is incomplete", name, s->d->res, i);
    }
    return true;
}

void sb_lamp_cube_faces(sb_v3 pos, double near, double far, sb_m4 vp[6]) {
    static const double dir[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    static const double up[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
    sb_m4 proj = sb_m4_perspective(SB_PI / 2, 1, near, far);
    for (int f = 0; f < 6; f++) {
        sb_v3 d = sb_v3_make(dir[f][0], dir[f][1], dir[f][2]), u = sb_v3_make(up[f][0], up[f][1], up[f][2]);
        vp[f] = sb_m4_mul(proj, sb_m4_look_at(pos, sb_v3_add(pos, d), u));
    }
}

void sb_lamp_clip(const sb_light *src, const sb_scene *s, double near_share, double *near, double *far) {
    double diag = sb_v3_len(sb_v3_sub(s->bounds.hi, s->bounds.lo));
    *far = src->range > 0 ? src->range : 2 * diag;
    *near = fmax(*far * near_share, near_share * 1e-2);
}

const float sb_lamp_paraboloid_frame[9] = {1, 0, 0, 0, 0, -1, 0, 1, 0};

void sb_lamp_paraboloid_uniforms(const GLint u[5], sb_v3 lamp, double near, double far, float side) {
    glUniform3f(u[0], (float)lamp.x, (float)lamp.y, (float)lamp.z);
    glUniformMatrix3fv(u[1], 1, GL_FALSE, sb_lamp_paraboloid_frame);
    glUniform1f(u[2], side);
    glUniform1f(u[3], (float)near);
    glUniform1f(u[4], (float)far);
}

sb_lamp_state *sb_lamp_light(sb_lamp_state *s, int i) {
    return i ? (sb_lamp_state *)(s->others + (size_t)(i - 1) * s->size) : s;
}

/* Light i's lamp, clip range and maps (the kind's per-lamp setup too). */
static bool place(sb_lamp_state *l, const sb_run_ctx *rc, int which, GLuint array, sb_err *err) {
    const sb_gpu *g = rc->gpu;
    const sb_light *lamp = sb_scene_point_light(g->scene, which, NULL);
    l->source = lamp;
    l->lamp = lamp->position;
    sb_lamp_clip(lamp, g->scene, l->kind->near_share, &l->near, &l->far);
    if (l->kind->setup) l->kind->setup(l);
    return make_targets(l, array, rc->tech->name, err);
}

/* grid=on: the lamps' records (vis_lamps.glsl), the grid's input and the pass that reads them. */
static bool make_loop(sb_lamp_state *s, const sb_run_ctx *rc, sb_err *err) {
    const sb_gpu *g = rc->gpu;
    enum { REC = 3 };
    float *rec = sb_xcalloc((size_t)s->count * REC * 4, sizeof(float));
    s->grid_pos = sb_xmalloc(sizeof *s->grid_pos * (size_t)s->count);
    s->grid_range = sb_xmalloc(sizeof *s->grid_range * (size_t)s->count);
    for (int i = 0; i < s->count; i++) {
        const sb_lamp_state *l = sb_lamp_light(s, i);
        const sb_light *src = l->source;
        double range = src->range > 0 ? src->range : 0;
        float *r = rec + (size_t)i * REC * 4;
        r[0] = (float)l->lamp.x, r[1] = (float)l->lamp.y, r[2] = (float)l->lamp.z, r[3] = (float)range;
        r[4] = (float)l->near, r[5] = (float)l->far, r[6] = (float)s->d->res;
        if (src->type == SB_LIGHT_SPOT && src->cone > 0)
            r[8] = (float)src->direction.x, r[9] = (float)src->direction.y, r[10] = (float)src->direction.z,
            r[11] = (float)(1 - cos(src->cone));
        s->grid_pos[i] = l->lamp, s->grid_range[i] = range;
    }
    glGenBuffers(1, &s->rec_buf);
    glBindBuffer(GL_TEXTURE_BUFFER, s->rec_buf);
    glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)((size_t)s->count * REC * 16), rec, GL_STATIC_DRAW);
    glGenTextures(1, &s->rec_tex);
    glBindTexture(GL_TEXTURE_BUFFER, s->rec_tex);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, s->rec_buf);
    free(rec);
    s->grid = sb_xcalloc(1, sizeof *s->grid);
    sb_lightgrid_init(s->grid, g->width, g->height);
    char defines[96];
    snprintf(defines, sizeof defines, "#define SB_LIGHT_LOOP\n#define SB_LIGHT_GRID\n#define SB_FILTER %d\n", s->d->filter);
    const char *parts[] = {sb_shader_lightgrid_glsl, sb_shader_vis_lamps_glsl, s->kind->vis_glsl};
    char label[64];
    snprintf(label, sizeof label, "%s (every lamp)", rc->tech->name);
    if (!sb_final_prog_create_parts(&s->loop_fp, g, label, parts, 3, defines, err)) return false;
    const char *names[] = {"u_map", "u_lights", "u_bias", "u_normal"};
    for (int i = 0; i < 4; i++) s->u_loop[i] = glGetUniformLocation(s->loop_fp.prog, names[i]);
    for (int i = 0; i < 4; i++)
        s->u_loop_lookup[i] =
            s->kind->lookup_uniforms[i] ? glGetUniformLocation(s->loop_fp.prog, s->kind->lookup_uniforms[i]) : -1;
    sb_lightgrid_locate(s->grid, s->loop_fp.prog);
    return true;
}

bool sb_lamp_technique_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    sb_lamp_state *s = state;
    const sb_gpu *g = rc->gpu;
    const char *name = rc->tech->name;
    s->kind = rc->tech->impl;
    s->d = desc;
    s->layered = s->kind->layered ? sb_layered_resolve(g->ctx, s->d->layered) : 0;
    s->count = rc->lights ? rc->lights->count : 1;
    s->size = rc->tech->state_size;
    if (s->count > 1) s->others = sb_xcalloc((size_t)s->count - 1, s->size);
    if (one_pass(s->d, s->count))
        s->array = sb_shadow_texture(array_target(s->kind), GL_DEPTH_COMPONENT32F, s->d->res, s->d->res,
                                     s->count * s->kind->maps, s->d->filter != 0);
    for (int i = 0; i < s->count; i++) {
        sb_lamp_state *l = sb_lamp_light(s, i);
        l->kind = s->kind;
        l->d = s->d;
        l->layered = s->layered;
        l->index = i;
        if (!place(l, rc, rc->lights ? rc->lights->idx[i] : s->d->light, s->array, err)) return false;
    }
    if (s->array && !make_loop(s, rc, err)) return false;
    for (int a = 0; a < (g->scene->alpha_tested_draws ? 2 : 1); a++)
        if (!s->kind->program(s, a, a ? NULL : sb_opaque_define(g), err)) return false;
    char defines[64];
    snprintf(defines, sizeof defines, "#define SB_FILTER %d\n", s->d->filter);
    if (!sb_final_prog_create(&s->fp, g, name, s->kind->vis_glsl, defines, err)) return false;
    const char *names[] = {"u_map", "u_lamp", "u_near", "u_far", "u_res", "u_bias", "u_normal"};
    GLint *locs[] = {&s->u_map, &s->u_lamp, &s->u_near, &s->u_far, &s->u_res, &s->u_bias, &s->u_normal};
    for (size_t i = 0; i < SB_COUNT(names); i++) *locs[i] = glGetUniformLocation(s->fp.prog, names[i]);
    for (int i = 0; i < 4; i++)
        s->u_lookup[i] = s->kind->lookup_uniforms[i] ? glGetUniformLocation(s->fp.prog, s->kind->lookup_uniforms[i]) : -1;
    for (int i = 1; i < s->count; i++) {   /* the programs, shared: only the first light's state frees them */
        sb_lamp_state *l = sb_lamp_light(s, i);
        memcpy(l->pass, s->pass, sizeof s->pass);
        l->fp = s->fp;
        l->u_map = s->u_map, l->u_lamp = s->u_lamp, l->u_near = s->u_near, l->u_far = s->u_far;
        l->u_res = s->u_res, l->u_bias = s->u_bias, l->u_normal = s->u_normal;
        memcpy(l->u_lookup, s->u_lookup, sizeof s->u_lookup);
    }
    return sb_gl_check(name, err);
}

uint32_t sb_lamp_casters(const sb_lamp_state *s, sb_frame *f) {
    double box[6][4];
    sb_cube_planes(s->lamp, s->far, box);
    return sb_scene_collect(f->gpu->scene, (const double(*)[4])box, 6, f->scratch);
}

void sb_lamp_draw(sb_lamp_state *s, sb_frame *f, uint32_t n, int instances,
                  void (*set)(const sb_lamp_state *s, int a, const void *arg), const void *arg) {
    for (int a = 0; a < 2 && s->pass[a].prog; a++) {
        glUseProgram(s->pass[a].prog);
        set(s, a, arg);
        for (uint32_t i = 0; i < n; i++)
            if (sb_draw_variant(f->gpu, f->scratch[i]) == a) sb_submit(f, f->scratch[i], instances);
        sb_submit_flush(f);
    }
}

/* One light's maps, inside the shadow stage; returns how many it rendered. */
static int render_maps(sb_lamp_state *l, sb_frame *f) {
    /* the lamp first: its draws keep the triangles facing it */
    sb_frame_shade_point(f, l->lamp);
    glBindFramebuffer(GL_FRAMEBUFFER, l->fbo_all);
    glViewport(0, 0, l->d->res, l->d->res);
    glClear(GL_DEPTH_BUFFER_BIT);   /* every layer */
    return l->kind->render(l, f);
}

/* One light's camera pass: the first clears and lays the ambient, each further one adds its light. */
static void shade(sb_lamp_state *l, sb_frame *f, bool first) {
    sb_frame_shade_lamp(f, l->source);
    glUseProgram(l->fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(l->kind->target, l->tex);
    glUniform1i(l->u_map, 0);
    glUniform3f(l->u_lamp, (float)l->lamp.x, (float)l->lamp.y, (float)l->lamp.z);
    glUniform1f(l->u_near, (float)l->near);
    glUniform1f(l->u_far, (float)l->far);
    glUniform1f(l->u_res, (float)l->d->res);
    glUniform1f(l->u_bias, (float)l->d->bias);
    glUniform1f(l->u_normal, (float)l->d->normal);
    if (l->kind->lookup) l->kind->lookup(l->u_lookup);
    if (first) {
        sb_final_pass(f, &l->fp, false);
        return;
    }
    /* a further lamp adds nothing beyond its range: a timed frame's pass is cut to the pixels its footprint
       covers (lightgrid.h) and its draws to the box of its range, so a pixel pays for the lamps that reach it (an
       evaluation pass writes its targets whole) */
    sb_lamp_footprint fp = {0};
    double range = l->source ? l->source->range : 0;
    bool cut = !f->eval && range > 0;
    if (cut && !sb_lamp_footprint_of(f, l->lamp, range, &fp)) return;   /* out of view: nothing to add */
    if (cut) {
        glEnable(GL_SCISSOR_TEST);
        glScissor(fp.x0, fp.y0, fp.x1 - fp.x0, fp.y1 - fp.y0);
        sb_cube_planes(l->lamp, range, f->pass_box);
        f->pass_box_count = 6;
    }
    sb_final_pass_add(f, &l->fp);
    if (cut) {
        glDisable(GL_SCISSOR_TEST);
        f->pass_box_count = 0;
    }
}

/* grid=on: every lamp's light in one camera pass, each pixel looping over its cluster's lamps. */
static void shade_all(sb_lamp_state *s, sb_frame *f) {
    glUseProgram(s->loop_fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(array_target(s->kind), s->array);
    glUniform1i(s->u_loop[0], 0);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_BUFFER, s->rec_tex);
    glUniform1i(s->u_loop[1], 1);
    glActiveTexture(GL_TEXTURE0);
    sb_lightgrid_bind(s->grid, 2);
    glUniform1f(s->u_loop[2], (float)s->d->bias);
    glUniform1f(s->u_loop[3], (float)s->d->normal);
    if (s->kind->lookup) s->kind->lookup(s->u_loop_lookup);
    sb_final_pass(f, &s->loop_fp, false);
}

void sb_lamp_technique_frame(void *state, sb_frame *f) {
    sb_lamp_state *s = state;
    const sb_lamp_kind *k = s->kind;
    /* every light, or the one an evaluation pass scores */
    int first, end;
    sb_frame_light_range(f, s->count, &first, &end);
    sb_stage_begin(f, &sb_stage_cascade);
    sb_shadow_depth_state((float)s->d->slope);
    glDisable(GL_CULL_FACE);
    glBindVertexArray(f->gpu->vao);
    int rendered = 0;
    for (int i = first; i < end; i++) rendered += render_maps(sb_lamp_light(s, i), f);
    glDisable(GL_POLYGON_OFFSET_FILL);
    f->counters.cascades_rendered = rendered;
    f->counters.cascades_skipped = k->maps * (end - first) - rendered;
    sb_stage_end(f, &sb_stage_cascade);

    /* grid=on, a timed frame: every lamp in one pass through the grid (an evaluation pass adds the lamps one by
       one, uncut: the per-light way the test holds this one's image to) */
    if (s->array && !f->eval) {
        sb_stage_begin(f, &sb_stage_clusters);
        uint32_t items = sb_lightgrid_build(s->grid, f, s->grid_pos, s->grid_range, s->count);
        sb_count(&f->counters, &sb_lamp_counters[0], items);
        sb_stage_end(f, &sb_stage_clusters);
        sb_stage_begin(f, &sb_stage_final);
        shade_all(s, f);
        sb_stage_end(f, &sb_stage_final);
        return;
    }
    sb_stage_begin(f, &sb_stage_final);
    for (int i = first; i < end; i++) shade(sb_lamp_light(s, i), f, i == first);
    sb_stage_end(f, &sb_stage_final);
}

static void free_maps(sb_lamp_state *l) {
    if (l->fbo_all) glDeleteFramebuffers(1, &l->fbo_all);
    if (l->fbo[0] && l->kind) glDeleteFramebuffers(l->kind->maps, l->fbo);
    if (l->tex) glDeleteTextures(1, &l->tex);
}

void sb_lamp_technique_destroy(void *state) {
    sb_lamp_state *s = state;
    for (int i = 1; s->others && i < s->count; i++) free_maps(sb_lamp_light(s, i));
    free(s->others);
    sb_final_prog_free(&s->fp);
    sb_final_prog_free(&s->loop_fp);
    if (s->grid) sb_lightgrid_free(s->grid);
    free(s->grid);
    free(s->grid_pos);
    free(s->grid_range);
    if (s->rec_tex) glDeleteTextures(1, &s->rec_tex);
    if (s->rec_buf) glDeleteBuffers(1, &s->rec_buf);
    for (int a = 0; a < 2; a++)
        if (s->pass[a].prog) glDeleteProgram(s->pass[a].prog);
    free_maps(s);
    if (s->array) glDeleteTextures(1, &s->array);
}
