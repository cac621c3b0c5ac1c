/* cube.c - point-light shadows with a depth cube map: six 90-degree
 * perspective faces around the lamp, rendered per face (casters culled per
 * face frustum over the BVH) or in one layered pass (a geometry shader routes
 * each triangle to the faces it touches, or instancing with gl_Layer from the
 * vertex shader), the same `layered=` choice as cascades. The final pass
 * shades and shadows the lamp; evaluation casts the reference rays to it. */
#include <string.h>

#include "render.h"
#include "shaders.h"

typedef struct cube_desc {
    int res, light, filter, layered;
    double bias, slope, normal;
} cube_desc;

static const sb_param_def cube_params[] = {
    SB_PARAM_I(cube_desc, res, 1024, 64, 8192, "cube face resolution"),
    SB_PARAM_I(cube_desc, light, 0, 0, 15, "which point or spot light of the scene (in file order)"),
    SB_PARAM_FA(cube_desc, bias, 1.5, 0, 100, "constant bias, in texels at the point's distance"),
    SB_PARAM_FA(cube_desc, slope, 2, 0, 100, "slope-scaled bias (glPolygonOffset factor)"),
    SB_PARAM_FA(cube_desc, normal, 1, 0, 100, "normal offset, in texels"),
    SB_PARAM_E(cube_desc, filter, hw, "none|hw|pcf", "shadow filter"),
    SB_PARAM_E(cube_desc, layered, off, "off|gs|vs|on", "six passes, or one layered pass"),
};

typedef struct {
    const cube_desc *d;         /* the instance's parameters */
    int layered;                /* resolved (on: the best available) */
    sb_v3 lamp;                 /* origin-relative */
    double near, far;
    GLuint tex, fbo_all, fbo_face[6];
    struct {   /* the depth pass: [0] without the alpha test (opaque draws), [1] with it (sb_draw_variant) */
        GLuint prog;            /* per face, or layered (by `layered`) */
        GLint u_vp;             /* per face: the face's matrix; layered: the six (u_face_vp) */
    } pass[2];
    sb_m4 face_vp[6];
    double planes[6][6][4];
    sb_final_prog fp;
    GLint u_cube, u_lamp, u_near, u_far, u_res, u_bias, u_normal;
} cube_state;

static const double face_dir[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
static const double face_up[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};

static bool cube_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    const cube_desc *d = desc;
    if (!sb_lamp_supported(rc->gpu, d->light, "cube", why)) return false;
    if (!sb_layered_supported(rc->gpu->ctx, d->layered, "cube", why)) return false;
    return sb_lamp_maps_fit(rc->gpu, "cube", d->res, 6, true, why);   /* six 32F faces */
}

/* The six faces' matrices and culling planes around the lamp. */
static void face_frusta(cube_state *s) {
    sb_m4 proj = sb_m4_perspective(SB_PI / 2, 1, s->near, s->far);
    for (int f = 0; f < 6; f++) {
        sb_v3 dir = sb_v3_make(face_dir[f][0], face_dir[f][1], face_dir[f][2]);
        sb_v3 up = sb_v3_make(face_up[f][0], face_up[f][1], face_up[f][2]);
        s->face_vp[f] = sb_m4_mul(proj, sb_m4_look_at(s->lamp, sb_v3_add(s->lamp, dir), up));
        sb_frustum_planes(s->face_vp[f], s->planes[f]);
    }
}

/* The depth pass's program, variant a (1: with the alpha test): per face,
 * or layered by a geometry shader or by gl_Layer from the vertex shader. */
static bool create_depth_program(cube_state *s, int a, const char *defines, sb_err *err) {
    static const char *const names[3] = {"cube face", "cube layered (geometry shader)", "cube layered (vertex shader)"};
    char label[96];
    snprintf(label, sizeof label, "%s%s", names[s->layered], a ? " (alpha-tested draws)" : "");
    const char *fs[] = {sb_shader_depth_frag};
    GLuint p = 0;
    if (s->layered == 0) {
        const char *vs[] = {sb_shader_cube_depth_vert};
        p = sb_gpu_program(label, defines, vs, 1, fs, 1, err);
    } else if (s->layered == 1) {
        const char *vs[] = {sb_shader_csm_layer_gs_vert}, *gs[] = {sb_shader_cube_layer_geom};
        const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 1}, {GL_GEOMETRY_SHADER, gs, 1}, {GL_FRAGMENT_SHADER, fs, 1}};
        p = sb_gpu_link(label, defines, st, 3, err);
    } else {
        static const char vs_src[] =
            "layout(location = 0) in vec3 a_pos;\n"
            "uniform mat4 u_face_vp[6];\n"
            "void main() {\n"
            "    gl_Layer = gl_InstanceID;\n"
            "    gl_Position = u_face_vp[gl_InstanceID] * vec4(a_pos, 1.0);\n"
            "    SB_ALPHA_VS();\n"
            "}\n";
        const char *vs[] = {vs_src};
        const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 1}, {GL_FRAGMENT_SHADER, fs, 1}};
        char defs[256];
        snprintf(defs, sizeof defs, "#extension GL_ARB_shader_viewport_layer_array : require\n%s", defines ? defines : "");
        p = sb_gpu_link(label, defs, st, 2, err);
    }
    s->pass[a].prog = p;
    s->pass[a].u_vp = p ? glGetUniformLocation(p, s->layered ? "u_face_vp" : "u_vp") : -1;
    return p != 0;
}

static bool cube_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    cube_state *s = state;
    const cube_desc *d = desc;
    const sb_gpu *g = rc->gpu;
    s->d = d;
    s->layered = sb_layered_resolve(g->ctx, d->layered);
    const sb_light *lamp = sb_scene_point_light(g->scene, d->light, NULL);
    s->lamp = lamp->position;
    sb_v3 ext = sb_v3_sub(g->scene->bounds.hi, g->scene->bounds.lo);
    double diag = sb_v3_len(ext);
    s->far = lamp->range > 0 ? lamp->range : 2 * diag;
    s->near = fmax(s->far * 1e-4, 1e-6);
    face_frusta(s);
    s->tex = sb_shadow_texture(GL_TEXTURE_CUBE_MAP, GL_DEPTH_COMPONENT32F, s->d->res, 6, s->d->filter != 0);
    glGenFramebuffers(1, &s->fbo_all);
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo_all);
    glFramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, s->tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return sb_fail(err, "cube:res=%d: layered cube framebuffer is incomplete", s->d->res);
    glGenFramebuffers(6, s->fbo_face);
    for (int f = 0; f < 6; f++) {
        glBindFramebuffer(GL_FRAMEBUFFER, s->fbo_face[f]);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_CUBE_MAP_POSITIVE_X + f, s->tex, 0);
        glDrawBuffer(GL_NONE);
        glReadBuffer(GL_NONE);
    }
    for (int a = 0; a < (g->scene->alpha_tested_draws ? 2 : 1); a++)
        if (!create_depth_program(s, a, a ? NULL : sb_opaque_define(g), err)) return false;
    char defines[64];
    snprintf(defines, sizeof defines, "#define SB_FILTER %d\n", s->d->filter);
    if (!sb_final_prog_create(&s->fp, rc->gpu, "cube", sb_shader_vis_cube_glsl, defines, err)) return false;
    const char *names[] = {"u_cube", "u_lamp", "u_near", "u_far", "u_res", "u_bias", "u_normal"};
    GLint *locs[] = {&s->u_cube, &s->u_lamp, &s->u_near, &s->u_far, &s->u_res, &s->u_bias, &s->u_normal};
    for (size_t i = 0; i < SB_COUNT(names); i++) *locs[i] = glGetUniformLocation(s->fp.prog, names[i]);
    return sb_gl_check("cube", err);
}

static void cube_frame(void *state, sb_frame *f) {
    cube_state *s = state;
    const sb_gpu *g = f->gpu;
    const sb_scene *sc = g->scene;
    /* the lamp, before the shadow stage: its draws keep the triangles facing it */
    sb_frame_shade_point(f, s->lamp);
    sb_stage_begin(f, SB_STAGE_CASCADE);
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo_all);
    glViewport(0, 0, s->d->res, s->d->res);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glDisable(GL_CULL_FACE);
    if (s->d->slope != 0) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset((float)s->d->slope, 0.0f);
    }
    glBindVertexArray(g->vao);
    float m[6][16];
    for (int k = 0; k < 6; k++) sb_m4_to_float(s->face_vp[k], m[k]);
    int faces = 0;
    /* opaque casters first, with the variant without the alpha test; then the alpha-tested ones */
    if (s->layered == 0) {
        for (int k = 0; k < 6; k++) {
            uint32_t n = sb_scene_collect(sc, (const double(*)[4])s->planes[k], 6, f->scratch);
            if (!n) continue;
            faces++;
            glBindFramebuffer(GL_FRAMEBUFFER, s->fbo_face[k]);
            for (int a = 0; a < 2 && s->pass[a].prog; a++) {
                glUseProgram(s->pass[a].prog);
                glUniformMatrix4fv(s->pass[a].u_vp, 1, GL_FALSE, m[k]);
                for (uint32_t i = 0; i < n; i++)
                    if (sb_draw_variant(g, f->scratch[i]) == a) sb_submit(f, f->scratch[i], 1);
            }
        }
    } else {
        /* casters within the lamp's range: the box around it */
        double box[6][4];
        sb_cube_planes(s->lamp, s->far, box);
        uint32_t n = sb_scene_collect(sc, (const double(*)[4])box, 6, f->scratch);
        bool gs = s->layered == 1;
        for (int a = 0; a < 2 && s->pass[a].prog; a++) {
            glUseProgram(s->pass[a].prog);
            glUniformMatrix4fv(s->pass[a].u_vp, 6, GL_FALSE, &m[0][0]);
            for (uint32_t i = 0; i < n; i++)
                if (sb_draw_variant(g, f->scratch[i]) == a) sb_submit(f, f->scratch[i], gs ? 1 : 6);
        }
        faces = n ? 6 : 0;
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    f->counters.cascades_rendered = faces;
    f->counters.cascades_skipped = 6 - faces;
    sb_stage_end(f, SB_STAGE_CASCADE);

    sb_stage_begin(f, SB_STAGE_FINAL);
    glUseProgram(s->fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_CUBE_MAP, s->tex);
    glUniform1i(s->u_cube, 0);
    glUniform3f(s->u_lamp, (float)s->lamp.x, (float)s->lamp.y, (float)s->lamp.z);
    glUniform1f(s->u_near, (float)s->near);
    glUniform1f(s->u_far, (float)s->far);
    glUniform1f(s->u_res, (float)s->d->res);
    glUniform1f(s->u_bias, (float)s->d->bias);
    glUniform1f(s->u_normal, (float)s->d->normal);
    sb_final_pass(f, &s->fp, false);
    sb_stage_end(f, SB_STAGE_FINAL);
}

static void cube_destroy(void *state) {
    cube_state *s = state;
    sb_final_prog_free(&s->fp);
    for (int a = 0; a < 2; a++)
        if (s->pass[a].prog) glDeleteProgram(s->pass[a].prog);
    if (s->fbo_all) glDeleteFramebuffers(1, &s->fbo_all);
    if (s->fbo_face[0]) glDeleteFramebuffers(6, s->fbo_face);
    if (s->tex) glDeleteTextures(1, &s->tex);
}

const sb_technique sb_technique_cube = {
    .name = "cube",
    .summary = "point-light shadows with a depth cube map (six faces, per face or layered)",
    .params = cube_params,
    .param_count = (int)SB_COUNT(cube_params),
    .desc_size = sizeof(cube_desc),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_POINT_LIGHT,
    .state_size = sizeof(cube_state),
    .supported = cube_supported,
    .create = cube_create,
    .frame = cube_frame,
    .destroy = cube_destroy,
};
