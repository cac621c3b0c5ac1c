/* lamp.c - the point-light techniques' shared machinery (lamp.h). */
#include "lamp.h"

#include <string.h>

double sb_lamp_technique_shadow_bytes(const sb_technique *t, const void *desc) {
    const sb_lamp_kind *k = t->impl;
    const sb_lamp_desc *d = desc;
    return (double)d->res * d->res * k->maps * 4;   /* 32F layers */
}

bool sb_lamp_technique_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    const sb_lamp_kind *k = rc->tech->impl;
    const sb_lamp_desc *d = desc;
    const char *name = rc->tech->name;
    if (!sb_lamp_supported(rc->gpu, d->light, name, why)) return false;
    if (k->layered && !sb_layered_supported(rc->gpu->ctx, d->layered, name, why)) return false;
    return sb_lamp_maps_fit(rc->gpu, name, d->res, sb_lamp_technique_shadow_bytes(rc->tech, desc),
                            k->target == GL_TEXTURE_CUBE_MAP, why);
}

static bool make_targets(sb_lamp_state *s, const char *name, sb_err *err) {
    const sb_lamp_kind *k = s->kind;
    s->tex = sb_shadow_texture(k->target, GL_DEPTH_COMPONENT32F, s->d->res, s->d->res, k->maps, s->d->filter != 0);
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

bool sb_lamp_technique_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    sb_lamp_state *s = state;
    const sb_gpu *g = rc->gpu;
    const char *name = rc->tech->name;
    s->kind = rc->tech->impl;
    s->d = desc;
    s->layered = s->kind->layered ? sb_layered_resolve(g->ctx, s->d->layered) : 0;
    const sb_light *lamp = sb_scene_point_light(g->scene, s->d->light, NULL);
    s->lamp = lamp->position;
    double diag = sb_v3_len(sb_v3_sub(g->scene->bounds.hi, g->scene->bounds.lo));
    s->far = lamp->range > 0 ? lamp->range : 2 * diag;
    s->near = fmax(s->far * s->kind->near_share, s->kind->near_share * 1e-2);
    if (s->kind->setup) s->kind->setup(s);
    if (!make_targets(s, name, err)) return false;
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

void sb_lamp_technique_frame(void *state, sb_frame *f) {
    sb_lamp_state *s = state;
    const sb_lamp_kind *k = s->kind;
    /* the lamp, before the shadow stage: its draws keep the triangles facing it */
    sb_frame_shade_point(f, s->lamp);
    sb_stage_begin(f, SB_STAGE_CASCADE);
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo_all);
    glViewport(0, 0, s->d->res, s->d->res);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);   /* every layer */
    glDisable(GL_CULL_FACE);
    if (s->d->slope != 0) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset((float)s->d->slope, 0.0f);
    }
    glBindVertexArray(f->gpu->vao);
    int rendered = k->render(s, f);
    glDisable(GL_POLYGON_OFFSET_FILL);
    f->counters.cascades_rendered = rendered;
    f->counters.cascades_skipped = k->maps - rendered;
    sb_stage_end(f, SB_STAGE_CASCADE);

    sb_stage_begin(f, SB_STAGE_FINAL);
    glUseProgram(s->fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(k->target, s->tex);
    glUniform1i(s->u_map, 0);
    glUniform3f(s->u_lamp, (float)s->lamp.x, (float)s->lamp.y, (float)s->lamp.z);
    glUniform1f(s->u_near, (float)s->near);
    glUniform1f(s->u_far, (float)s->far);
    glUniform1f(s->u_res, (float)s->d->res);
    glUniform1f(s->u_bias, (float)s->d->bias);
    glUniform1f(s->u_normal, (float)s->d->normal);
    if (k->lookup) k->lookup(s);
    sb_final_pass(f, &s->fp, false);
    sb_stage_end(f, SB_STAGE_FINAL);
}

void sb_lamp_technique_destroy(void *state) {
    sb_lamp_state *s = state;
    sb_final_prog_free(&s->fp);
    for (int a = 0; a < 2; a++)
        if (s->pass[a].prog) glDeleteProgram(s->pass[a].prog);
    if (s->fbo_all) glDeleteFramebuffers(1, &s->fbo_all);
    if (s->fbo[0] && s->kind) glDeleteFramebuffers(s->kind->maps, s->fbo);
    if (s->tex) glDeleteTextures(1, &s->tex);
}
