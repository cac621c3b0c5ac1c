/* render.c - scene upload, render target, the final-pass program, counted draw submission. */
#include "render.h"

#include "pose.h"

#include <math.h>

#include <stdlib.h>
#include <string.h>

#include "motion.h"
#include "shaders.h"
#include "timing.h"

/* A software rasterizer (llvmpipe) bins what is submitted on the submitting thread and holds every binned scene
 * until its threads have drawn it; a pass per framebuffer is a scene, and the submission runs ahead of the drawing:
 * pssm's four cascade passes on the hallway tiled 10x10 (5.3 M triangles) peaked at 615 MB, one layered pass at
 * 363 MB, and with the drawing done at once (LP_NUM_THREADS=0) 239 MB. There the submission goes in pieces of about
 * SB_SOFT_PIECE_TRIS triangles, and each piece waits for the one before it to be drawn (a fence), so that at most
 * two are binned at once whatever the level's size. A GPU's driver bounds its own queue: nothing waits there. */
#define SB_SOFT_PIECE_TRIS 250000u
#define SB_SOFT_PIECE_WAIT_NS 30000000000ull   /* a piece not drawn in 30 s is not waited on further */
struct sb_gpu_pieces {
    uint64_t tris;            /* submitted since the last fence */
    GLsync prev;              /* the last piece's fence */
};

static void pieces_submitted(const sb_gpu *g, uint64_t tris) {
    struct sb_gpu_pieces *p = g->pieces;
    if (!p || (p->tris += tris) < SB_SOFT_PIECE_TRIS) return;
    p->tris = 0;
    GLsync now = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    if (p->prev) {
        glClientWaitSync(p->prev, GL_SYNC_FLUSH_COMMANDS_BIT, SB_SOFT_PIECE_WAIT_NS);
        glDeleteSync(p->prev);
    }
    p->prev = now;
}

const char *sb_opaque_define(const sb_gpu *g) {
    return g->scene->alpha_tested_draws ? "#define SB_NO_ALPHA\n" : "";
}

int sb_draw_variant(const sb_gpu *g, uint32_t d) { return g->scene->draws[d].material != 0; }

/* Links variant i of the camera pass (2 * eval + alpha). */
static bool final_variant(sb_final_prog *fp, int i, const sb_gpu *g, const char *label, const char *defines,
                          const char *const *vis_parts, int nvis, sb_err *err) {
    bool eval = i >> 1, alpha = i & 1;
    const char *vs[] = {sb_shader_scene_vert};
    const char *fs[8];
    int n = 0;
    for (int k = 0; k < nvis && n < 7; k++) fs[n++] = vis_parts[k];
    fs[n++] = sb_shader_final_frag;
    char defs[1024];
    snprintf(defs, sizeof defs, "#define SB_AMBIENT %.17g\n#define SB_DIRECT %.17g\n%s%s%s", SB_SHADE_AMBIENT,
             SB_SHADE_DIRECT, eval ? "#define SB_EVAL\n" : "", alpha ? "" : sb_opaque_define(g), defines ? defines : "");
    char name[160];
    snprintf(name, sizeof name, "%s%s%s", label, eval ? " (evaluation)" : "", alpha ? " (alpha-tested draws)" : "");
    sb_final_variant *v = &fp->v[i];
    if (!(v->prog = sb_gpu_program(name, defs, vs, 1, fs, n, err))) return false;
    v->u_view = glGetUniformLocation(v->prog, "u_view");
    v->u_proj = glGetUniformLocation(v->prog, "u_proj");
    v->u_light = glGetUniformLocation(v->prog, "u_shade_light");
    v->u_more = glGetUniformLocation(v->prog, "u_shade_more");
    v->u_spot = glGetUniformLocation(v->prog, "u_shade_spot");
    v->u_depth_view = glGetUniformLocation(v->prog, "u_depth_view");
    if (i == 0) return true;
    /* the technique's uniforms reach this variant by copy from v[0]: one only it read would keep
       its default, 0 (and the error be measured on another picture). Refused here, at create. */
    GLint count = 0;
    glGetProgramiv(v->prog, GL_ACTIVE_UNIFORMS, &count);
    for (GLuint u = 0; u < (GLuint)count; u++) {
        char un[256];
        GLint size = 0, block = -1;
        GLenum type = 0;
        glGetActiveUniform(v->prog, u, sizeof un, NULL, &size, &type, un);
        glGetActiveUniformsiv(v->prog, 1, &u, GL_UNIFORM_BLOCK_INDEX, &block);
        if (block >= 0 || glGetUniformLocation(fp->v[0].prog, un) >= 0) continue;
        /* the shared pass's own: set on each variant, or bound by the shader (the alpha test's sb_ samplers) */
        bool own = !strncmp(un, "sb_", 3);
        const char *shared[] = {"u_view", "u_proj", "u_shade_light", "u_shade_more", "u_shade_spot", "u_depth_view"};
        for (size_t k = 0; k < SB_COUNT(shared); k++) own |= !strcmp(un, shared[k]);
        if (!own)
            return sb_fail(err, "%s: uniform %s is read by the %s variant of the camera pass only: its value would not "
                                "reach it (use it in the timed variant too, or derive it there)",
                           label, un, eval ? "evaluation" : "alpha-tested");
    }
    if (!sb_gl_links_make(&v->from_timed, fp->v[0].prog, v->prog))
        return sb_fail(err, "%s: more than %d uniforms to carry to its variants", label, SB_GL_MAX_LINKS);
    return true;
}

bool sb_final_prog_create_parts(sb_final_prog *fp, const sb_gpu *g, const char *label, const char *const *vis_parts,
                                int nvis, const char *defines, sb_err *err) {
    memset(fp, 0, sizeof *fp);
    bool alpha = g->scene->alpha_tested_draws > 0;
    for (int i = 0; i < 4; i++) {
        if ((i & 1) && !alpha) continue;
        if (!final_variant(fp, i, g, label, defines, vis_parts, nvis, err)) {
            sb_final_prog_free(fp);
            return false;
        }
    }
    fp->prog = fp->v[0].prog;
    fp->eval_prog = fp->v[2].prog;
    return true;
}

bool sb_final_prog_create(sb_final_prog *fp, const sb_gpu *g, const char *label, const char *vis_glsl,
                          const char *defines, sb_err *err) {
    return sb_final_prog_create_parts(fp, g, label, &vis_glsl, 1, defines, err);
}

void sb_final_prog_free(sb_final_prog *fp) {
    for (int i = 0; i < 4; i++)
        if (fp->v[i].prog) glDeleteProgram(fp->v[i].prog);
    memset(fp, 0, sizeof *fp);
}

/* The divisor of the per-draw attributes (colour, caster mask): above any draw's instance count. */
#define SB_DRAW_DIVISOR 64

static GLuint make_tex(GLenum internal, int w, int h) {
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexStorage2D(GL_TEXTURE_2D, 1, internal, w, h);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

GLuint sb_cpu_vis_texture(const sb_gpu *g) { return make_tex(GL_R8, g->width, g->height); }

void sb_cpu_vis_bind(GLuint tex, const sb_gpu *g, const unsigned char *vis) {
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, tex);
    if (!vis) return;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, g->width, g->height, GL_RED, GL_UNSIGNED_BYTE, vis);
}

/* ---- the alpha test's data ---- */

/* A material as alpha.glsl's SbMaterial (48 bytes). */
typedef struct {
    uint32_t i[4];
    float f[8];
} packed_material;

/* ---- the scene's geometry on the GPU: a shared primitive once ---- */

/* Which instances (sb_draw.proto) draw their proto's GPU copy through their transform. A shadow pass draws an
 * open single-sided draw's light-facing triangles only (sb_facing, ordered per draw): an instance may share
 * that order when its triangles face the light as its proto's do: always when double-sided or closed (drawn
 * whole), and for an open one when it is only moved (a translation) and the light is the sun. A lamp lowers
 * the sharing to the first kind (its direction differs from point to point), planar's receiver pass (which
 * draws triangles by their scene numbers) to none: sb_gpu_share. */
enum { SHARE_ALL, SHARE_WHOLE, SHARE_NONE };

struct sb_gpu_geom {
    int mode;
    uint32_t *first;            /* per draw: its first index in the GPU's index buffer */
    uint32_t *vbase;            /* per draw: where its first vertex (sb_draw.first_vertex) is in the vertex buffer */
    uint32_t index_count;       /* the GPU's index buffer */
    uint32_t *orig;             /* that buffer as uploaded (NULL: the scene's own indices, no instance copied) */
};

static bool shares(const sb_scene *s, uint32_t d, int mode) {
    const sb_draw *dr = &s->draws[d];
    if (dr->proto == d || mode == SHARE_NONE) return false;
    return dr->double_sided || dr->closed || (mode == SHARE_ALL && sb_xform_translation_only(dr->xform));
}

/* Per draw, 1 where an instance cannot share its proto's GPU copy under `mode` (drawn from vertices of its own,
 * placed: sb_scene_flatten); NULL when no instance is so. */
static uint8_t *own_copies(const sb_scene *s, int mode) {
    uint8_t *which = NULL;
    for (uint32_t d = 0; d < s->draw_count && s->instance_draws; d++) {
        if (!SB_DRAW_IS_INSTANCE(s, d) || shares(s, d, mode)) continue;
        if (!which) which = sb_xcalloc(s->draw_count, 1);
        which[d] = 1;
    }
    return which;
}

double sb_gpu_scene_bytes(const sb_scene *s) {
    uint64_t nv = s->vertex_count, ni = s->index_count;
    uint8_t *which = own_copies(s, SHARE_ALL);
    if (which) {
        sb_scene_flat f;
        sb_scene_flatten(s, which, &f);
        nv = f.vertex_count, ni = f.index_count;
        sb_scene_flat_free(&f);
        free(which);
    }
    double b = (double)nv * SB_VERTEX_BYTES + (double)ni * sizeof(uint32_t) + (double)(s->draw_count + 1) * 48;
    if (s->alpha_tested_draws > 0)
        b += (double)s->material_count * sizeof(packed_material) + (s->texel_count ? s->texel_count : 1);
    return b;
}

/* (Re)fills the vertex, index and per-draw transform buffers for sharing `mode`: the scene's own triangles as
 * they are, then an instance that cannot share on vertices of its own (its triangles then numbered as
 * sb_scene_flatten numbers them, planar's receivers among them under SHARE_NONE). */
static void upload_geometry_as(const sb_gpu *g, int mode) {
    const sb_scene *s = g->scene;
    struct sb_gpu_geom *gm = g->geom;
    gm->mode = mode;
    free(gm->orig);
    gm->orig = NULL;
    float *xf = sb_xmalloc(sizeof(float) * 12 * (s->draw_count + 1));
    for (uint32_t d = 0; d <= s->draw_count; d++)
        memcpy(xf + 12 * (size_t)d, d < s->draw_count && shares(s, d, mode) ? s->draws[d].xform : sb_xform_identity,
               sizeof sb_xform_identity);
    glBindBuffer(GL_ARRAY_BUFFER, g->xform_buf);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(sizeof(float) * 12 * (s->draw_count + 1)), xf, GL_STATIC_DRAW);
    free(xf);
    uint8_t *which = own_copies(s, mode);
    sb_scene_flat f;
    if (which) sb_scene_flatten(s, which, &f);
    else f = (sb_scene_flat){s->vertices, s->vertex_count, s->indices, s->index_count, NULL, false};
    for (uint32_t d = 0; d < s->draw_count; d++) {
        const sb_draw *dr = &s->draws[d];
        gm->first[d] = f.first ? f.first[d] : dr->first_index;   /* a shared instance: its proto's run */
        gm->vbase[d] = SB_DRAW_IS_INSTANCE(s, d) ? UINT32_MAX : dr->first_vertex;
    }
    gm->index_count = f.index_count;
    glBindBuffer(GL_ARRAY_BUFFER, g->vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)f.vertex_count * SB_VERTEX_BYTES, f.vertices, GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g->ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)f.index_count * sizeof(uint32_t), f.indices, GL_STATIC_DRAW);
    if (f.owned) {
        gm->orig = (uint32_t *)f.indices;   /* kept: the facing order's source */
        free((void *)f.vertices);
    }
    free(f.first);
    free(which);
}

/* upload_geometry_as, then the moving vertices posed again where the GPU poses them: the upload sent the CPU's
 * copy, which may hold an older pose. */
static void upload_geometry(const sb_gpu *g, int mode) {
    upload_geometry_as(g, mode);
    sb_pose_remap(g->pose);
    sb_pose_run(g->pose, g->scene, g->vbo);
}

/* Materials as alpha.glsl's SbMaterial and the texels as an R8UI buffer texture. */
static bool upload_alpha(sb_gpu *g, const sb_scene *s, sb_err *err) {
    /* every program of the session compiles with the common GLSL, the alpha test when the scene has one, and
       the instance transform (common.glsl's sb_world) when it has shared geometry */
    const char *prelude[] = {s->alpha_tested_draws > 0 ? "#define SB_ALPHA\n" : "",
                             s->instance_draws > 0 ? "#define SB_SHARED\n" : "", sb_shader_common_glsl,
                             sb_shader_alpha_glsl};
    sb_gl_set_prelude(prelude, 4);
    if (!s->alpha_tested_draws) return true;
    GLint max_texels = 0;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    if (s->texel_count > (uint32_t)max_texels)
        return sb_fail(err, "%s: the alpha textures hold %u texels, more than this GL's buffer textures (%d)", s->file,
                       s->texel_count, max_texels);
    packed_material *m = sb_xcalloc(s->material_count, sizeof *m);
    for (uint32_t k = 0; k < s->material_count; k++) {
        const sb_material *sm = &s->materials[k];
        const sb_texture *t = sm->texture >= 0 ? &s->textures[sm->texture] : NULL;
        m[k] = (packed_material){{t ? t->offset : 0, t ? t->w : 0, t ? t->h : 0, t ? (t->wrap_s | t->wrap_t << 16) : 0},
                        {sm->test ? sm->cutoff : 0, sm->alpha, sm->uv[0], sm->uv[1], sm->uv[2], sm->uv[3], sm->uv[4],
                         sm->uv[5]}};
    }
    glGenBuffers(1, &g->mat_ssbo);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->mat_ssbo);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(s->material_count * sizeof *m), m, GL_STATIC_DRAW);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, g->mat_ssbo);
    free(m);
    glGenBuffers(1, &g->texel_buf);
    glBindBuffer(GL_TEXTURE_BUFFER, g->texel_buf);
    glBufferData(GL_TEXTURE_BUFFER, s->texel_count ? s->texel_count : 1, s->texels, GL_STATIC_DRAW);
    glGenTextures(1, &g->texel_tex);
    glActiveTexture(GL_TEXTURE15);
    glBindTexture(GL_TEXTURE_BUFFER, g->texel_tex);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_R8UI, g->texel_buf);
    glActiveTexture(GL_TEXTURE0);
    return true;
}

/* ---- single-sided draws in shadow passes ---- */

/* The GPU index buffer with each open single-sided draw's range split: the
 * triangles whose front faces `light` first (count[d] of them), then the
 * rest, which shadow passes leave out as glTF culls them. A closed mesh is
 * drawn whole: from the light its back faces lie behind its front faces and
 * cast no other shadow, and leaving them out changes what the slope bias does
 * at its silhouettes (measured: cube on towers-night err_rate 0.0065 whole,
 * 0.0127 front faces only). */
typedef struct sb_facing {
    bool valid;
    double light[4];
    uint32_t *count;            /* per draw */
    uint32_t *indices;          /* the scene's index buffer as uploaded */
} sb_facing;

static bool faces_light(const sb_scene *s, const sb_draw *dr, const uint32_t *t, const double light[4]) {
    float a[3], b[3], c[3];
    sb_draw_point(s, dr, t[0], a), sb_draw_point(s, dr, t[1], b), sb_draw_point(s, dr, t[2], c);
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double L[3] = {light[0], light[1], light[2]};
    if (light[3] > 0.5)
        for (int k = 0; k < 3; k++) L[k] -= a[k];
    return n[0] * L[0] + n[1] * L[1] + n[2] * L[2] > 0;
}

static void arrange_for(const sb_gpu *g, const double light[4]) {
    if (light[3] > 0.5 && g->geom->mode == SHARE_ALL) sb_gpu_share(g, false);   /* a lamp: see sb_gpu_share */
    sb_facing *fc = g->facing;
    const sb_scene *s = g->scene;
    const struct sb_gpu_geom *gm = g->geom;
    const uint32_t *orig = gm->orig ? gm->orig : s->indices;   /* the GPU's numbering, as uploaded */
    uint32_t *rest = sb_xmalloc(sizeof(uint32_t) * 3 * SB_CHUNK_TRIS);
    for (uint32_t d = 0; d < s->draw_count; d++) {
        const sb_draw *dr = &s->draws[d];
        fc->count[d] = dr->index_count / 3;
        if (dr->double_sided || dr->closed || shares(s, d, gm->mode)) continue;
        if (dr->motion != SB_DRAW_STILL) sb_scene_sync_vertices(s);   /* which way it faces: the CPU's pose */
        /* which way a triangle faces from the scene's vertices as the draw places them; what moves is its GPU copy */
        const uint32_t *flat = s->indices + dr->first_index, *src = orig + gm->first[d];
        uint32_t *dst = fc->indices + gm->first[d], n = dr->index_count / 3, front = 0, back = 0;
        for (uint32_t t = 0; t < n; t++)
            memcpy(faces_light(s, dr, flat + 3 * t, light) ? dst + 3 * front++ : rest + 3 * back++, src + 3 * t, 12);
        memcpy(dst + 3 * front, rest, 12 * (size_t)back);
        fc->count[d] = front;
    }
    for (uint32_t d = 0; d < s->draw_count; d++)   /* a shared open draw is only moved: it faces as its proto */
        if (shares(s, d, gm->mode)) fc->count[d] = fc->count[s->draws[d].proto];
    free(rest);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g->ibo);
    glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, (GLsizeiptr)gm->index_count * sizeof(uint32_t), fc->indices);
    memcpy(fc->light, light, sizeof fc->light);
    fc->valid = true;
}

/* Triangles of draw d that a shadow pass lit by `light` draws. */
static uint32_t shadow_triangles(const sb_gpu *g, uint32_t d, const double light[4]) {
    const sb_draw *dr = &g->scene->draws[d];
    if (dr->double_sided || dr->closed || !g->facing) return dr->index_count / 3;
    if (!g->facing->valid || memcmp(g->facing->light, light, sizeof g->facing->light)) arrange_for(g, light);
    return g->facing->count[d];
}

/* The facing order's buffers for the index buffer as uploaded now. */
static void facing_reset(const sb_gpu *g) {
    if (!g->facing) return;
    const struct sb_gpu_geom *gm = g->geom;
    free(g->facing->indices);
    g->facing->indices = sb_xmalloc(sizeof(uint32_t) * (gm->index_count ? gm->index_count : 1));
    memcpy(g->facing->indices, gm->orig ? gm->orig : g->scene->indices, sizeof(uint32_t) * gm->index_count);
    g->facing->valid = false;
}

void sb_gpu_update_motion(const sb_gpu *g) {
    const sb_scene *s = g->scene;
    const struct sb_gpu_geom *gm = g->geom;
    if (!g->pose) sb_scene_sync_vertices(s);   /* no posing pass: the CPU poses every placement */
    glBindBuffer(GL_ARRAY_BUFFER, g->vbo);
    uint32_t done = UINT32_MAX;   /* a primitive's chunks name the same vertices: the last one sent */
    for (uint32_t d = 0; d < s->draw_count; d++) {
        const sb_draw *dr = &s->draws[d];
        if (dr->motion == SB_DRAW_STILL || dr->first_vertex == done || gm->vbase[d] == UINT32_MAX ||
            !sb_pose_leaves(g->pose, d))
            continue;
        glBufferSubData(GL_ARRAY_BUFFER, (GLintptr)gm->vbase[d] * SB_VERTEX_BYTES,
                        (GLsizeiptr)dr->vertex_count * SB_VERTEX_BYTES, sb_vertex(s, dr->first_vertex));
        done = dr->first_vertex;
    }
    sb_pose_due(g->pose);   /* the GPU poses its vertices in the next frame drawn (sb_render_camera) */
    if (g->facing) g->facing->valid = false;   /* an open moving draw faces the light otherwise now */
}


void sb_gpu_triangle(const sb_gpu *g, uint32_t t, uint32_t out[3]) {
    const uint32_t *ix = g->geom->orig ? g->geom->orig : g->scene->indices;
    memcpy(out, ix + 3 * (size_t)t, 3 * sizeof(uint32_t));
}

void sb_gpu_share(const sb_gpu *g, bool planar) {
    int mode = planar ? SHARE_NONE : SHARE_WHOLE;
    if (!g->scene->instance_draws || g->geom->mode >= mode) return;
    upload_geometry(g, mode);
    facing_reset(g);
}

/* The VAO's attributes: the vertex buffer's (position, normal, texture coordinates and material), and per draw,
 * read at the draw's baseInstance, its instance transform, colour and mask (the divisor exceeds any draw's
 * instances: 8 cascades, 6 faces, so every instance of a draw reads its own entry). */
static void vertex_arrays(sb_gpu *g) {
    const sb_scene *s = g->scene;
    glBindBuffer(GL_ARRAY_BUFFER, g->xform_buf);
    for (int r = 0; r < 3; r++) {   /* an instance's transform (common.glsl's sb_world): per draw, three rows */
        glEnableVertexAttribArray(6 + r);
        glVertexAttribPointer(6 + r, 4, GL_FLOAT, GL_FALSE, 48, (void *)(16 * (size_t)r));
        glVertexAttribDivisor(6 + r, SB_DRAW_DIVISOR);
    }
    glBindBuffer(GL_ARRAY_BUFFER, g->vbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, SB_VERTEX_BYTES, (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, SB_VERTEX_BYTES, (void *)12);
    glEnableVertexAttribArray(2);   /* texture coordinates and material: the alpha test (alpha.glsl) */
    glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, SB_VERTEX_BYTES, (void *)24);
    glEnableVertexAttribArray(3);
    glVertexAttribIPointer(3, 1, GL_UNSIGNED_INT, SB_VERTEX_BYTES, (void *)32);
    float *colors = sb_xmalloc(sizeof(float) * 4 * (s->draw_count + 1));
    for (uint32_t d = 0; d < s->draw_count; d++) memcpy(colors + 4 * d, s->draws[d].color, 4 * sizeof(float));
    glGenBuffers(1, &g->color_buf);
    glBindBuffer(GL_ARRAY_BUFFER, g->color_buf);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(sizeof(float) * 4 * (s->draw_count + 1)), colors, GL_STATIC_DRAW);
    free(colors);
    glEnableVertexAttribArray(4);
    glVertexAttribPointer(4, 4, GL_FLOAT, GL_FALSE, 16, (void *)0);
    glVertexAttribDivisor(4, SB_DRAW_DIVISOR);
    glGenBuffers(1, &g->mask_buf);
    glBindBuffer(GL_ARRAY_BUFFER, g->mask_buf);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(s->draw_count + 4), NULL, GL_STREAM_DRAW);
    glEnableVertexAttribArray(5);
    glVertexAttribIPointer(5, 1, GL_UNSIGNED_BYTE, 1, (void *)0);
    glVertexAttribDivisor(5, SB_DRAW_DIVISOR);
    glGenBuffers(1, &g->indirect_buf);
}

/* The camera's render targets (colour, visibility, depth and stencil, positions, aux, base colour) on one FBO. */
static bool render_targets(sb_gpu *g, int w, int h, sb_err *err) {
    g->color_tex = make_tex(GL_RGBA8, w, h);
    g->vis_tex = make_tex(GL_R8, w, h);
    g->depth_tex = make_tex(GL_DEPTH32F_STENCIL8, w, h);   /* stencil: shadow volumes */
    g->pos_tex = make_tex(GL_RGBA32F, w, h);
    g->aux_tex = make_tex(GL_RGBA32F, w, h);
    g->base_tex = make_tex(GL_RGBA8, w, h);
    glGenFramebuffers(1, &g->fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, g->color_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, g->vis_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, g->pos_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT3, GL_TEXTURE_2D, g->aux_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT4, GL_TEXTURE_2D, g->base_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, g->depth_tex, 0);
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, bufs);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return sb_fail(err, "render target %dx%d is incomplete (out of memory or unsupported size?)", w, h);
    return true;
}

/* The z-pass programs: without the alpha test, and with it where the scene has alpha-tested draws. */
static bool zpass_programs(sb_gpu *g, sb_err *err) {
    const char *vs[] = {sb_shader_scene_vert};
    const char *fs[] = {sb_shader_depth_frag};
    for (int a = 0; a < (g->scene->alpha_tested_draws ? 2 : 1); a++) {
        g->zpass_prog[a] = sb_gpu_program(a ? "zpass (alpha-tested draws)" : "zpass", a ? NULL : sb_opaque_define(g),
                                          vs, 1, fs, 1, err);
        if (!g->zpass_prog[a]) return false;
        g->zpass_u_view[a] = glGetUniformLocation(g->zpass_prog[a], "u_view");
        g->zpass_u_proj[a] = glGetUniformLocation(g->zpass_prog[a], "u_proj");
    }
    return true;
}

bool sb_gpu_init(sb_gpu *g, const sb_context *ctx, const sb_scene *s, int w, int h, sb_v3 sun, sb_err *err) {
    memset(g, 0, sizeof *g);
    g->scene = s;
    g->ctx = ctx;
    g->width = w;
    g->height = h;
    g->sun = sb_v3_norm(sun);
    glGenVertexArrays(1, &g->vao);
    glBindVertexArray(g->vao);
    glGenBuffers(1, &g->vbo);
    glGenBuffers(1, &g->ibo);
    glGenBuffers(1, &g->xform_buf);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g->ibo);   /* the VAO's element buffer */
    g->geom = sb_xcalloc(1, sizeof *g->geom);
    g->geom->first = sb_xcalloc(s->draw_count + 1, sizeof(uint32_t));
    g->geom->vbase = sb_xcalloc(s->draw_count + 1, sizeof(uint32_t));
    upload_geometry(g, SHARE_ALL);
    bool open_single_sided = false;
    for (uint32_t d = 0; d < s->draw_count; d++) open_single_sided |= !s->draws[d].double_sided && !s->draws[d].closed;
    if (open_single_sided) {
        g->facing = sb_xcalloc(1, sizeof *g->facing);
        g->facing->count = sb_xcalloc(s->draw_count, sizeof(uint32_t));
        facing_reset(g);
    }
    vertex_arrays(g);
    if (ctx && ctx->software) g->pieces = sb_xcalloc(1, sizeof *g->pieces);
    /* the targets, the alpha test's data, the z-pass, a moving scene's posing pass (handed the vertex buffer's
       numbering, which upload_geometry keeps current) */
    bool ok = render_targets(g, w, h, err) && upload_alpha(g, s, err) && zpass_programs(g, err) &&
              sb_pose_create(&g->pose, s, g->geom->vbase, err) && sb_gl_check("creating GPU resources", err);
    if (!ok) sb_gpu_free(g);
    return ok;
}

void sb_gpu_free(sb_gpu *g) {
    for (int a = 0; a < 2; a++)
        if (g->zpass_prog[a]) glDeleteProgram(g->zpass_prog[a]);
    if (g->fbo) glDeleteFramebuffers(1, &g->fbo);
    GLuint tex[] = {g->color_tex, g->vis_tex, g->depth_tex, g->pos_tex, g->aux_tex, g->base_tex};
    for (size_t i = 0; i < SB_COUNT(tex); i++) /* nothing to delete (nor a GL) when the session never opened */
        if (tex[i]) glDeleteTextures(1, &tex[i]);
    GLuint bufs[] = {g->vbo, g->color_buf, g->mask_buf, g->indirect_buf, g->xform_buf};
    for (size_t i = 0; i < SB_COUNT(bufs); i++)
        if (bufs[i]) glDeleteBuffers(1, &bufs[i]);
    if (g->ibo) glDeleteBuffers(1, &g->ibo);
    if (g->vao) glDeleteVertexArrays(1, &g->vao);
    if (g->mat_ssbo) glDeleteBuffers(1, &g->mat_ssbo);
    if (g->texel_buf) glDeleteBuffers(1, &g->texel_buf);
    if (g->texel_tex) glDeleteTextures(1, &g->texel_tex);
    sb_pose_free(g->pose);
    g->pose = NULL;
    if (g->pieces) {
        if (g->pieces->prev) glDeleteSync(g->pieces->prev);
        free(g->pieces);
        g->pieces = NULL;
    }
    if (g->facing) {
        free(g->facing->count);
        free(g->facing->indices);
        free(g->facing);
    }
    if (g->geom) {
        free(g->geom->first);
        free(g->geom->vbase);
        free(g->geom->orig);
        free(g->geom);
    }
    memset(g, 0, sizeof *g);
}

void sb_frame_setup(sb_frame *f, const sb_gpu *g, const sb_camera *cam) {
    memset(&f->counters, 0, sizeof f->counters);
    f->cmd_count = 0;
    f->gpu = g;
    f->cam = *cam;
    sb_v3 eye = sb_v3_sub(cam->pos, g->scene->origin);
    f->view = sb_m4_view(eye, cam->right, cam->up, cam->forward);
    f->proj = sb_m4_perspective(cam->fov_deg * SB_PI / 180, cam->aspect, cam->znear, cam->zfar);
    f->view_proj = sb_m4_mul(f->proj, f->view);
    sb_frustum_planes(f->view_proj, f->frustum);
    f->shade_light[0] = g->sun.x;
    f->shade_light[1] = g->sun.y;
    f->shade_light[2] = g->sun.z;
    f->shade_light[3] = 0;
}

void sb_frame_jitter(sb_frame *f, double jx, double jy) {
    /* clip x += ndc offset x w, and w = -z_view: the projection's z column takes the offset */
    f->proj.m[8] -= 2 * jx / f->gpu->width;
    f->proj.m[9] -= 2 * jy / f->gpu->height;
    f->view_proj = sb_m4_mul(f->proj, f->view);
    sb_frustum_planes(f->view_proj, f->frustum);
}

static void human_bytes(double b, char *out, size_t len) {
    if (b >= 1073741824.0) snprintf(out, len, "%.1f GiB", b / 1073741824.0);
    else snprintf(out, len, "%.0f MiB", b / 1048576.0);
}

bool sb_gpu_memory_fits(const sb_gpu *g, double bytes, const char *who, const char *what, sb_err *why) {
    char source[96];
    double free_bytes = sb_context_memory_free(g->ctx, source, sizeof source);
    if (free_bytes <= 0) return true;   /* unknown: a failed allocation then fails the run with the GL error */
    /* the camera targets: colour RGBA8, visibility R8, depth-stencil 32F+8, position and normal RGBA32F, base RGBA8 */
    double targets = (double)g->width * g->height * (4 + 1 + 8 + 16 + 16 + 4);
    if (bytes + targets <= free_bytes) return true;
    char need[32], have[32];
    human_bytes(bytes, need, sizeof need);
    human_bytes(free_bytes - targets > 0 ? free_bytes - targets : 0, have, sizeof have);
    return sb_fail(why, "%s: needs %s of %s, more than the %s %s (beside the camera targets)", who, need, what, have,
                   source);
}

bool sb_lamp_supported(const sb_gpu *g, int light, const char *technique, sb_err *why) {
    int k = 0;
    if (!sb_scene_point_light(g->scene, light, &k))
        return sb_fail(why, "%s:light=%d: the scene has %d point or spot light(s)", technique, light, k);
    return true;
}

bool sb_lamp_maps_fit(const sb_gpu *g, const char *technique, int res, double bytes, bool cube, sb_err *why) {
    GLint max = 0;
    glGetIntegerv(cube ? GL_MAX_CUBE_MAP_TEXTURE_SIZE : GL_MAX_TEXTURE_SIZE, &max);
    if (max > 0 && res > max)
        return sb_fail(why, "%s:res=%d exceeds %s %d of %s", technique, res,
                       cube ? "GL_MAX_CUBE_MAP_TEXTURE_SIZE" : "GL_MAX_TEXTURE_SIZE", max, g->ctx->renderer);
    char who[64];
    snprintf(who, sizeof who, "%s:res=%d", technique, res);
    return sb_gpu_memory_fits(g, bytes, who, "shadow maps", why);
}

void sb_frame_shade_point(sb_frame *f, sb_v3 pos) {
    f->shade_light[0] = pos.x;
    f->shade_light[1] = pos.y;
    f->shade_light[2] = pos.z;
    f->shade_light[3] = 1;
}

/* The frame's spot cone from a lamp (none for a point light or NULL, the sun). */
static void shade_spot(sb_frame *f, const sb_light *lamp) {
    bool spot = lamp && lamp->type == SB_LIGHT_SPOT && lamp->cone > 0;
    f->shade_spot[0] = spot ? lamp->direction.x : 0, f->shade_spot[1] = spot ? lamp->direction.y : 0;
    f->shade_spot[2] = spot ? lamp->direction.z : 0, f->shade_spot[3] = spot ? 1 - cos(lamp->cone) : 0;
}

void sb_frame_shade_lamp(sb_frame *f, const sb_light *lamp) {
    sb_frame_shade_point(f, lamp->position);
    f->shade_range = lamp->range > 0 ? lamp->range : 0;
    shade_spot(f, lamp);
}

void sb_frame_shade_light_of(sb_frame *f, int idx) {
    const sb_gpu *g = f->gpu;
    if (idx != SB_LIGHT_SUN) {
        sb_frame_shade_lamp(f, sb_scene_point_light(g->scene, idx, NULL));
        return;
    }
    f->shade_light[0] = g->sun.x, f->shade_light[1] = g->sun.y, f->shade_light[2] = g->sun.z, f->shade_light[3] = 0;
    f->shade_range = 0;
    shade_spot(f, NULL);
}

void sb_stage_begin(sb_frame *f, const sb_stage_def *s) {
    int slot = sb_stage_slot(s);
    if (slot < 0) {
        fprintf(stderr, "shadowbench: stage '%s' is timed but declared by no technique (sb_technique.stages)\n", s->name);
        abort();
    }
    f->stage = s;
    f->stage_slot = slot;
    sb_timer_stage_begin(f->timer, slot);
}
void sb_stage_end(sb_frame *f, const sb_stage_def *s) {
    sb_submit_flush(f);
    sb_timer_stage_end(f->timer, f->stage == s ? f->stage_slot : sb_stage_slot(s));
}

static bool shadow_stage(const sb_frame *f) { return f->stage && f->stage->shadow; }

/* A draw (what the GPU draws: a mesh range, its instances) and an API call are counted apart: with
   --submit indirect one call issues a pass's draws. */
static void count_draws(sb_frame *f, uint64_t triangles, int instances) {
    uint64_t tris = triangles * (uint64_t)(instances > 1 ? instances : 1);
    f->counters.draw_calls++;
    f->counters.stage_draw_calls[f->stage_slot]++;
    f->counters.triangles += tris;
    if (shadow_stage(f)) {
        f->counters.shadow_draw_calls++;
        f->counters.shadow_triangles += tris;
    }
}

static void count_api_call(sb_frame *f) {
    f->counters.api_calls++;
    f->counters.shadow_api_calls += shadow_stage(f);
}

void sb_submit(sb_frame *f, uint32_t d, int instances) {
    const sb_draw *dr = &f->gpu->scene->draws[d];
    uint32_t tris = shadow_stage(f) ? shadow_triangles(f->gpu, d, f->shade_light) : dr->index_count / 3;
    if (tris == 0) return;
    GLsizei n = instances > 1 ? instances : 1;
    count_draws(f, tris, instances);
    if (f->gpu->indirect) {   /* count, instances, first index, base vertex, base instance */
        uint32_t *c = f->cmds + 5 * (size_t)f->cmd_count++;
        c[0] = 3 * tris, c[1] = (uint32_t)n, c[2] = f->gpu->geom->first[d], c[3] = 0, c[4] = d;
        return;
    }
    const void *offset = (const void *)((size_t)f->gpu->geom->first[d] * sizeof(uint32_t));
    glDrawElementsInstancedBaseInstance(GL_TRIANGLES, (GLsizei)(3 * tris), GL_UNSIGNED_INT, offset, n, d);
    count_api_call(f);
    pieces_submitted(f->gpu, (uint64_t)tris * (uint64_t)n);
}

void sb_submit_flush(sb_frame *f) {
    if (!f->cmd_count) return;
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, f->gpu->indirect_buf);
    /* a fresh store each flush: the commands of a draw still in flight are not overwritten (no wait) */
    glBufferData(GL_DRAW_INDIRECT_BUFFER, (GLsizeiptr)(20 * (size_t)f->cmd_count), f->cmds, GL_STREAM_DRAW);
    /* one call for the pass; on a software rasterizer one a piece (its commands' triangles up to the piece's size),
       each followed by its fence */
    for (uint32_t k = 0, end; k < f->cmd_count; k = end) {
        uint64_t tris = 0;   /* a command's vertex count over 3, times its instances */
        for (end = k; end < f->cmd_count && (end == k || !f->gpu->pieces || tris < SB_SOFT_PIECE_TRIS); end++)
            tris += (uint64_t)f->cmds[5 * end] / 3 * f->cmds[5 * end + 1];
        glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT, (const void *)(20 * (size_t)k), (GLsizei)(end - k), 0);
        count_api_call(f);
        pieces_submitted(f->gpu, tris);
    }
    f->cmd_count = 0;
}

void sb_set_draw_masks(const sb_frame *f, const uint8_t *masks) {
    const sb_gpu *g = f->gpu;
    glBindBuffer(GL_ARRAY_BUFFER, g->mask_buf);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(g->scene->draw_count + 4), NULL, GL_STREAM_DRAW);   /* orphaned */
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)g->scene->draw_count, masks);
}

/* A camera pass's draw: back faces culled unless the material is double-sided
 * (*culling: the GL state, changed only when the next draw needs the other; the
 * draws collected before it are issued first). */
static void camera_submit(sb_frame *f, uint32_t d, bool *culling) {
    bool want = !f->gpu->scene->draws[d].double_sided;
    if (want != *culling) {
        sb_submit_flush(f);
        if (want) glEnable(GL_CULL_FACE);
        else glDisable(GL_CULL_FACE);
        *culling = want;
    }
    sb_submit(f, d, 1);
}

void sb_count_draw(sb_frame *f, uint64_t triangles, int instances) {
    count_draws(f, triangles, instances);
    count_api_call(f);
}

void sb_set_camera_uniforms(const sb_frame *f, GLint u_view, GLint u_proj) {
    float m[16];
    sb_m4_to_float(f->view, m);
    glUniformMatrix4fv(u_view, 1, GL_FALSE, m);
    sb_m4_to_float(f->proj, m);
    glUniformMatrix4fv(u_proj, 1, GL_FALSE, m);
}

/* The camera's render target with depth testing and back-face culling. */
void sb_shadow_depth_state(float slope) {
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    if (slope != 0) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(slope, 0.0f);
    }
}

static void bind_camera_target(const sb_gpu *g, GLenum depth_func, bool depth_write) {
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
    glViewport(0, 0, g->width, g->height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(depth_func);
    glDepthMask(depth_write ? GL_TRUE : GL_FALSE);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
}

sb_v3 sb_frame_eye(const sb_frame *f) {
    return f->look ? f->look->eye : sb_v3_sub(f->cam.pos, f->gpu->scene->origin);
}

void sb_zpass(sb_frame *f) {
    const sb_gpu *g = f->gpu;
    f->look_depth = false;   /* the frame's own camera: a look's pass cannot reuse it */
    bind_camera_target(g, GL_LESS, true);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glStencilMask(0xff);
    glClearStencil(0);
    glClear(GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    glBindVertexArray(g->vao);
    uint32_t n = sb_scene_collect(g->scene, (const double(*)[4])f->frustum, 6, f->scratch);
    bool culling = true;
    for (int a = 0; a < 2 && g->zpass_prog[a]; a++) {   /* opaque draws, then the alpha-tested ones */
        glUseProgram(g->zpass_prog[a]);
        sb_set_camera_uniforms(f, g->zpass_u_view[a], g->zpass_u_proj[a]);
        for (uint32_t i = 0; i < n; i++)
            if (sb_draw_variant(g, f->scratch[i]) == a) camera_submit(f, f->scratch[i], &culling);
        sb_submit_flush(f);
    }
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDisable(GL_CULL_FACE);
}

/* Timed frames draw colour alone; the evaluation pass all five targets. */
static void final_targets(const sb_frame *f, GLenum depth_func, bool depth_write) {
    bind_camera_target(f->gpu, depth_func, depth_write);
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2, GL_COLOR_ATTACHMENT3,
                           GL_COLOR_ATTACHMENT4};
    glDrawBuffers(f->eval ? 5 : 1, bufs);
}

static void draw_scene(sb_frame *f, const sb_final_prog *fp, GLenum depth_func, bool depth_write);

/* Clears the targets (and depth, unless it is reused) and draws the scene. */
static void camera_pass(sb_frame *f, const sb_final_prog *fp, GLenum depth_func, bool depth_write, bool clear_depth) {
    final_targets(f, depth_func, depth_write);
    const float sky[4] = {0.55f, 0.7f, 0.9f, 1.0f}, one[4] = {1, 1, 1, 1}, none[4] = {0, 0, 0, -1};
    glClearBufferfv(GL_COLOR, 0, sky);
    if (f->eval) {
        glClearBufferfv(GL_COLOR, 1, one);
        glClearBufferfv(GL_COLOR, 2, none);
        glClearBufferfv(GL_COLOR, 3, none);
        glClearBufferfv(GL_COLOR, 4, sky);   /* the sky's colour, N.L 1: unshadowed by anything */
    }
    if (clear_depth) glClear(GL_DEPTH_BUFFER_BIT);
    draw_scene(f, fp, depth_func, depth_write);
}

void sb_final_pass(sb_frame *f, const sb_final_prog *fp, bool reuse_depth) {
    if (f->look && !f->look_depth) reuse_depth = false;
    camera_pass(f, fp, reuse_depth ? GL_LEQUAL : GL_LESS, !reuse_depth, !reuse_depth);
}

void sb_gbuffer_pass(sb_frame *f, const sb_final_prog *fp) {
    camera_pass(f, fp, GL_LEQUAL, true, true);
    f->look_depth = f->look != NULL;
}

void sb_final_pass_add(sb_frame *f, const sb_final_prog *fp) {
    f->shade_add = true;
    glEnablei(GL_BLEND, 0);
    glBlendFunci(0, GL_ONE, GL_ONE);
    sb_final_draw(f, fp, true);
    glDisablei(GL_BLEND, 0);
    f->shade_add = false;
}

void sb_final_draw(sb_frame *f, const sb_final_prog *fp, bool reuse_depth) {
    if (f->look && !f->look_depth) reuse_depth = false;
    draw_scene(f, fp, reuse_depth ? GL_LEQUAL : GL_LESS, !reuse_depth);
}

static void draw_scene(sb_frame *f, const sb_final_prog *fp, GLenum depth_func, bool depth_write) {
    const sb_gpu *g = f->gpu;
    final_targets(f, depth_func, depth_write);
    glBindVertexArray(g->vao);
    double planes[12][4];
    memcpy(planes, f->look ? f->look->frustum : f->frustum, sizeof(double[6][4]));
    memcpy(planes + 6, f->pass_box, sizeof f->pass_box);
    uint32_t n = sb_scene_collect(g->scene, (const double(*)[4])planes, 6 + f->pass_box_count, f->scratch);
    bool culling = true;
    float depth_view[16];
    sb_m4_to_float(f->view, depth_view);
    /* opaque draws first, with the variant without the alpha test; then the alpha-tested ones */
    for (int a = 0; a < 2 && fp->v[a].prog; a++) {
        const sb_final_variant *v = &fp->v[2 * f->eval + a];
        uint32_t count = 0;
        for (uint32_t i = 0; i < n; i++) count += sb_draw_variant(g, f->scratch[i]) == a;
        if (!count) continue;
        /* the technique set its uniforms on v[0] */
        if (v != &fp->v[0]) sb_gl_links_copy(&v->from_timed, fp->prog, v->prog);
        glUseProgram(v->prog);
        if (f->look) {
            float m[16];
            sb_m4_to_float(f->look->view, m);
            glUniformMatrix4fv(v->u_view, 1, GL_FALSE, m);
            sb_m4_to_float(f->look->proj, m);
            glUniformMatrix4fv(v->u_proj, 1, GL_FALSE, m);
        } else {
            sb_set_camera_uniforms(f, v->u_view, v->u_proj);
        }
        if (v->u_depth_view >= 0) glUniformMatrix4fv(v->u_depth_view, 1, GL_FALSE, depth_view);
        glUniform4f(v->u_light, (float)f->shade_light[0], (float)f->shade_light[1], (float)f->shade_light[2],
                    (float)f->shade_light[3]);
        if (v->u_more >= 0) glUniform2f(v->u_more, (float)f->shade_range, f->shade_add ? 1.0f : 0.0f);
        if (v->u_spot >= 0)
            glUniform4f(v->u_spot, (float)f->shade_spot[0], (float)f->shade_spot[1], (float)f->shade_spot[2],
                        (float)f->shade_spot[3]);
        for (uint32_t i = 0; i < n; i++)
            if (sb_draw_variant(g, f->scratch[i]) == a) camera_submit(f, f->scratch[i], &culling);
        sb_submit_flush(f);
    }
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
}

void sb_gpu_readback(const sb_gpu *g, float *depth, unsigned char *vis, unsigned char *rgba) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, g->fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    if (depth) glReadPixels(0, 0, g->width, g->height, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    if (vis) {
        glReadBuffer(GL_COLOR_ATTACHMENT1);
        glReadPixels(0, 0, g->width, g->height, GL_RED, GL_UNSIGNED_BYTE, vis);
    }
    if (rgba) {
        glReadBuffer(GL_COLOR_ATTACHMENT0);
        glReadPixels(0, 0, g->width, g->height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    }
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
}

sb_v3 sb_frame_unproject(const sb_frame *f, double x, double y, double d) {
    sb_m4 inv;
    if (!sb_m4_invert(f->view_proj, &inv)) return sb_v3_make(NAN, NAN, NAN);
    sb_v3 ndc = sb_v3_make(2 * (x + 0.5) / f->gpu->width - 1, 2 * (y + 0.5) / f->gpu->height - 1, 2 * d - 1);
    return sb_v3_add(sb_m4_point(inv, ndc), f->gpu->scene->origin);
}

void sb_gpu_readback_base(const sb_gpu *g, unsigned char *rgba) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, g->fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT4);
    glReadPixels(0, 0, g->width, g->height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
}

void sb_gpu_readback_eval(const sb_gpu *g, float *pos, float *aux) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, g->fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    if (pos) {
        glReadBuffer(GL_COLOR_ATTACHMENT2);
        glReadPixels(0, 0, g->width, g->height, GL_RGBA, GL_FLOAT, pos);
    }
    if (aux) {
        glReadBuffer(GL_COLOR_ATTACHMENT3);
        glReadPixels(0, 0, g->width, g->height, GL_RGBA, GL_FLOAT, aux);
    }
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
}

void sb_final_pass_stencil(sb_frame *f, const sb_final_prog *fp, GLint u_lit, GLuint mask) {
    if (f->look) f->look_failed = true;   /* the stencil holds the frame's own view's shadows */
    glEnable(GL_STENCIL_TEST);
    glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
    glStencilFunc(GL_EQUAL, 0, mask);
    glUseProgram(fp->prog);
    glUniform1f(u_lit, 1.0f);
    sb_final_pass(f, fp, true);     /* clears colour, keeps depth and stencil */
    glStencilFunc(GL_NOTEQUAL, 0, mask);
    glUseProgram(fp->prog);
    glUniform1f(u_lit, 0.0f);
    sb_final_draw(f, fp, true);     /* the same draws again, without clearing */
    glDisable(GL_STENCIL_TEST);
}

bool sb_frame_moved_meets(const sb_frame *f, bool (*meets)(const sb_aabb *box, const void *region), const void *region) {
    const sb_scene *s = f->gpu->scene;
    for (uint32_t i = 0; i < f->moved_count; i++)
        if (meets(&f->moved_from[i], region) || meets(&s->draws[f->moved[i]].box, region)) return true;
    return false;
}
