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

const sb_counter_def sb_csm_counters[SB_CSM_COUNTER_COUNT] = {
    {.name = "cascades_invalidated", .unit = "count", .stats = SB_STAT_MEAN, .moving = true,
     .doc = "cache=on: kept shadow maps drawn again because a moved caster's box, before or after the move, overlaps "
            "their light volume (empty: nothing moves, or no cascades)"},
};

bool sb_csm_fits_receivers(const sb_csm_desc *d) {
    return d->fit == SB_FIT_RECEIVERS || (d->fit == SB_FIT_AUTO && !d->stable && d->warp != SB_WARP_TSM);
}

bool sb_csm_check(const sb_csm_desc *d, const char *name, sb_err *err) {
    if (d->warp && d->stable)
        return sb_fail(err, "%sstable=on cannot be combined with a perspective warp (a warped map follows the camera)",
                       name);
    if (d->fit == SB_FIT_RECEIVERS && (d->warp == SB_WARP_TSM || d->stable))
        return sb_fail(err, "%sfit=receivers cannot be combined with %s", name,
                       d->stable ? "stable=on (the sphere is the fit)" : "warp=tsm (its trapezoid is the fit)");
    if (d->warp && d->filter == SB_FILTER_PCSS)   /* measured: docs/techniques.md, the conformance sweep */
        return sb_fail(err, "%sfilter=pcss cannot be combined with a perspective warp (its blocker search and penumbra "
                            "width read depths and texel sizes that the warp makes non-uniform: 11x warp=none's error "
                            "on overhangs)", name);
    if (d->cache && !d->stable)
        return sb_fail(err, "%scache=on needs stable=on (an unstable fit moves every frame: nothing could be reused)",
                       name);
    return true;
}

double sb_csm_bytes(const sb_csm_desc *d) {
    static const int depth_bytes[] = {2, 4, 4};                 /* 16, 24 (stored in 32 bits), 32f */
    static const int moment_channels[] = {0, 2, 1, 4};          /* depth, vsm, esm, msm (create_maps) */
    double texels = (double)d->res * d->res * (d->cascades < 1 ? 1 : d->cascades);
    return texels * (depth_bytes[d->depth] + 2.0 * 4 * moment_channels[d->format]);   /* moments and their blur */
}

double sb_csm_technique_shadow_bytes(const sb_technique *t, const void *desc) {
    (void)t;
    return sb_csm_bytes(desc);
}

/* Whether the maps (and moments, and their blur copy) fit in the GPU memory the context has. */
static bool maps_fit(const sb_gpu *g, const sb_csm_desc *d, const char *name, sb_err *why) {
    double bytes = sb_csm_bytes(d);
    char who[160];
    if (d->cascades > 1) snprintf(who, sizeof who, "%s:res=%d:cascades=%d", name, d->res, d->cascades);
    else snprintf(who, sizeof who, "%s:res=%d", name, d->res);
    return sb_gpu_memory_fits(g, bytes, who, "shadow maps", why);
}

/* A moments map's texel format, for GL and for the blur's image (by
 * SB_MAP_*): as many 32-bit float channels as the format stores
 * (moments.frag): esm one, vsm two, msm four. A channel more would be memory
 * traffic in every clear, draw, blur pass and lookup. */
static const struct {
    GLenum gl;
    const char *glsl;
} moments_format[] = {{0, ""}, {GL_RG32F, "rg32f"}, {GL_R32F, "r32f"}, {GL_RGBA32F, "rgba32f"}};

/* One texture of the maps the GL would not allocate, found before anything renders: a skip naming its size and
 * what the GL did allocate (sb_gl_allocates). */
static bool texture_allocates(const sb_gpu *g, GLenum format, const char *what, const sb_csm_desc *d, const char *name,
                              sb_err *why) {
    double bytes = (double)d->res * d->res * d->cascades * sb_gl_texel_bytes(format);
    int fit = 0;
    if (sb_gl_allocates(format, d->res, d->res, d->cascades, &fit)) return true;
    return sb_fail(why, "%s:res=%d:cascades=%d: the GL (%s) does not allocate one %s texture of %dx%dx%d (%.1f GiB); "
                        "it allocates %d layer(s) of that size (%.1f GiB) in one texture: fewer cascades or a lower res "
                        "fit", name, d->res, d->cascades, g->ctx->renderer, what, d->res, d->res, d->cascades,
                   bytes / 1073741824.0, fit, bytes / d->cascades * fit / 1073741824.0);
}

static const GLenum csm_depth_formats[] = {GL_DEPTH_COMPONENT16, GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT32F};

bool sb_csm_supported(const sb_gpu *g, const sb_csm_desc *d, const char *name, sb_err *why) {
    const sb_context *ctx = g->ctx;
    if (!sb_layered_supported(ctx, d->layered, name, why)) return false;
    GLint max_size = 0, max_layers = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    if (d->res > max_size) return sb_fail(why, "%s:res=%d exceeds GL_MAX_TEXTURE_SIZE %d of %s", name, d->res, max_size,
                                          ctx->renderer);
    if (d->cascades > max_layers)
        return sb_fail(why, "%s: %d maps exceed GL_MAX_ARRAY_TEXTURE_LAYERS %d", name, d->cascades, max_layers);
    return maps_fit(g, d, name, why) && texture_allocates(g, csm_depth_formats[d->depth], "depth", d, name, why) &&
           (!d->format || texture_allocates(g, moments_format[d->format].gl, "moments", d, name, why));
}

/* The array depth map (and moments), one framebuffer for all layers and one a layer. */
static bool create_maps(sb_csm *c, const char *name, sb_err *err) {
    const sb_csm_desc *d = &c->d;
    const GLenum *depth_formats = csm_depth_formats;
    bool bilinear = !(d->filter == SB_FILTER_NONE || d->filter == SB_FILTER_PCF3 || d->filter == SB_FILTER_PCF5);
    c->tex = sb_shadow_texture(GL_TEXTURE_2D_ARRAY, depth_formats[d->depth], d->res, d->res, c->count, bilinear);
    if (d->format) { /* filtered formats: moments beside the depth the rasterizer tests with */
        GLuint m[2];
        glGenTextures(2, m);
        c->moments = m[0];
        c->moments_tmp = m[1];
        for (int i = 0; i < 2; i++) {
            glBindTexture(GL_TEXTURE_2D_ARRAY, m[i]);
            glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, moments_format[d->format].gl, d->res, d->res, c->count);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        }
    }
    glGenFramebuffers(1, &c->fbo_all);
    glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_all);
    glFramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, c->tex, 0);
    if (d->format) glFramebufferTexture(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, c->moments, 0);
    glDrawBuffer(d->format ? GL_COLOR_ATTACHMENT0 : GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return sb_fail(err, "%s:res=%d:cascades=%d: layered shadow framebuffer is incomplete", name, d->res, c->count);
    glGenFramebuffers(c->count, c->fbo_layer);
    for (int k = 0; k < c->count; k++) {
        glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_layer[k]);
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, c->tex, 0, k);
        if (d->format) glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, c->moments, 0, k);
        glDrawBuffer(d->format ? GL_COLOR_ATTACHMENT0 : GL_NONE);
        glReadBuffer(GL_NONE);
    }
    glGenBuffers(1, &c->block);
    glBindBuffer(GL_UNIFORM_BUFFER, c->block);
    glBufferData(GL_UNIFORM_BUFFER, sizeof(sb_cascade_block), NULL, GL_DYNAMIC_DRAW);
    return true;
}

/* The programs that render the maps: per cascade, layered by a geometry shader
 * or by gl_Layer from the vertex shader, and the moments' blur. Each comes in
 * two variants where the scene has alpha-tested draws: without the alpha test
 * (opaque draws: no discard, so early depth testing stays) and with it. */
static bool create_depth_programs(sb_csm *c, sb_err *err) {
    const sb_csm_desc *d = &c->d;
    const char *fs_depth[] = {d->format ? sb_shader_moments_frag : sb_shader_depth_frag};
    for (int a = 0; a < (c->gpu->scene->alpha_tested_draws ? 2 : 1); a++) {
        sb_csm_pass *p = &c->pass[a];
        char defs[256];
        snprintf(defs, sizeof defs, "%s#define SB_MAP_FORMAT %d\n", a ? "" : sb_opaque_define(c->gpu), d->format);
        const char *vs_cascade[] = {sb_shader_csm_block_glsl, sb_shader_csm_depth_vert};
        const sb_shader_src per[] = {{GL_VERTEX_SHADER, vs_cascade, 2}, {GL_FRAGMENT_SHADER, fs_depth, 1}};
        if (!(p->prog_cascade = sb_gpu_link(a ? "cascade depth (alpha-tested draws)" : "cascade depth", defs, per, 2,
                                            err)))
            return false;
        p->u_cascade = glGetUniformLocation(p->prog_cascade, "u_cascade");
        if (d->layered == SB_LAYERED_GS) {
            const char *vs[] = {sb_shader_csm_layer_gs_vert};
            const char *gs[] = {sb_shader_csm_block_glsl, sb_shader_csm_layer_geom};
            const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 1}, {GL_GEOMETRY_SHADER, gs, 2},
                                        {GL_FRAGMENT_SHADER, fs_depth, 1}};
            if (!(p->prog_layered = sb_gpu_link("layered (geometry shader)", defs, st, 3, err))) return false;
        } else if (d->layered == SB_LAYERED_VS) {
            const char *vs[] = {sb_shader_csm_block_glsl, sb_shader_csm_layer_vs_vert};
            const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 2}, {GL_FRAGMENT_SHADER, fs_depth, 1}};
            char vs_defs[320];
            snprintf(vs_defs, sizeof vs_defs, "#extension GL_ARB_shader_viewport_layer_array : require\n%s", defs);
            if (!(p->prog_layered = sb_gpu_link("layered (vertex shader)", vs_defs, st, 2, err))) return false;
        }
        p->e_cascade = glGetUniformLocation(p->prog_cascade, "u_exponent");
        p->e_layered = p->prog_layered ? glGetUniformLocation(p->prog_layered, "u_exponent") : -1;
    }
    if (d->format && d->blur > 0) {
        const char *cs[] = {sb_shader_blur_comp};
        const sb_shader_src st[] = {{GL_COMPUTE_SHADER, cs, 1}};
        char defs[96];
        snprintf(defs, sizeof defs, "#define SB_BLUR_RADIUS %d\n#define SB_IMAGE_FORMAT %s\n", d->blur,
                 moments_format[d->format].glsl);
        if (!(c->blur_prog = sb_gpu_link("moments blur", defs, st, 1, err))) return false;
        c->b_dir = glGetUniformLocation(c->blur_prog, "u_dir");
        c->b_layer = glGetUniformLocation(c->blur_prog, "u_layer");
    }
    return true;
}

/* The final pass with the cascade lookup (vis_csm.glsl), and its uniforms. */
static bool create_final(sb_csm *c, const char *name, sb_err *err) {
    char defines[192];
    const sb_csm_desc *d = &c->d;
    snprintf(defines, sizeof defines,
             "#define SB_FILTER %d\n#define SB_SELECT %d\n#define SB_MAP_FORMAT %d\n#define SB_MAPS %d\n"
             "#define SB_WARP %d\n#define SB_BLEND %d\n",
             d->filter, d->select, d->format, c->count, d->warp != SB_WARP_NONE || d->perspective, d->blend > 0);
    const char *vis[] = {sb_shader_csm_block_glsl, sb_shader_vis_csm_glsl};
    if (!sb_final_prog_create_parts(&c->fp, c->gpu, name, vis, 2, defines, err)) return false;
    const char *names[] = {"u_shadow",    "u_bias",  "u_normal",    "u_blend",   "u_light",   "u_texel",
                           "u_depth_raw", "u_moments", "u_bleed",   "u_exponent", "u_sun_tan"};
    GLint *locs[] = {&c->u_shadow,    &c->u_bias,    &c->u_normal,  &c->u_blend,    &c->u_light,  &c->u_texel,
                     &c->u_depth_raw, &c->u_moments, &c->u_bleed,   &c->u_exponent, &c->u_sun_tan};
    for (size_t i = 0; i < SB_COUNT(names); i++) *locs[i] = glGetUniformLocation(c->fp.prog, names[i]);
    glGenSamplers(1, &c->raw_sampler);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_COMPARE_MODE, GL_NONE);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glSamplerParameteri(c->raw_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return true;
}

bool sb_csm_create(sb_csm *c, const sb_gpu *g, const sb_csm_desc *d, const char *name, sb_err *err) {
    memset(c, 0, sizeof *c);
    c->gpu = g;
    c->d = *d;
    if (c->d.cascades < 1) c->d.cascades = 1;
    c->d.layered = sb_layered_resolve(g->ctx, d->layered);
    c->count = c->d.cascades;
    c->mask = sb_xcalloc(g->scene->draw_count + 1, 1);
    return create_maps(c, name, err) && create_depth_programs(c, err) && create_final(c, name, err) &&
           sb_gl_check(name, err);
}

void sb_csm_destroy(sb_csm *c) {
    sb_final_prog_free(&c->fp);
    for (int a = 0; a < 2; a++) {
        if (c->pass[a].prog_cascade) glDeleteProgram(c->pass[a].prog_cascade);
        if (c->pass[a].prog_layered) glDeleteProgram(c->pass[a].prog_layered);
    }
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
    for (int k = 0; k < 8 && !c->d.stable; k++) {   /* stable: the slice as the fixed range cuts it, whole */
        sb_v3 q = sb_aabb_corner(&s->bounds, k);
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
    const sb_csm_desc *d = &c->d;
    if (d->warp == SB_WARP_LISPSM)
        sb_light_fit_lispsm(s, f->gpu->sun, eye, f->cam.forward, zn, zf, corners, 8, d->res, d->min_angle,
                            sb_csm_fits_receivers(d), out);
    else if (d->warp == SB_WARP_TSM) sb_light_fit_tsm(s, f->gpu->sun, corners, d->res, d->focus, zn, zf, out);
    else if (d->stable) sb_light_fit_stable(s, f->gpu->sun, corners, 8, d->res, out);
    else if (sb_csm_fits_receivers(d)) sb_light_fit_receivers(s, f->gpu->sun, corners, d->res, out);
    else sb_light_fit_points(s, f->gpu->sun, corners, 8, d->res, out);
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
    return sb_scene_collect(f->gpu->scene, (const double(*)[4])planes, 6, f->scratch) > 0;
}

static void block_put(sb_csm *c, int k, const sb_light_fit *fit, double zn, double zf, bool active) {
    sb_m4_to_float(fit->view_proj, c->cpu.light_vp[k]);
    sb_m4_to_float(fit->shadow_mat, c->cpu.shadow_mat[k]);
    c->cpu.s.cascade[k][0] = (float)zn;
    c->cpu.s.cascade[k][1] = (float)zf;
    c->cpu.s.cascade[k][2] = (float)fit->texel_world;
    c->cpu.s.cascade[k][3] = (float)(fit->zf - fit->zn);
    c->cpu.s.flags[k][0] = active ? 1.0f : 0.0f;
    c->cpu.s.flags[k][1] = fit->warped ? 1.0f : 0.0f;
}

void sb_csm_upload(sb_csm *c, const double *zn, const double *zf) {
    memset(&c->cpu, 0, sizeof c->cpu);
    c->cpu.info[0] = (float)c->count;
    for (int k = 0; k < c->count; k++) block_put(c, k, &c->fit[k], zn[k], zf[k], c->active[k]);
    glBindBuffer(GL_UNIFORM_BUFFER, c->block);
    glBufferSubData(GL_UNIFORM_BUFFER, 0, sizeof c->cpu, &c->cpu);
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
        f->counters.warp_fallbacks += c->d.warp && c->active[k] && !c->fit[k].warped;
    }
    sb_csm_upload(c, splits, splits + 1);
}

uint32_t sb_csm_cull(sb_csm *c, sb_frame *f, const sb_light_fit *bound) {
    const sb_scene *s = f->gpu->scene;
    memset(c->mask, 0, s->draw_count);
    uint32_t *list = f->scratch;
    for (int k = 0; k < c->count; k++) {
        if (!bound && !c->active[k]) continue;
        const sb_light_fit *fit = bound ? bound : &c->fit[k];
        uint32_t n = sb_scene_collect(s, (const double(*)[4])fit->planes, 6, list);
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

/* The slope-scaled offset (glPolygonOffset factor): `slope` for orthographic
 * maps, 4x it when a map of this frame is warped (LiSPSM, TSM, PSM), whose
 * depth is not linear in distance: the default 0.5 is 2 there, as it was
 * before orthographic maps went to 0.5 (README, shadow-map parameters). */
static float slope_factor(const sb_csm *c) {
    for (int k = 0; k < c->count; k++)
        if (c->active[k] && c->fit[k].warped) return (float)(4 * c->d.slope);
    return (float)c->d.slope;
}

/* Whether a box (origin-relative) reaches into a layer's light volume: its window across, anywhere from the
 * light to the far plane along (depth clamp keeps casters toward the light). The fit is orthographic wherever a
 * cache is kept (stable=on, no warp). */
static bool box_in_layer(const sb_aabb *b, const void *region) {
    const float *vp = region;
    sb_m4 m;
    for (int i = 0; i < 16; i++) m.m[i] = vp[i];
    sb_aabb c = sb_aabb_transform(m, b);   /* an orthographic fit: w is 1 */
    return c.hi.x >= -1 && c.lo.x <= 1 && c.hi.y >= -1 && c.lo.y <= 1 && c.lo.z <= 1;
}

/* Whether a caster moved into, out of or within layer k since the last frame (its box before or after). */
static bool moved_into(const sb_csm *c, const sb_frame *f, int k) {
    return sb_frame_moved_meets(f, box_in_layer, c->cpu.light_vp[k]);
}

void sb_csm_render(sb_csm *c, sb_frame *f) {
    const sb_gpu *g = f->gpu;
    const sb_csm_desc *d = &c->d;
    const sb_scene *s = g->scene;
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, c->block);
    glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_all);
    glViewport(0, 0, d->res, d->res);
    sb_shadow_depth_state(d->slope != 0 ? slope_factor(c) : 0);
    /* cache=on: a layer still holding what this frame's fit would draw (the same light view-projection, bit for
       bit: the same snapped window and light) is kept, not drawn again, unless a caster moved into, out of or
       within its light volume since the last frame (its box before or after the move overlaps it: UE5's rule);
       the stale check's frame (bypass_cache) draws every layer and keeps none of them */
    unsigned todo = 0;
    int cached = 0, invalidated = 0;
    for (int k = 0; k < c->count; k++) {
        if (!c->active[k]) continue;
        bool same = d->cache && c->cached[k] && !memcmp(c->cached_vp[k], c->cpu.light_vp[k], sizeof c->cached_vp[k]);
        bool moved = same && f->moved_count && moved_into(c, f, k);
        bool keep = same && !moved && !f->bypass_cache;
        invalidated += moved;
        cached += keep;
        if (keep) continue;
        todo |= 1u << k;
        memcpy(c->cached_vp[k], c->cpu.light_vp[k], sizeof c->cached_vp[k]);
        c->cached[k] = d->cache && !f->bypass_cache;
    }
    sb_count(&f->counters, &sb_csm_counters[0], invalidated);
    /* cleared: every layer at once (fbo_all), or with the cache each layer drawn again */
    for (int k = 0; k < (d->cache ? c->count : 1); k++) {
        if (d->cache && !(todo & (1u << k))) continue;
        if (d->cache) glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_layer[k]);
        if (d->format) { /* moments of the far plane: nothing occludes */
            const float z = 1.0f, e = (float)exp(d->exponent);
            const float far[4] = {d->format == SB_MAP_ESM ? e : z, z, z, z};
            glClearBufferfv(GL_COLOR, 0, far);
        }
        glClear(GL_DEPTH_BUFFER_BIT);
    }
    if (!c->no_clamp) glEnable(GL_DEPTH_CLAMP);   /* casters toward the light stay, at depth 0 */
    glBindVertexArray(g->vao);
    int rendered = 0;
    for (int k = 0; k < c->count; k++) rendered += c->active[k];
    f->counters.cascades_rendered = rendered - cached;
    f->counters.cascades_cached = cached;
    f->counters.cascades_skipped = c->count - rendered;
    if (d->cache)
        for (uint32_t i = 0; i < s->draw_count; i++) c->mask[i] &= (uint8_t)todo;   /* casters of layers drawn again */
    /* opaque casters first, with the variant without the alpha test; then the alpha-tested ones */
    for (int a = 0; a < 2 && c->pass[a].prog_cascade; a++) {
        const sb_csm_pass *p = &c->pass[a];
        if (d->layered == SB_LAYERED_OFF) {
            glUseProgram(p->prog_cascade);
            if (p->e_cascade >= 0) glUniform1f(p->e_cascade, (float)d->exponent);
            for (int k = 0; k < c->count; k++) {
                if (!(todo & (1u << k))) continue;   /* inactive, or kept */
                glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_layer[k]);
                glUniform1i(p->u_cascade, k);
                for (uint32_t d = 0; d < s->draw_count; d++)
                    if ((c->mask[d] & (1u << k)) && sb_draw_variant(g, d) == a) sb_submit(f, d, 1);
                sb_submit_flush(f);
            }
        } else {
            bool gs = d->layered == SB_LAYERED_GS;
            glBindFramebuffer(GL_FRAMEBUFFER, c->fbo_all);
            glUseProgram(p->prog_layered);
            if (p->e_layered >= 0) glUniform1f(p->e_layered, (float)d->exponent);
            if (a == 0) sb_set_draw_masks(f, c->mask);   /* each draw's cascades, read at its baseInstance */
            for (uint32_t d = 0; d < s->draw_count; d++) {
                unsigned m = c->mask[d];
                if (!m || sb_draw_variant(g, d) != a) continue;
                sb_submit(f, d, gs ? 1 : popcount8(m));
            }
            sb_submit_flush(f);
        }
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    if (d->format && d->blur > 0) { /* separable Gaussian per rendered layer: moments -> tmp -> moments */
        glUseProgram(c->blur_prog);
        const GLenum fmt = moments_format[d->format].gl;
        for (int k = 0; k < c->count; k++) {
            if (!(todo & (1u << k))) continue;
            glUniform1i(c->b_layer, k);
            for (int pass = 0; pass < 2; pass++) {
                glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
                glBindImageTexture(0, pass ? c->moments_tmp : c->moments, 0, GL_TRUE, 0, GL_READ_ONLY, fmt);
                glBindImageTexture(1, pass ? c->moments : c->moments_tmp, 0, GL_TRUE, 0, GL_WRITE_ONLY, fmt);
                glUniform2i(c->b_dir, pass ? 0 : 1, pass ? 1 : 0);
                /* x: across the direction, 64 a group; y: runs of 8 along it (blur.comp) */
                glDispatchCompute((GLuint)(d->res + 63) / 64, (GLuint)(d->res + 7) / 8, 1);
            }
        }
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    }
}

void sb_csm_draw(sb_csm *c, sb_frame *f) {
    sb_stage_begin(f, &sb_stage_cascade);
    sb_csm_cull(c, f, NULL);
    sb_csm_render(c, f);
    sb_stage_end(f, &sb_stage_cascade);
    sb_stage_begin(f, &sb_stage_final);
    sb_csm_final(c, f, false);
    sb_stage_end(f, &sb_stage_final);
}

void sb_csm_final(sb_csm *c, sb_frame *f, bool reuse_depth) {
    const sb_gpu *g = f->gpu;
    const sb_csm_desc *d = &c->d;
    glUseProgram(c->fp.prog);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, c->block);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, c->tex);
    glUniform1i(c->u_shadow, 0);
    glUniform1f(c->u_bias, (float)d->bias);
    glUniform1f(c->u_normal, (float)d->normal);
    glUniform1f(c->u_blend, (float)d->blend);
    glUniform3f(c->u_light, (float)g->sun.x, (float)g->sun.y, (float)g->sun.z);
    glUniform2f(c->u_texel, 1.0f / d->res, 1.0f / d->res);
    /* the same texture on unit 2 through a sampler without comparison */
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D_ARRAY, c->tex);
    glBindSampler(2, c->raw_sampler);
    glUniform1i(c->u_depth_raw, 2);
    glUniform1f(c->u_sun_tan, (float)tan(d->sun_size * SB_PI / 180));
    if (d->format) {
        glActiveTexture(GL_TEXTURE3);
        glBindTexture(GL_TEXTURE_2D_ARRAY, c->moments);
        glUniform1i(c->u_moments, 3);
        glUniform1f(c->u_bleed, (float)d->bleed);
        glUniform1f(c->u_exponent, (float)d->exponent);
    }
    glActiveTexture(GL_TEXTURE0);
    sb_final_pass(f, &c->fp, reuse_depth);
    glBindSampler(2, 0);
}

/* ---- cascade techniques as rows ---- */

void sb_csm_view_splits(const void *desc, const sb_frame *f, int count, double near, double far, double *out) {
    (void)desc;
    (void)count;
    (void)f;
    out[0] = near;
    out[1] = far;
}

void sb_csm_range(const sb_csm *c, const sb_frame *f, double *near, double *far) {
    bool fixed = c->d.stable && c->range_far > c->range_near && c->range_near > 0;
    *near = fixed ? c->range_near : f->cam.znear;
    *far = fixed ? c->range_far : f->cam.zfar;
}

bool sb_csm_technique_check(const void *desc, sb_err *err) { return sb_csm_check(desc, "", err); }

bool sb_csm_technique_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    return sb_csm_supported(rc->gpu, desc, rc->tech->name, why);
}

bool sb_csm_technique_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    sb_csm_state *st = state;
    st->kind = rc->tech->impl;
    st->desc = desc;
    if (!sb_csm_create(&st->csm, rc->gpu, desc, rc->tech->name, err)) return false;
    const sb_csm_desc *d = desc;
    st->csm.range_near = rc->shadow_near;
    st->csm.range_far = d->distance > 0 ? d->distance : rc->shadow_far;
    return true;
}

void sb_csm_technique_frame(void *state, sb_frame *f) {
    sb_csm_state *st = state;
    double splits[SB_MAX_CASCADES + 1], zn, zf;
    sb_csm_range(&st->csm, f, &zn, &zf);
    st->kind->splits(st->desc, f, st->csm.count, zn, zf, splits);
    sb_csm_fit(&st->csm, f, splits);
    sb_csm_draw(&st->csm, f);
}

void sb_csm_technique_destroy(void *state) {
    sb_csm_state *st = state;
    sb_csm_destroy(&st->csm);
}
