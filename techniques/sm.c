/* sm.c - one shadow map (Williams 1978) fitted to the camera frustum's
 * light-space bounds, extended toward the light so that off-screen casters
 * still shadow. Bias: constant, slope-scaled, normal offset. Filters: none,
 * hw (2x2 bilinear compare), pcf3, pcf5, poisson16. */
#include <string.h>

#include "lightfit.h"
#include "shaders.h"

static const sb_param_def sm_params[] = {
    {"res", SB_PARAM_INT, "2048", 64, 16384, NULL, "shadow map resolution (texels per side)"},
    {"bias", SB_PARAM_FLOAT, "1", 0, 100, NULL, "constant depth bias, in shadow texels of world size"},
    {"slope", SB_PARAM_FLOAT, "2", 0, 100, NULL, "slope-scaled bias (glPolygonOffset factor)"},
    {"normal", SB_PARAM_FLOAT, "1", 0, 100, NULL, "normal offset, in shadow texels"},
    {"filter", SB_PARAM_ENUM, "hw", 0, 0, "none|hw|pcf3|pcf5|poisson16", "shadow filter"},
};

typedef struct {
    int res, filter;
    double bias, slope, normal;
    GLuint tex, fbo;
    sb_final_prog fp;
    GLint u_shadow, u_shadow_mat, u_bias, u_normal, u_light, u_texel;
    sb_light_fit fit;
} sm_state;

static bool sm_create(void *state, sb_gpu *gpu, const sb_params *p, sb_err *err) {
    (void)gpu;
    sm_state *s = state;
    s->res = (int)sb_param_num(p, "res");
    s->bias = sb_param_num(p, "bias");
    s->slope = sb_param_num(p, "slope");
    s->normal = sb_param_num(p, "normal");
    s->filter = sb_param_choice(p, "filter");
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (s->res > max_size) return sb_fail(err, "sm:res=%d exceeds GL_MAX_TEXTURE_SIZE %d", s->res, max_size);
    glGenTextures(1, &s->tex);
    glBindTexture(GL_TEXTURE_2D, s->tex);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_DEPTH_COMPONENT32F, s->res, s->res);
    GLint f = s->filter == 0 || s->filter == 2 || s->filter == 3 ? GL_NEAREST : GL_LINEAR;
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, f);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, f);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
    const float border[4] = {1, 1, 1, 1};
    glTexParameterfv(GL_TEXTURE_2D, GL_TEXTURE_BORDER_COLOR, border);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &s->fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, s->tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return sb_fail(err, "sm:res=%d: shadow map framebuffer is incomplete", s->res);
    char defines[64];
    snprintf(defines, sizeof defines, "#define SB_FILTER %d\n", s->filter);
    if (!sb_final_prog_create(&s->fp, "sm", sb_shader_vis_sm_glsl, defines, err)) return false;
    s->u_shadow = glGetUniformLocation(s->fp.prog, "u_shadow");
    s->u_shadow_mat = glGetUniformLocation(s->fp.prog, "u_shadow_mat");
    s->u_bias = glGetUniformLocation(s->fp.prog, "u_bias");
    s->u_normal = glGetUniformLocation(s->fp.prog, "u_normal_offset");
    s->u_light = glGetUniformLocation(s->fp.prog, "u_light");
    s->u_texel = glGetUniformLocation(s->fp.prog, "u_texel");
    return sb_gl_check("sm: creating the shadow map", err);
}

static void sm_frame(void *state, sb_frame *f) {
    sm_state *s = state;
    sb_gpu *g = f->gpu;
    sb_v3 corners[8];
    sb_frustum_corners(&f->cam, g->scene->origin, f->cam.znear, f->cam.zfar, corners);
    sb_light_fit_points(g->scene, g->sun, corners, 8, s->res, &s->fit);

    sb_stage_begin(f, SB_STAGE_CASCADE);
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo);
    glViewport(0, 0, s->res, s->res);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_CLAMP);
    if (s->slope > 0) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset((float)(s->slope * g->test_bias_sign), 0.0f);
    }
    float vp[16];
    sb_m4_to_float(s->fit.view_proj, vp);
    sb_draw_casters(f, (const double(*)[4])s->fit.planes, 6, vp);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    f->counters.cascades_rendered = 1;
    sb_stage_end(f, SB_STAGE_CASCADE);

    sb_stage_begin(f, SB_STAGE_FINAL);
    glUseProgram(s->fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, s->tex);
    glUniform1i(s->u_shadow, 0);
    float m[16];
    sb_m4_to_float(s->fit.shadow_mat, m);
    glUniformMatrix4fv(s->u_shadow_mat, 1, GL_FALSE, m);
    double depth_range = s->fit.zf - s->fit.zn;
    glUniform1f(s->u_bias, (float)(g->test_bias_sign * s->bias * s->fit.texel_world / depth_range));
    glUniform1f(s->u_normal, (float)(g->test_bias_sign * s->normal * s->fit.texel_world));
    glUniform3f(s->u_light, (float)g->sun.x, (float)g->sun.y, (float)g->sun.z);
    glUniform2f(s->u_texel, 1.0f / s->res, 1.0f / s->res);
    sb_final_pass(f, &s->fp);
    sb_stage_end(f, SB_STAGE_FINAL);
}

static void sm_destroy(void *state, sb_gpu *gpu) {
    (void)gpu;
    sm_state *s = state;
    sb_final_prog_free(&s->fp);
    if (s->fbo) glDeleteFramebuffers(1, &s->fbo);
    if (s->tex) glDeleteTextures(1, &s->tex);
}

const sb_technique sb_technique_sm = {
    .name = "sm",
    .summary = "one shadow map fitted to the view frustum (Williams 1978)",
    .params = sm_params,
    .param_count = (int)SB_COUNT(sm_params),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(sm_state),
    .create = sm_create,
    .frame = sm_frame,
    .destroy = sm_destroy,
};
