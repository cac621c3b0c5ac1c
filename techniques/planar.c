/* planar.c - planar projected shadows (Blinn 1988). Casters are flattened
 * onto each receiver plane with the shadow matrix of a directional light,
 *   p' = p - L (n·p + d) / (n·L),
 * and drawn into the stencil only where the plane itself is visible (so
 * overlapping shadow triangles count once and shadows stay on the plane).
 * Receiver planes are found when this technique first needs them (SB_NEEDS_PLANE): planes holding at least 10% of the
 * area of the scene bounds' largest face (a scene without one skips the
 * technique). No self-shadowing and no curved receivers: the error metric
 * shows what that costs.
 * Stages: zpass (depth, stencil cleared), volumes (the projected casters,
 * into the stencil), final (drawn twice: stencil shadow bit clear, lit; set,
 * shadowed). */
#include <stdlib.h>
#include <string.h>

#include "render.h"
#include "shaders.h"

/* No parameters: everything is the scene's, made once (load). */
typedef struct {
    GLuint prog_mark, prog_flat;
    GLint m_view, m_proj;
    GLint f_view, f_proj, f_flatten, f_plane, f_eps;
    sb_final_prog fp;
    GLint u_lit;
    GLuint plane_ibo[SB_MAX_PLANES];    /* each plane's triangles */
    float flatten[SB_MAX_PLANES][16];
    bool usable[SB_MAX_PLANES];         /* facing the light */
    float eps;
} planar_geo;

typedef struct {
    const planar_geo *geo;
} planar_state;

static void planar_unload(void *data) {
    planar_geo *s = data;
    if (!s) return;
    sb_final_prog_free(&s->fp);
    if (s->prog_mark) glDeleteProgram(s->prog_mark);
    if (s->prog_flat) glDeleteProgram(s->prog_flat);
    for (int k = 0; k < SB_MAX_PLANES; k++)
        if (s->plane_ibo[k]) glDeleteBuffers(1, &s->plane_ibo[k]);
    free(s);
}

static bool planar_load(const sb_gpu *g, void **data, sb_err *err) {
    planar_geo *s = sb_xcalloc(1, sizeof *s);
    *data = s;
    const sb_scene *sc = g->scene;
    sb_v3 L = g->sun;
    sb_v3 ext = sb_v3_sub(sc->bounds.hi, sc->bounds.lo);
    s->eps = (float)(sb_v3_len(ext) * 1e-5);
    for (uint32_t k = 0; k < sc->plane_count; k++) {
        const sb_plane *pl = &sc->planes[k];
        double nl = pl->n[0] * L.x + pl->n[1] * L.y + pl->n[2] * L.z;
        s->usable[k] = nl > 1e-6;    /* a plane facing away from the sun receives no shadow */
        if (!s->usable[k]) continue;
        /* M = I - L n^T / (n·L), translation -L d / (n·L) (column-major) */
        double Ld[3] = {L.x, L.y, L.z};
        sb_m4 m = sb_m4_identity();
        for (int c = 0; c < 3; c++)
            for (int r = 0; r < 3; r++) m.m[c * 4 + r] -= Ld[r] * pl->n[c] / nl;
        for (int r = 0; r < 3; r++) m.m[12 + r] = -Ld[r] * pl->d / nl;
        sb_m4_to_float(m, s->flatten[k]);
        uint32_t *idx = sb_xmalloc(sizeof(uint32_t) * 3 * pl->tri_count);
        for (uint32_t t = 0; t < pl->tri_count; t++) sb_gpu_triangle(g, pl->tris[t], idx + 3 * t);
        glGenBuffers(1, &s->plane_ibo[k]);
        glBindBuffer(GL_COPY_WRITE_BUFFER, s->plane_ibo[k]); /* not through a VAO's element binding */
        glBufferData(GL_COPY_WRITE_BUFFER, (GLsizeiptr)(12 * (size_t)pl->tri_count), idx, GL_STATIC_DRAW);
        free(idx);
    }
    const char *vs_mark[] = {sb_shader_scene_vert}, *fs_mark[] = {sb_shader_depth_frag};
    s->prog_mark = sb_gpu_program("planar (receivers)", NULL, vs_mark, 1, fs_mark, 1, err);
    if (!s->prog_mark) return false;
    s->m_view = glGetUniformLocation(s->prog_mark, "u_view");
    s->m_proj = glGetUniformLocation(s->prog_mark, "u_proj");
    const char *vs_flat[] = {sb_shader_planar_vert}, *fs_flat[] = {sb_shader_planar_frag};
    s->prog_flat = sb_gpu_program("planar (casters)", NULL, vs_flat, 1, fs_flat, 1, err);
    if (!s->prog_flat) return false;
    s->f_view = glGetUniformLocation(s->prog_flat, "u_view");
    s->f_proj = glGetUniformLocation(s->prog_flat, "u_proj");
    s->f_flatten = glGetUniformLocation(s->prog_flat, "u_flatten");
    s->f_plane = glGetUniformLocation(s->prog_flat, "u_plane");
    s->f_eps = glGetUniformLocation(s->prog_flat, "u_eps");
    if (!sb_final_prog_create(&s->fp, g, "planar", sb_shader_vis_volumes_glsl, NULL, err)) return false;
    s->u_lit = glGetUniformLocation(s->fp.prog, "u_lit");
    return sb_gl_check("planar", err);
}

static bool planar_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    (void)desc;
    (void)err;
    ((planar_state *)state)->geo = rc->scene_data;
    return true;
}

static void planar_frame(void *state, sb_frame *f) {
    const planar_geo *s = ((planar_state *)state)->geo;
    const sb_gpu *g = f->gpu;
    const sb_scene *sc = g->scene;

    sb_stage_begin(f, &sb_stage_zpass);
    sb_zpass(f);
    sb_stage_end(f, &sb_stage_zpass);

    sb_stage_begin(f, &sb_stage_volumes);
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
    glDrawBuffer(GL_NONE);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_STENCIL_TEST);
    glBindVertexArray(g->vao);
    for (uint32_t k = 0; k < sc->plane_count; k++) {
        if (!s->usable[k]) continue;
        GLint id = (GLint)k + 1;
        /* 1: where the plane is what the camera sees, the low bits hold its id */
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LEQUAL);
        glStencilMask(0x7f);
        glStencilFunc(GL_ALWAYS, id, 0x7f);
        glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
        glUseProgram(s->prog_mark);
        sb_set_camera_uniforms(f, s->m_view, s->m_proj);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s->plane_ibo[k]);
        glDrawElements(GL_TRIANGLES, (GLsizei)(3 * sc->planes[k].tri_count), GL_UNSIGNED_INT, 0);
        sb_count_draw(f, sc->planes[k].tri_count, 1);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g->ibo);
        /* 2: every caster above the plane, flattened onto it, sets the shadow bit once */
        glDisable(GL_DEPTH_TEST);
        glStencilMask(0x80);
        glStencilFunc(GL_EQUAL, 0x80 | id, 0x7f);
        glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
        glUseProgram(s->prog_flat);
        sb_set_camera_uniforms(f, s->f_view, s->f_proj);
        glUniformMatrix4fv(s->f_flatten, 1, GL_FALSE, s->flatten[k]);
        const sb_plane *pl = &sc->planes[k];
        glUniform4f(s->f_plane, (float)pl->n[0], (float)pl->n[1], (float)pl->n[2], (float)pl->d);
        glUniform1f(s->f_eps, s->eps);
        for (uint32_t d = 0; d < sc->draw_count; d++) sb_submit(f, d, 1);
        sb_submit_flush(f);
    }
    glStencilMask(0xff);
    glEnable(GL_DEPTH_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    sb_stage_end(f, &sb_stage_volumes);

    sb_stage_begin(f, &sb_stage_final);
    sb_final_pass_stencil(f, &s->fp, s->u_lit, 0x80);   /* the shadow bit */
    sb_stage_end(f, &sb_stage_final);
}

static void planar_destroy(void *state) { (void)state; }

const sb_technique sb_technique_planar = {
    .name = "planar",
    .summary = "planar projected shadows onto the scene's large planes, with the stencil (Blinn 1988)",
    SB_STAGES(&sb_stage_zpass, &sb_stage_volumes, &sb_stage_final),
    .needs = SB_NEEDS_SUN | SB_NEEDS_PLANE,
    .state_size = sizeof(planar_state),
    .load = planar_load,
    .unload = planar_unload,
    .create = planar_create,
    .frame = planar_frame,
    .destroy = planar_destroy,
};
