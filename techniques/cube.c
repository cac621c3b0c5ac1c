/* cube.c - point-light shadows with a depth cube map: six 90-degree
 * perspective faces around the lamp, rendered per face (casters culled per
 * face frustum over the BVH) or in one layered pass (a geometry shader routes
 * each triangle to the faces it touches, or instancing with gl_Layer from the
 * vertex shader), the same `layered=` choice as cascades. A lamp technique
 * (lamp.h): the lamp, its maps, the final pass and the reference are the
 * shared ones. */
#include "lamp.h"
#include "shaders.h"

static const sb_param_def cube_params[] = {
    SB_LAMP_PARAMS("cube face resolution"),
    SB_PARAM_E(sb_lamp_desc, filter, hw, "none|hw|pcf", "shadow filter", .tune = "none,hw,pcf3"),
    SB_PARAM_E(sb_lamp_desc, layered, off, "off|gs|vs|on", "six passes, or one layered pass"),
    SB_LAMP_GRID_PARAM,
};

typedef struct {
    sb_lamp_state lamp;         /* first: the shared machinery's */
    sb_m4 face_vp[6];
    double planes[6][6][4];     /* each face's culling frustum */
} cube_state;

/* The six faces' matrices and culling planes around the lamp. */
static void face_frusta(sb_lamp_state *ls) {
    cube_state *s = (cube_state *)ls;
    sb_lamp_cube_faces(ls->lamp, ls->near, ls->far, s->face_vp);
    for (int f = 0; f < 6; f++) sb_frustum_planes(s->face_vp[f], s->planes[f]);
}

/* The depth pass's program, variant a (1: with the alpha test): per face,
 * or layered by a geometry shader or by gl_Layer from the vertex shader. */
static bool depth_program(sb_lamp_state *s, int a, const char *defines, sb_err *err) {
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
        const char *vs[] = {sb_shader_cube_layer_vs_vert};
        const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 1}, {GL_FRAGMENT_SHADER, fs, 1}};
        char defs[256];
        snprintf(defs, sizeof defs, "#extension GL_ARB_shader_viewport_layer_array : require\n%s", defines ? defines : "");
        p = sb_gpu_link(label, defs, st, 2, err);
    }
    s->pass[a].prog = p;
    s->pass[a].u[0] = p ? glGetUniformLocation(p, s->layered ? "u_face_vp" : "u_vp") : -1;
    return p != 0;
}

/* arg: the matrices to set, one face's or the six */
static void set_face(const sb_lamp_state *s, int a, const void *arg) {
    glUniformMatrix4fv(s->pass[a].u[0], s->layered ? 6 : 1, GL_FALSE, arg);
}

static int render(sb_lamp_state *ls, sb_frame *f) {
    cube_state *s = (cube_state *)ls;
    float m[6][16];
    for (int k = 0; k < 6; k++) sb_m4_to_float(s->face_vp[k], m[k]);
    if (ls->layered) { /* the casters in the lamp's range, once, to every face */
        uint32_t n = sb_lamp_casters(ls, f);
        sb_lamp_draw(ls, f, n, ls->layered == 1 ? 1 : 6, set_face, m);
        return n ? 6 : 0;
    }
    int faces = 0;
    for (int k = 0; k < 6; k++) {
        uint32_t n = sb_scene_collect(f->gpu->scene, (const double(*)[4])s->planes[k], 6, f->scratch);
        if (!n) continue;
        faces++;
        glBindFramebuffer(GL_FRAMEBUFFER, ls->fbo[k]);
        sb_lamp_draw(ls, f, n, 1, set_face, m[k]);
    }
    return faces;
}

static const sb_lamp_kind cube_kind = {
    .target = GL_TEXTURE_CUBE_MAP, .maps = 6, .layered = true, .near_share = 1e-4,
    .vis_glsl = sb_shader_vis_cube_glsl, .setup = face_frusta, .program = depth_program, .render = render,
};

const sb_technique sb_technique_cube =
    SB_LAMP_TECHNIQUE("cube", "point-light shadows with a depth cube map (six faces, per face or layered)", cube_params,
                      cube_state, &cube_kind);
