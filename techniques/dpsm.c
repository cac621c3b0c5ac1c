/* dpsm.c - dual-paraboloid shadow maps (Brabec, Annen & Seidel 2002) for a
 * point light: two maps, each a hemisphere projected onto a paraboloid in the
 * vertex shader (one pass per hemisphere, clipped at its rim), storing the
 * linear distance to the lamp. Cheaper than a cube (two passes, not six);
 * large triangles that span much of a hemisphere bend, since the paraboloid
 * projection is not linear: the error metric shows what that costs. The
 * front hemisphere looks down (-Y). */
#include <string.h>

#include "render.h"
#include "shaders.h"

typedef struct dpsm_desc {
    int res, light, filter;
    double bias, slope, normal;
} dpsm_desc;

static const sb_param_def dpsm_params[] = {
    SB_PARAM_I(dpsm_desc, res, 1024, 64, 8192, "resolution of each paraboloid map"),
    SB_PARAM_I(dpsm_desc, light, 0, 0, 15, "which point or spot light of the scene (in file order)"),
    SB_PARAM_FA(dpsm_desc, bias, 1.5, 0, 100, "constant bias, in texels at the point's distance"),
    SB_PARAM_FA(dpsm_desc, slope, 2, 0, 100, "slope-scaled bias (glPolygonOffset factor)"),
    SB_PARAM_FA(dpsm_desc, normal, 1, 0, 100, "normal offset, in texels"),
    SB_PARAM_E(dpsm_desc, filter, hw, "none|hw", "shadow filter"),
};

typedef struct {
    const dpsm_desc *d;         /* the instance's parameters */
    double near, far;
    sb_v3 lamp;
    float frame[9];
    GLuint tex, fbo[2];
    struct {   /* the depth pass: [0] without the alpha test (opaque draws), [1] with it (sb_draw_variant) */
        GLuint prog;
        GLint lamp, frame, side, near, far;
    } pass[2];
    sb_final_prog fp;
    GLint u_maps, u_lamp, u_frame, u_near, u_far, u_res, u_bias, u_normal;
} dpsm_state;

static bool dpsm_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    const dpsm_desc *d = desc;
    if (!sb_lamp_supported(rc->gpu, d->light, "dpsm", why)) return false;
    return sb_lamp_maps_fit(rc->gpu, "dpsm", d->res, 2, false, why);   /* two 32F paraboloid maps */
}

static bool dpsm_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    dpsm_state *s = state;
    const dpsm_desc *d = desc;
    const sb_gpu *g = rc->gpu;
    s->d = d;
    const sb_light *lamp = sb_scene_point_light(g->scene, d->light, NULL);
    s->lamp = lamp->position;
    double diag = sb_v3_len(sb_v3_sub(g->scene->bounds.hi, g->scene->bounds.lo));
    s->far = lamp->range > 0 ? lamp->range : 2 * diag;
    s->near = fmax(s->far * 1e-5, 1e-7);
    /* lamp frame: x = +X, y = +Z, z = -Y (the front hemisphere looks down); rows of a world -> frame matrix */
    const float fr[9] = {1, 0, 0, 0, 0, -1, 0, 1, 0}; /* column-major mat3: columns are the images of x, y, z */
    memcpy(s->frame, fr, sizeof fr);
    s->tex = sb_shadow_texture(GL_TEXTURE_2D_ARRAY, GL_DEPTH_COMPONENT32F, s->d->res, 2, s->d->filter != 0);
    glGenFramebuffers(2, s->fbo);
    for (int i = 0; i < 2; i++) {
        glBindFramebuffer(GL_FRAMEBUFFER, s->fbo[i]);
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, s->tex, 0, i);
        glDrawBuffer(GL_NONE);
        glReadBuffer(GL_NONE);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return sb_fail(err, "dpsm:res=%d: framebuffer is incomplete", s->d->res);
    }
    const char *vs[] = {sb_shader_dpsm_vert}, *fs[] = {sb_shader_depth_frag};
    for (int a = 0; a < (g->scene->alpha_tested_draws ? 2 : 1); a++) {
        const char *label = a ? "dpsm paraboloid (alpha-tested draws)" : "dpsm paraboloid";
        GLuint p = sb_gpu_program(label, a ? NULL : sb_opaque_define(g), vs, 1, fs, 1, err);
        if (!(s->pass[a].prog = p)) return false;
        s->pass[a].lamp = glGetUniformLocation(p, "u_lamp");
        s->pass[a].frame = glGetUniformLocation(p, "u_frame");
        s->pass[a].side = glGetUniformLocation(p, "u_side");
        s->pass[a].near = glGetUniformLocation(p, "u_near");
        s->pass[a].far = glGetUniformLocation(p, "u_far");
    }
    if (!sb_final_prog_create(&s->fp, rc->gpu, "dpsm", sb_shader_vis_dpsm_glsl, NULL, err)) return false;
    const char *names[] = {"u_maps", "u_lamp", "u_frame", "u_near", "u_far", "u_res", "u_bias", "u_normal"};
    GLint *locs[] = {&s->u_maps, &s->u_lamp, &s->u_frame, &s->u_near, &s->u_far, &s->u_res, &s->u_bias, &s->u_normal};
    for (size_t i = 0; i < SB_COUNT(names); i++) *locs[i] = glGetUniformLocation(s->fp.prog, names[i]);
    return sb_gl_check("dpsm", err);
}

static void dpsm_frame(void *state, sb_frame *f) {
    dpsm_state *s = state;
    const sb_gpu *g = f->gpu;
    const sb_scene *sc = g->scene;
    /* the lamp, before the shadow stage: its draws keep the triangles facing it */
    sb_frame_shade_point(f, s->lamp);
    sb_stage_begin(f, SB_STAGE_CASCADE);
    double box[6][4];
    sb_cube_planes(s->lamp, s->far, box);
    uint32_t n = sb_scene_collect(sc, (const double(*)[4])box, 6, f->scratch);
    glViewport(0, 0, s->d->res, s->d->res);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_CLIP_DISTANCE0);
    if (s->d->slope != 0) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset((float)s->d->slope, 0.0f);
    }
    glBindVertexArray(g->vao);
    for (int side = 0; side < 2; side++) {
        glBindFramebuffer(GL_FRAMEBUFFER, s->fbo[side]);
        glClear(GL_DEPTH_BUFFER_BIT);
        /* opaque casters first, without the alpha test; then the alpha-tested ones */
        for (int a = 0; a < 2 && s->pass[a].prog; a++) {
            glUseProgram(s->pass[a].prog);
            glUniform3f(s->pass[a].lamp, (float)s->lamp.x, (float)s->lamp.y, (float)s->lamp.z);
            glUniformMatrix3fv(s->pass[a].frame, 1, GL_FALSE, s->frame);
            glUniform1f(s->pass[a].near, (float)s->near);
            glUniform1f(s->pass[a].far, (float)s->far);
            glUniform1f(s->pass[a].side, side ? -1.0f : 1.0f);
            for (uint32_t i = 0; i < n; i++)
                if (sb_draw_variant(g, f->scratch[i]) == a) sb_submit(f, f->scratch[i], 1);
        }
    }
    glDisable(GL_CLIP_DISTANCE0);
    glDisable(GL_POLYGON_OFFSET_FILL);
    f->counters.cascades_rendered = n ? 2 : 0;
    f->counters.cascades_skipped = n ? 0 : 2;
    sb_stage_end(f, SB_STAGE_CASCADE);

    sb_stage_begin(f, SB_STAGE_FINAL);
    glUseProgram(s->fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, s->tex);
    glUniform1i(s->u_maps, 0);
    glUniform3f(s->u_lamp, (float)s->lamp.x, (float)s->lamp.y, (float)s->lamp.z);
    glUniformMatrix3fv(s->u_frame, 1, GL_FALSE, s->frame);
    glUniform1f(s->u_near, (float)s->near);
    glUniform1f(s->u_far, (float)s->far);
    glUniform1f(s->u_res, (float)s->d->res);
    glUniform1f(s->u_bias, (float)s->d->bias);
    glUniform1f(s->u_normal, (float)s->d->normal);
    sb_final_pass(f, &s->fp, false);
    sb_stage_end(f, SB_STAGE_FINAL);
}

static void dpsm_destroy(void *state) {
    dpsm_state *s = state;
    sb_final_prog_free(&s->fp);
    for (int a = 0; a < 2; a++)
        if (s->pass[a].prog) glDeleteProgram(s->pass[a].prog);
    if (s->fbo[0]) glDeleteFramebuffers(2, s->fbo);
    if (s->tex) glDeleteTextures(1, &s->tex);
}

const sb_technique sb_technique_dpsm = {
    .name = "dpsm",
    .summary = "point-light shadows with dual-paraboloid maps (Brabec et al. 2002)",
    .params = dpsm_params,
    .param_count = (int)SB_COUNT(dpsm_params),
    .desc_size = sizeof(dpsm_desc),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_POINT_LIGHT,
    .state_size = sizeof(dpsm_state),
    .supported = dpsm_supported,
    .create = dpsm_create,
    .frame = dpsm_frame,
    .destroy = dpsm_destroy,
};
