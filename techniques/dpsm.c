/* dpsm.c - dual-paraboloid shadow maps (Brabec, Annen & Seidel 2002) for a
 * point light: two maps, each a hemisphere projected onto a paraboloid in the
 * vertex shader (one pass per hemisphere, clipped at its rim), storing the
 * linear distance to the lamp. Cheaper than a cube (two passes, not six);
 * large triangles that span much of a hemisphere bend, since the paraboloid
 * projection is not linear: the error metric shows what that costs. The
 * front hemisphere looks down (-Y). A lamp technique (lamp.h). */
#include "lamp.h"
#include "shaders.h"

static const sb_param_def dpsm_params[] = {
    SB_LAMP_PARAMS("resolution of each paraboloid map"),
    SB_PARAM_E(sb_lamp_desc, filter, hw, "none|hw", "shadow filter", .tune = "none,hw,pcf3"),
    SB_LAMP_GRID_PARAM,
};

/* The lamp's frame: x = +X, y = +Z, z = -Y (the front hemisphere looks down), as a column-major mat3 whose
 * columns are the images of x, y and z. */

static bool depth_program(sb_lamp_state *s, int a, const char *defines, sb_err *err) {
    const char *vs[] = {sb_shader_dpsm_vert}, *fs[] = {sb_shader_depth_frag};
    const char *label = a ? "dpsm paraboloid (alpha-tested draws)" : "dpsm paraboloid";
    GLuint p = sb_gpu_program(label, defines, vs, 1, fs, 1, err);
    if (!(s->pass[a].prog = p)) return false;
    const char *names[] = {"u_lamp", "u_frame", "u_side", "u_near", "u_far"};
    for (int i = 0; i < (int)SB_COUNT(names); i++) s->pass[a].u[i] = glGetUniformLocation(p, names[i]);
    return true;
}

/* arg: the hemisphere, 1 front or -1 back */
static void set_side(const sb_lamp_state *s, int a, const void *arg) {
    sb_lamp_paraboloid_uniforms(s->pass[a].u, s->lamp, s->near, s->far, *(const float *)arg);
}

static int render(sb_lamp_state *s, sb_frame *f) {
    uint32_t n = sb_lamp_casters(s, f);
    static const float sides[2] = {1.0f, -1.0f};
    glEnable(GL_CLIP_DISTANCE0);   /* each hemisphere clipped at its rim */
    for (int side = 0; side < 2; side++) {
        glBindFramebuffer(GL_FRAMEBUFFER, s->fbo[side]);
        sb_lamp_draw(s, f, n, 1, set_side, &sides[side]);
    }
    glDisable(GL_CLIP_DISTANCE0);
    return n ? 2 : 0;
}

static void lookup(const GLint u[4]) { glUniformMatrix3fv(u[0], 1, GL_FALSE, sb_lamp_paraboloid_frame); }

static const sb_lamp_kind dpsm_kind = {
    .target = GL_TEXTURE_2D_ARRAY, .maps = 2, .near_share = 1e-5, .vis_glsl = sb_shader_vis_dpsm_glsl,
    .program = depth_program, .render = render, .lookup_uniforms = {"u_frame"}, .lookup = lookup,
};

const sb_technique sb_technique_dpsm =
    SB_LAMP_TECHNIQUE("dpsm", "point-light shadows with dual-paraboloid maps (Brabec et al. 2002)", dpsm_params,
                      sb_lamp_state, &dpsm_kind);
