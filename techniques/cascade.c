/* cascade.c - shared cascade machinery (see cascade.h). */
#include "cascade.h"

#include <stdlib.h>
#include <string.h>

#include "shaders.h"

void sb_split_distances(double lambda, int m, double n, double f, double *out) {
    out[0] = n;
    for (int i = 1; i < m; i++) {
        double lg = n * pow(f / n, (double)i / m);
        double un = n + (f - n) * i / m;
        out[i] = lambda * lg + (1 - lambda) * un;
    }
    out[m] = f;
}

static bool has_param(const sb_params *p, const char *name) { return !isnan(sb_param_num(p, name)); }

bool sb_csm_create(sb_csm *c, sb_gpu *g, const sb_params *p, const char *name, sb_err *err) {
    return sb_csm_create_desc(c, g, p, name, &(sb_csm_desc){0}, err);
}

bool sb_csm_create_desc(sb_csm *c, sb_gpu *g, const sb_params *p, const char *name, const sb_csm_desc *desc,
                        sb_err *err) {
    memset(c, 0, sizeof *c);
    c->gpu = g;
    c->res = (int)sb_param_num(p, "res");
    c->count = desc->maps ? desc->maps : has_param(p, "cascades") ? (int)sb_param_num(p, "cascades") : 1;
    c->filter = sb_param_choice(p, "filter");
    c->select = desc->select_map ? 1 : has_param(p, "select") ? sb_param_choice(p, "select") : 0;
    c->blend = has_param(p, "blend") ? sb_param_num(p, "blend") : 0;
    c->stable = sb_param_choice(p, "stable") == 1;
    c->warp = has_param(p, "warp") ? sb_param_choice(p, "warp") : 0;
    c->min_angle = has_param(p, "min_angle") ? sb_param_num(p, "min_angle") : 5;
    c->focus = has_param(p, "focus") ? sb_param_num(p, "focus") : 0.3;
    c->format = sb_param_choice(p, "format");
    c->blur = (int)sb_param_num(p, "blur");
    c->bleed = sb_param_num(p, "bleed");
    c->exponent = sb_param_num(p, "exponent");
    if (c->warp && c->stable)
        return sb_fail(err, "%s: stable=on cannot be combined with a perspective warp (a warped map follows the camera)",
                       name);
    c->bias = sb_param_num(p, "bias");
    c->slope = sb_param_num(p, "slope");
    c->normal = sb_param_num(p, "normal");
    c->sun_size = sb_param_num(p, "sun_size");
    int depth = sb_param_choice(p, "depth");
    c->depth_format = depth == 0 ? GL_DEPTH_COMPONENT16 : depth == 1 ? GL_DEPTH_COMPONENT24 : GL_DEPTH_COMPONENT32F;
    int layered = has_param(p, "layered") ? sb_param_choice(p, "layered") : 0;
    const sb_context *ctx = g->ctx;
    if (layered == 3) layered = ctx->has_vs_layer ? SB_LAYERED_VS : SB_LAYERED_GS; /* on: the best available */
    if (layered == SB_LAYERED_VS && !ctx->has_vs_layer)
        return sb_fail(err, "%s:layered=vs needs GL_ARB_shader_viewport_layer_array, which %s lacks", name,
                       ctx->renderer);
    c->layered = layered;
    GLint max_size = 0, max_layers = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    if (c->res > max_size) return sb_fail(err, "%s:res=%d exceeds GL_MAX_TEXTURE_SIZE %d", name, c->res, max_size);
    c->mask = calloc(g->scene->draw_count + 1, 1);

    bool bilinear = !(c->filter == 0 || c->filter == 2 || c->filter == 3); /* hw compare, poisson, pcss taps */
    c->tex = sb_shadow_texture(GL_TEXTURE_2D_ARRAY, c->depth_format, c->res, c->count, bilinear);
    if (c->format) { /* filtered formats: moments beside the depth the rasterizer tests with */
        GLuint m[2];
        glGenTextures(2, m);
        c->moments = m[0];
        c->moments_tmp = m[1];
        for (int i = 0; i < 2; i++) {
            glBindTexture(GL_TEXTURE_2D_ARRAY, m[i]);
            glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_RGBA32F, c->res, c->res, c->count);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        }
    }
    glGenFramebuffers(1, &c->fbo_all);
    glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_all);
    glFramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, c->tex, 0);
    if (c->format) glFramebufferTexture(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, c->moments, 0);
    glDrawBuffer(c->format ? GL_COLOR_ATTACHMENT0 : GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return sb_fail(err, "%s:res=%d:cascades=%d: layered shadow framebuffer is incomplete", name, c->res, c->count);
    glGenFramebuffers(c->count, c->fbo_layer);
    for (int k = 0; k < c->count; k++) {
        glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_layer[k]);
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, c->tex, 0, k);
        if (c->format) glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, c->moments, 0, k);
        glDrawBuffer(c->format ? GL_COLOR_ATTACHMENT0 : GL_NONE);
        glReadBuffer(GL_NONE);
    }
    glGenBuffers(1, &c->block);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, c->block);
    glBufferData(GL_SHADER_STORAGE_BUFFER, sizeof(sb_cascade_block), NULL, GL_DYNAMIC_DRAW);

    const char *fs_depth[] = {c->format ? sb_shader_moments_frag : sb_shader_depth_frag};
    char fmt_define[64];
    snprintf(fmt_define, sizeof fmt_define, "#define SB_FORMAT %d\n", c->format);
    const char *vs_cascade[] = {sb_shader_csm_block_glsl, sb_shader_csm_depth_vert};
    const sb_shader_src per[] = {{GL_VERTEX_SHADER, vs_cascade, 2}, {GL_FRAGMENT_SHADER, fs_depth, 1}};
    c->prog_cascade = sb_gpu_link("cascade depth", fmt_define, per, 2, err);
    if (!c->prog_cascade) return false;
    c->u_cascade = glGetUniformLocation(c->prog_cascade, "u_cascade");
    if (c->layered == SB_LAYERED_GS) {
        const char *vs[] = {sb_shader_csm_layer_gs_vert};
        const char *gs[] = {sb_shader_csm_block_glsl, sb_shader_csm_layer_geom};
        const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 1}, {GL_GEOMETRY_SHADER, gs, 2},
                                    {GL_FRAGMENT_SHADER, fs_depth, 1}};
        c->prog_gs = sb_gpu_link("layered (geometry shader)", fmt_define, st, 3, err);
        if (!c->prog_gs) return false;
        c->u_mask_gs = glGetUniformLocation(c->prog_gs, "u_mask");
    } else if (c->layered == SB_LAYERED_VS) {
        const char *vs[] = {sb_shader_csm_block_glsl, sb_shader_csm_layer_vs_vert};
        const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 2}, {GL_FRAGMENT_SHADER, fs_depth, 1}};
        char defs[160];
        snprintf(defs, sizeof defs, "#extension GL_ARB_shader_viewport_layer_array : require\n%s", fmt_define);
        c->prog_vs = sb_gpu_link("layered (vertex shader)", defs, st, 2, err);
        if (!c->prog_vs) return false;
        c->u_mask_vs = glGetUniformLocation(c->prog_vs, "u_mask");
    }
    GLuint progs3[3] = {c->prog_cascade, c->prog_gs, c->prog_vs};
    for (int i = 0; i < 3; i++) c->d_exponent[i] = progs3[i] ? glGetUniformLocation(progs3[i], "u_exponent") : -1;
    if (c->format && c->blur > 0) {
        const char *cs[] = {sb_shader_blur_comp};
        const sb_shader_src st[] = {{GL_COMPUTE_SHADER, cs, 1}};
        c->blur_prog = sb_gpu_link("moments blur", NULL, st, 1, err);
        if (!c->blur_prog) return false;
        c->b_dir = glGetUniformLocation(c->blur_prog, "u_dir");
        c->b_radius = glGetUniformLocation(c->blur_prog, "u_radius");
        c->b_layer = glGetUniformLocation(c->blur_prog, "u_layer");
    }
    char defines[128];
    snprintf(defines, sizeof defines, "#define SB_FILTER %d\n#define SB_SELECT %d\n#define SB_FORMAT %d\n", c->filter,
             c->select, c->format);
    char vis[16384];
    snprintf(vis, sizeof vis, "%s%s", sb_shader_csm_block_glsl, sb_shader_vis_csm_glsl);
    if (!sb_final_prog_create(&c->fp, name, vis, defines, err)) return false;
    c->u_shadow = glGetUniformLocation(c->fp.prog, "u_shadow");
    c->u_bias = glGetUniformLocation(c->fp.prog, "u_bias");
    c->u_normal = glGetUniformLocation(c->fp.prog, "u_normal");
    c->u_blend = glGetUniformLocation(c->fp.prog, "u_blend");
    c->u_light = glGetUniformLocation(c->fp.prog, "u_light");
    c->u_texel = glGetUniformLocation(c->fp.prog, "u_texel");
    c->u_depth_raw = glGetUniformLocation(c->fp.prog, "u_depth_raw");
    c->u_moments = glGetUniformLocation(c->fp.prog, "u_moments");
    c->u_bleed = glGetUniformLocation(c->fp.prog, "u_bleed");
    c->u_exponent = glGetUniformLocation(c->fp.prog, "u_exponent");
    c->u_sun_tan = glGetUniformLocation(c->fp.prog, "u_sun_tan");
    glGenSamplers(1, &c->raw_sampler);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_COMPARE_MODE, GL_NONE);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return sb_gl_check(name, err);
}

void sb_csm_destroy(sb_csm *c) {
    sb_final_prog_free(&c->fp);
    GLuint progs[] = {c->prog_cascade, c->prog_gs, c->prog_vs};
    for (size_t i = 0; i < SB_COUNT(progs); i++)
        if (progs[i]) glDeleteProgram(progs[i]);
    if (c->fbo_all) glDeleteFramebuffers(1, &c->fbo_all);
    if (c->fbo_layer[0]) glDeleteFramebuffers(c->count, c->fbo_layer);
    if (c->tex) glDeleteTextures(1, &c->tex);
    if (c->block) glDeleteBuffers(1, &c->block);
    if (c->raw_sampler) glDeleteSamplers(1, &c->raw_sampler);
    if (c->blur_prog) glDeleteProgram(c->blur_prog);
    GLuint m[2] = {c->moments, c->moments_tmp};
    if (c->moments) glDeleteTextures(2, m);
    free(c->mask);
    memset(c, 0, sizeof *c);
}

void sb_csm_fit_slice(const sb_csm *c, const sb_frame *f, double zn, double zf, sb_light_fit *out) {
    const sb_scene *s = f->gpu->scene;
    /* only the part of the slice where the scene can be: a far plane far beyond
       the scene must not spread a (stable, sphere-fitted) map over empty space */
    sb_v3 eye = sb_v3_sub(f->cam.pos, s->origin);
    double dmin = 1e300, dmax = -1e300;
    for (int k = 0; k < 8; k++) {
        sb_v3 q = sb_v3_make(k & 1 ? s->bounds.hi.x : s->bounds.lo.x, k & 2 ? s->bounds.hi.y : s->bounds.lo.y,
                             k & 4 ? s->bounds.hi.z : s->bounds.lo.z);
        double d = sb_v3_dot(sb_v3_sub(q, eye), f->cam.forward);
        dmin = fmin(dmin, d);
        dmax = fmax(dmax, d);
    }
    if (dmax > zn && dmin < zf) {
        zn = fmax(zn, dmin);
        zf = fmin(zf, dmax);
    }
    sb_v3 corners[8];
    sb_frustum_corners(&f->cam, s->origin, zn, zf, corners);
    if (c->warp == 1) sb_light_fit_lispsm(s, f->gpu->sun, eye, f->cam.forward, zn, zf, corners, 8, c->res, c->min_angle, out);
    else if (c->warp == 2) sb_light_fit_tsm(s, f->gpu->sun, corners, c->res, c->focus, out);
    else if (c->stable) sb_light_fit_stable(s, f->gpu->sun, corners, 8, c->res, out);
    else sb_light_fit_points(s, f->gpu->sun, corners, 8, c->res, out);
}

/* Is any draw (a receiver) inside the camera frustum between view depths zn and zf? */
static bool slice_has_receivers(const sb_frame *f, double zn, double zf) {
    double planes[6][4];
    memcpy(planes, f->frustum, sizeof planes);
    /* replace near/far (4, 5) with the slice's planes: forward·(p - eye) in [zn, zf] */
    sb_v3 eye = sb_v3_sub(f->cam.pos, f->gpu->scene->origin), fw = f->cam.forward;
    double d = sb_v3_dot(fw, eye);
    planes[4][0] = fw.x; planes[4][1] = fw.y; planes[4][2] = fw.z; planes[4][3] = -d - zn;
    planes[5][0] = -fw.x; planes[5][1] = -fw.y; planes[5][2] = -fw.z; planes[5][3] = d + zf;
    return sb_bvh_collect(f->gpu->scene, (const double(*)[4])planes, 6, f->gpu->scratch) > 0;
}

static void block_put(sb_csm *c, int k, const sb_light_fit *fit, double zn, double zf, bool active) {
    sb_m4_to_float(fit->view_proj, c->cpu.light_vp[k]);
    sb_m4_to_float(fit->shadow_mat, c->cpu.shadow_mat[k]);
    c->cpu.cascade[k][0] = (float)zn;
    c->cpu.cascade[k][1] = (float)zf;
    c->cpu.cascade[k][2] = (float)fit->texel_world;
    c->cpu.cascade[k][3] = (float)(fit->zf - fit->zn);
    c->cpu.flags[k][0] = active ? 1.0f : 0.0f;
    c->cpu.flags[k][1] = fit->warped ? 1.0f : 0.0f;
}

void sb_csm_upload(sb_csm *c, const double *zn, const double *zf) {
    memset(&c->cpu, 0, sizeof c->cpu);
    c->cpu.info[0] = (float)c->count;
    for (int k = 0; k < c->count; k++) block_put(c, k, &c->fit[k], zn[k], zf[k], c->active[k]);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, c->block);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof c->cpu, &c->cpu);
}

void sb_csm_fit(sb_csm *c, sb_frame *f, const double *splits) {
    for (int k = 0; k <= c->count; k++) c->splits[k] = splits[k];
    f->counters.split_count = c->count;
    for (int k = 0; k < c->count; k++) {
        double zn = splits[k], zf = splits[k + 1];
        f->counters.splits[k] = zf;
        c->active[k] = zf > zn && slice_has_receivers(f, zn, zf);
        if (c->active[k]) sb_csm_fit_slice(c, f, zn, zf, &c->fit[k]);
        else memset(&c->fit[k], 0, sizeof c->fit[k]);
        f->counters.warp_fallbacks += c->warp && c->active[k] && !c->fit[k].warped;
    }
    sb_csm_upload(c, splits, splits + 1);
}

uint32_t sb_csm_cull(sb_csm *c, sb_frame *f, const sb_light_fit *bound) {
    const sb_scene *s = f->gpu->scene;
    memset(c->mask, 0, s->draw_count);
    uint32_t *list = f->gpu->scratch;
    for (int k = 0; k < c->count; k++) {
        if (!bound && !c->active[k]) continue;
        const sb_light_fit *fit = bound ? bound : &c->fit[k];
        uint32_t n = sb_bvh_collect(s, (const double(*)[4])fit->planes, 6, list);
        for (uint32_t i = 0; i < n; i++) c->mask[list[i]] |= (uint8_t)(1u << k);
    }
    uint32_t casters = 0;
    for (uint32_t d = 0; d < s->draw_count; d++) casters += c->mask[d] != 0;
    return casters;
}

static int popcount8(unsigned m) {
    int n = 0;
    for (; m; m &= m - 1) n++;
    return n;
}

void sb_csm_render(sb_csm *c, sb_frame *f) {
    sb_gpu *g = f->gpu;
    const sb_scene *s = g->scene;
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, c->block);
    glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_all);
    glViewport(0, 0, c->res, c->res);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    if (c->format) { /* moments of the far plane: nothing occludes */
        const float z = 1.0f, e = (float)exp(c->exponent);
        const float far[4] = {c->format == 2 ? e : z, z, z, z};
        glClearBufferfv(GL_COLOR, 0, far);
    }
    glClear(GL_DEPTH_BUFFER_BIT);   /* every layer */
    if (!c->no_clamp) glEnable(GL_DEPTH_CLAMP);   /* casters toward the light stay, at depth 0 */
    if (c->slope > 0) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset((float)(c->slope * g->test_bias_sign), 0.0f);
    }
    glBindVertexArray(g->vao);
    GLuint progs3[3] = {c->prog_cascade, c->prog_gs, c->prog_vs};
    for (int i = 0; i < 3; i++)
        if (progs3[i] && c->d_exponent[i] >= 0) {
            glUseProgram(progs3[i]);
            glUniform1f(c->d_exponent[i], (float)c->exponent);
        }
    int rendered = 0;
    for (int k = 0; k < c->count; k++) rendered += c->active[k];
    f->counters.cascades_rendered = rendered;
    f->counters.cascades_skipped = c->count - rendered;
    if (c->layered == SB_LAYERED_OFF) {
        glUseProgram(c->prog_cascade);
        for (int k = 0; k < c->count; k++) {
            if (!c->active[k]) continue;
            glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_layer[k]);
            glUniform1i(c->u_cascade, k);
            for (uint32_t d = 0; d < s->draw_count; d++)
                if (c->mask[d] & (1u << k)) sb_submit(f, d, 1);
        }
    } else {
        bool gs = c->layered == SB_LAYERED_GS;
        glUseProgram(gs ? c->prog_gs : c->prog_vs);
        GLint u_mask = gs ? c->u_mask_gs : c->u_mask_vs;
        for (uint32_t d = 0; d < s->draw_count; d++) {
            unsigned m = c->mask[d];
            if (!m) continue;
            glUniform1ui(u_mask, m);
            sb_submit(f, d, gs ? 1 : popcount8(m));
        }
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    if (c->format && c->blur > 0) { /* separable Gaussian per rendered layer: moments -> tmp -> moments */
        glUseProgram(c->blur_prog);
        glUniform1i(c->b_radius, c->blur);
        for (int k = 0; k < c->count; k++) {
            if (!c->active[k]) continue;
            glUniform1i(c->b_layer, k);
            for (int pass = 0; pass < 2; pass++) {
                glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
                glBindImageTexture(0, pass ? c->moments_tmp : c->moments, 0, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
                glBindImageTexture(1, pass ? c->moments : c->moments_tmp, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
                glUniform2i(c->b_dir, pass ? 0 : 1, pass ? 1 : 0);
                glDispatchCompute((GLuint)(c->res + 15) / 16, (GLuint)(c->res + 15) / 16, 1);
            }
        }
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    }
}

void sb_csm_frame(sb_csm *c, sb_frame *f, const double *splits) {
    sb_csm_fit(c, f, splits);
    sb_csm_draw(c, f);
}

void sb_csm_draw(sb_csm *c, sb_frame *f) {
    sb_stage_begin(f, SB_STAGE_CASCADE);
    sb_csm_cull(c, f, NULL);
    sb_csm_render(c, f);
    sb_stage_end(f, SB_STAGE_CASCADE);
    sb_stage_begin(f, SB_STAGE_FINAL);
    sb_csm_final(c, f, false);
    sb_stage_end(f, SB_STAGE_FINAL);
}

void sb_csm_final(sb_csm *c, sb_frame *f, bool reuse_depth) {
    sb_gpu *g = f->gpu;
    glUseProgram(c->fp.prog);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, c->block);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, c->tex);
    glUniform1i(c->u_shadow, 0);
    glUniform1f(c->u_bias, (float)(g->test_bias_sign * c->bias));
    glUniform1f(c->u_normal, (float)(g->test_bias_sign * c->normal));
    glUniform1f(c->u_blend, (float)c->blend);
    glUniform3f(c->u_light, (float)g->sun.x, (float)g->sun.y, (float)g->sun.z);
    glUniform2f(c->u_texel, 1.0f / c->res, 1.0f / c->res);
    /* the same texture on unit 2 through a sampler without comparison */
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D_ARRAY, c->tex);
    glBindSampler(2, c->raw_sampler);
    glUniform1i(c->u_depth_raw, 2);
    glUniform1f(c->u_sun_tan, (float)tan(c->sun_size * SB_PI / 180));
    if (c->format) {
        glActiveTexture(GL_TEXTURE3);
        glBindTexture(GL_TEXTURE_2D_ARRAY, c->moments);
        glUniform1i(c->u_moments, 3);
        glUniform1f(c->u_bleed, (float)c->bleed);
        glUniform1f(c->u_exponent, (float)c->exponent);
    }
    glActiveTexture(GL_TEXTURE0);
    sb_final_pass(f, &c->fp, reuse_depth);
    glBindSampler(2, 0);
}
