/* atlas.c - every lamp's shadows in one depth atlas, as engines shadow many
 * local lights (Unity HDRP's shadow atlas): each lamp six perspective tiles
 * (a cube's faces; kind=dpsm: two paraboloids, dpsm.c's, a hemisphere each),
 * a spot whose cone fits a 90-degree frustum one perspective tile down its
 * cone), squares of one 2D depth texture of `size` texels a side,
 * and one camera pass that shades every lamp (final.frag's SB_LIGHT_LOOP,
 * vis_atlas.glsl reading each lamp's record from a texture buffer).
 *
 * Each frame, the lamps whose range reaches the view ask for tiles: `res`
 * texels a face (policy=fixed), or res scaled by the share of the screen
 * height the lamp's range covers, rounded down to a power of two
 * (policy=screen, HDRP's dynamic rescale). At most `max_lights` lamps, the
 * most important first (the largest on screen). When their tiles do not fit,
 * the largest tiles are halved one at a time (downscaled), then, with every
 * tile at the smallest size, the least important lamps dropped: they light
 * without shadows. Both are counted each frame (lights_downscaled,
 * lights_dropped) and the run warns with the counts. The tiles are packed in
 * Z order, largest first, so that every square lands aligned and none
 * overlap.
 *
 * cache=on keeps a lamp's tiles while it holds the same place in the atlas,
 * the lamp has not moved and no moved caster's box, before or after the
 * move, reaches into its range (the scene's clips, issue of moving scenes);
 * tiles drawn over another lamp's forget it. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lamp.h"
#include "lightgrid.h"
#include "render.h"
#include "shaders.h"

#define MIN_TILE 16      /* the smallest tile, and the atlas's cell */
#define LREC 36          /* texels of a lamp's record (vis_atlas.glsl's SB_LREC) */

typedef struct atlas_desc {
    int size, res, kind, max_lights, policy, cache, filter, grid;
    double bias, slope, normal;
} atlas_desc;

enum { POLICY_FIXED, POLICY_SCREEN };
enum { KIND_CUBE, KIND_DPSM };

static const sb_param_def atlas_params[] = {
    SB_PARAM_I(atlas_desc, size, 4096, 256, 16384, "the atlas's side in texels, a power of two",
               .tune = "2048,4096,8192", .role = SB_PARAM_RES),
    SB_PARAM_I(atlas_desc, res, 512, MIN_TILE, 4096, "a lamp's face at full scale, in texels (a power of two)",
               .tune = "256,512,1024"),
    SB_PARAM_E(atlas_desc, kind, cube, "cube|dpsm",
               "a lamp's tiles: six perspective faces of a cube, or two paraboloids (dpsm's, a hemisphere each)",
               .tune = "cube,dpsm"),
    SB_PARAM_I(atlas_desc, max_lights, 64, 1, SB_MAX_LIGHTS, "the most lamps shadowed a frame (the largest on screen)"),
    SB_PARAM_E(atlas_desc, policy, fixed, "fixed|screen",
               "a lamp's tile size: res for every lamp, or res scaled by the screen height its range covers",
               .tune = "fixed,screen"),
    SB_PARAM_E(atlas_desc, cache, off, "off|on",
               "keep a lamp's tiles while its place in the atlas holds, it has not moved and no moved caster reaches "
               "into its range", .role = SB_PARAM_CACHE),
    SB_PARAM_E(atlas_desc, filter, hw, "none|hw", "shadow filter", .tune = "none,hw"),
    SB_PARAM_E_LATE(atlas_desc, grid, on, "off|on",
                    "find each pixel's lamps by cluster (a light list per screen tile and depth slice, built each "
                    "frame: the clusters stage) instead of looping over every lamp in view"),
    SB_PARAM_FA(atlas_desc, bias, 1.5, 0, 100, "constant bias, in texels of the tile at the point's distance"),
    SB_PARAM_FA(atlas_desc, slope, 2, 0, 100, "slope-scaled bias (glPolygonOffset factor)"),
    SB_PARAM_FA(atlas_desc, normal, 1, 0, 100, "normal offset, in texels"),
};

/* Its counters: what the lamps in view got this frame. */
enum { C_SHADOWED, C_DROPPED, C_DOWNSCALED, C_OCCUPANCY, C_GRID, C_COUNT };
static const sb_counter_def atlas_counters[C_COUNT] = {
    [C_SHADOWED] = {.name = "lights_shadowed", .unit = "count", .stats = SB_STAT_MEAN,
                    .doc = "atlas: lamps with tiles this frame (empty: no atlas)"},
    [C_DROPPED] = {.name = "lights_dropped", .unit = "count", .stats = SB_STAT_MEAN | SB_STAT_MAX,
                   .flags = SB_USE_COMPARE,
                   .doc = "atlas: lamps lighting the view left without shadows (beyond max_lights, or no room at the "
                          "smallest tile)"},
    [C_DOWNSCALED] = {.name = "lights_downscaled", .unit = "count", .stats = SB_STAT_MEAN | SB_STAT_MAX,
                      .doc = "atlas: lamps whose tiles are smaller than their policy asked for, for want of room"},
    [C_OCCUPANCY] = {.name = "atlas_occupancy", .unit = "share", .stats = SB_STAT_MEAN,
                     .doc = "atlas: share of the atlas its tiles cover this frame"},
    [C_GRID] = SB_GRID_ITEMS_COUNTER,
};

/* One lamp this run shadows: where it is, and its tiles now and when last drawn. */
typedef struct lamp {
    int light;                  /* its index among the scene's point and spot lights */
    sb_v3 pos;                  /* origin-relative */
    double range, near, far;    /* range 0: none (the scene's size for far) */
    double importance;          /* this frame: the screen height its range covers, in pixels (0: out of view) */
    int faces;                  /* its tiles: the kind's (6 cube, 2 dpsm), or 1 for a spot whose cone fits one
                                   90-degree perspective tile */
    double cone;                /* a spot's outer half-angle (0: a point light) */
    sb_v3 dir;                  /* the way a spot shines */
    int want, tile;             /* texels a face: asked for, given (0: none) */
    uint64_t z;                 /* its first tile's Z-order cell (MIN_TILE cells): face k is tile z / tile cells + k */
    bool valid;                 /* cache: its tiles in the atlas are its own, drawn at kz, ktile from kpos */
    uint64_t kz;
    int ktile;
    sb_v3 kpos;
    sb_m4 face_vp[6];
} lamp;

typedef struct atlas_state {
    const atlas_desc *d;
    int count;                  /* lamps */
    lamp *lamps;
    int *order;                 /* scratch: lamp indices */
    GLuint tex, fbo, buf, buf_tex;
    GLuint fresh_tex, fresh_fbo;   /* the stale check's atlas (made on its first frame): the kept one untouched */
    GLuint depth_prog[2][2];    /* [perspective tiles, paraboloids][opaque, alpha-tested draws] */
    GLint u[2][2][5];           /* perspective: u_vp; paraboloid: u_lamp, u_frame, u_side, u_near, u_far */
    sb_final_prog fp;
    GLint u_atlas, u_lights, u_count, u_bias, u_normal;
    float *records;             /* count * LREC * 4 floats */
    sb_lightgrid grid;          /* grid=on: the lamps of each cluster, indices into this frame's records */
    sb_v3 *shown_pos;           /* this frame's records' lamps and ranges (the grid's input) */
    double *shown_range;
} atlas_state;

static bool pow2(int v) { return v > 0 && (v & (v - 1)) == 0; }

static bool atlas_check(const void *desc, sb_err *err) {
    const atlas_desc *d = desc;
    if (!pow2(d->size)) return sb_fail(err, "atlas:size=%d: not a power of two (256, 512, ... 16384)", d->size);
    if (!pow2(d->res) || d->res > d->size)
        return sb_fail(err, "atlas:res=%d: a power of two from %d to size (%d)", d->res, MIN_TILE, d->size);
    return true;
}

static double atlas_shadow_bytes(const sb_technique *t, const void *desc) {
    (void)t;
    const atlas_desc *d = desc;
    return (double)d->size * d->size * 4;   /* one 32F depth texture */
}

static bool atlas_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    const atlas_desc *d = desc;
    GLint max = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max);
    if (max > 0 && d->size > max)
        return sb_fail(why, "atlas:size=%d exceeds GL_MAX_TEXTURE_SIZE %d of %s", d->size, max, rc->gpu->ctx->renderer);
    return sb_gpu_memory_fits(rc->gpu, atlas_shadow_bytes(rc->tech, desc), "atlas", "the shadow atlas", why);
}

static void place_lamp(lamp *l, const sb_gpu *g, int which, int kind) {
    const sb_light *src = sb_scene_point_light(g->scene, which, NULL);
    l->light = which;
    l->pos = src->position;
    l->range = src->range > 0 ? src->range : 0;
    sb_lamp_clip(src, g->scene, 1e-4, &l->near, &l->far);   /* as cube's (dpsm's paraboloids store the distance) */
    l->cone = src->type == SB_LIGHT_SPOT ? src->cone : 0;
    l->dir = src->direction;
    l->faces = l->cone > 0 && l->cone <= SB_PI / 4 ? 1 : kind == KIND_DPSM ? 2 : 6;
    if (l->faces == 1) {   /* one perspective tile down the cone, as wide as the cone */
        sb_v3 up = fabs(l->dir.y) > 0.9 ? sb_v3_make(1, 0, 0) : sb_v3_make(0, 1, 0);
        l->face_vp[0] = sb_m4_mul(sb_m4_perspective(2 * l->cone, 1, l->near, l->far),
                                  sb_m4_look_at(l->pos, sb_v3_add(l->pos, l->dir), up));
        return;
    }
    sb_lamp_cube_faces(l->pos, l->near, l->far, l->face_vp);
}

/* A depth texture of the atlas's size and its framebuffer; false when incomplete. */
static bool make_atlas(const atlas_state *s, GLuint *tex, GLuint *fbo) {
    *tex = sb_shadow_texture(GL_TEXTURE_2D, GL_DEPTH_COMPONENT32F, s->d->size, s->d->size, 1, s->d->filter != 0);
    glGenFramebuffers(1, fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
    glFramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, *tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    return glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
}

static bool atlas_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    atlas_state *s = state;
    const sb_gpu *g = rc->gpu;
    s->d = desc;
    s->count = rc->lights->count;
    s->lamps = sb_xcalloc((size_t)s->count, sizeof *s->lamps);
    s->order = sb_xcalloc((size_t)s->count, sizeof *s->order);
    s->records = sb_xcalloc((size_t)s->count * LREC * 4, sizeof(float));
    s->shown_pos = sb_xcalloc((size_t)s->count, sizeof *s->shown_pos);
    s->shown_range = sb_xcalloc((size_t)s->count, sizeof *s->shown_range);
    if (s->d->grid) sb_lightgrid_init(&s->grid, g->width, g->height);
    for (int i = 0; i < s->count; i++) place_lamp(&s->lamps[i], g, rc->lights->idx[i], s->d->kind);
    if (!make_atlas(s, &s->tex, &s->fbo)) return sb_fail(err, "atlas:size=%d: the atlas's framebuffer is incomplete", s->d->size);
    glGenBuffers(1, &s->buf);
    glBindBuffer(GL_TEXTURE_BUFFER, s->buf);
    glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)s->count * LREC * 16, NULL, GL_DYNAMIC_DRAW);
    glGenTextures(1, &s->buf_tex);
    glBindTexture(GL_TEXTURE_BUFFER, s->buf_tex);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, s->buf);
    static const char *const prog_u[2][5] = {{"u_vp"}, {"u_lamp", "u_frame", "u_side", "u_near", "u_far"}};
    const char *fs[] = {sb_shader_depth_frag};
    for (int kp = 0; kp <= s->d->kind; kp++)   /* perspective tiles always (cube faces, spots), paraboloids for dpsm */
        for (int a = 0; a < (g->scene->alpha_tested_draws ? 2 : 1); a++) {
            const char *vs[] = {kp ? sb_shader_dpsm_vert : sb_shader_cube_depth_vert};
            char label[64];
            snprintf(label, sizeof label, "atlas %s tile%s", kp ? "paraboloid" : "perspective", a ? " (alpha-tested draws)" : "");
            s->depth_prog[kp][a] = sb_gpu_program(label, a ? NULL : sb_opaque_define(g), vs, 1, fs, 1, err);
            if (!s->depth_prog[kp][a]) return false;
            for (int k = 0; k < 5; k++)
                s->u[kp][a][k] = prog_u[kp][k] ? glGetUniformLocation(s->depth_prog[kp][a], prog_u[kp][k]) : -1;
        }
    bool spots = false;
    for (int i = 0; i < s->count; i++) spots |= s->lamps[i].faces == 1;
    char defines[160];
    snprintf(defines, sizeof defines, "#define SB_LIGHT_LOOP\n#define SB_FILTER %d\n#define SB_ATLAS_DPSM %d\n"
             "#define SB_ATLAS_SPOTS %d\n%s", s->d->filter, s->d->kind == KIND_DPSM, spots,
             s->d->grid ? "#define SB_LIGHT_GRID\n" : "");
    const char *parts[] = {sb_shader_lightgrid_glsl, sb_shader_vis_atlas_glsl};
    if (!sb_final_prog_create_parts(&s->fp, g, "atlas", parts + !s->d->grid, 2 - !s->d->grid, defines, err))
        return false;
    const char *names[] = {"u_atlas", "u_lights", "u_count", "u_bias", "u_normal"};
    GLint *locs[] = {&s->u_atlas, &s->u_lights, &s->u_count, &s->u_bias, &s->u_normal};
    for (size_t i = 0; i < SB_COUNT(names); i++) *locs[i] = glGetUniformLocation(s->fp.prog, names[i]);
    if (s->d->grid) sb_lightgrid_locate(&s->grid, s->fp.prog);
    return sb_gl_check("atlas", err);
}

/* ---- which lamps get tiles, how large, and where ---- */

/* The screen height the lamp's range covers, in pixels; 0 when its range lies outside the view. */
static double importance(const lamp *l, const sb_frame *f) {
    if (l->range <= 0) return f->gpu->height;   /* no range: it lights the whole view */
    for (int k = 0; k < 6; k++) {
        const double *p = f->frustum[k];
        if (p[0] * l->pos.x + p[1] * l->pos.y + p[2] * l->pos.z + p[3] < -l->range) return 0;
    }
    double dist = sb_v3_len(sb_v3_sub(l->pos, sb_frame_eye(f)));
    if (dist <= l->range) return f->gpu->height;
    return fmin(f->gpu->height, l->range / dist * f->gpu->height / tan(f->cam.fov_deg * SB_PI / 360));
}

/* qsort's comparisons read the lamps of the frame being allocated */
static const lamp *sort_lamps;
/* the largest on screen first (ties: the set's order) */
static int cmp_importance(const void *a, const void *b) {
    int i = *(const int *)a, j = *(const int *)b;
    double x = sort_lamps[i].importance, y = sort_lamps[j].importance;
    return x != y ? (x < y) - (x > y) : i - j;
}
/* the largest tiles first */
static int cmp_tile(const void *a, const void *b) {
    int i = *(const int *)a, j = *(const int *)b, x = sort_lamps[i].tile, y = sort_lamps[j].tile;
    return x != y ? y - x : i - j;
}

/* Cells of the atlas (MIN_TILE texels a side) a lamp's tiles take. */
static double cells(const lamp *l, int tile) { return (double)l->faces * (tile / MIN_TILE) * (tile / MIN_TILE); }

/* The x or y of a Z-order cell index (every other bit). */
static int unzip(uint64_t z) {
    int v = 0;
    for (int b = 0; b < 31; b++) v |= (int)((z >> (2 * b)) & 1) << b;
    return v;
}

/* This frame's lamps: tiles asked for and given, places, and the counters. Returns how many lamps have tiles (the
 * first `n` of s->order). */
static int allocate(atlas_state *s, sb_frame *f) {
    const atlas_desc *d = s->d;
    int n = 0, in_view = 0;
    for (int i = 0; i < s->count; i++) {
        lamp *l = &s->lamps[i];
        l->importance = importance(l, f);
        l->tile = l->want = 0;
        if (l->importance > 0) s->order[n++] = i;
    }
    in_view = n;
    sort_lamps = s->lamps;
    qsort(s->order, (size_t)n, sizeof *s->order, cmp_importance);
    if (n > d->max_lights) n = d->max_lights;
    for (int k = 0; k < n; k++) {
        lamp *l = &s->lamps[s->order[k]];
        int t = d->res;
        if (d->policy == POLICY_SCREEN) {
            double share = fmin(1, l->importance / f->gpu->height);
            while (t > MIN_TILE && t / 2 >= d->res * share) t /= 2;
        }
        l->want = l->tile = t;
    }
    double capacity = (double)(d->size / MIN_TILE) * (d->size / MIN_TILE), need = 0;
    for (int k = 0; k < n; k++) need += cells(&s->lamps[s->order[k]], s->lamps[s->order[k]].tile);
    while (need > capacity && n > 0) {
        int big = -1;   /* the largest tile above the smallest, the least important of those */
        for (int k = n - 1; k >= 0; k--) {
            const lamp *l = &s->lamps[s->order[k]];
            if (l->tile > MIN_TILE && (big < 0 || l->tile > s->lamps[s->order[big]].tile)) big = k;
        }
        lamp *l = &s->lamps[s->order[big < 0 ? n - 1 : big]];
        need -= cells(l, l->tile);
        if (big >= 0) {
            l->tile /= 2;
            need += cells(l, l->tile);
        } else {
            l->tile = 0;   /* every tile at the smallest: the least important goes */
            n--;
        }
    }
    int downscaled = 0;
    for (int k = 0; k < n; k++) downscaled += s->lamps[s->order[k]].tile < s->lamps[s->order[k]].want;
    /* largest first, each at the next Z-order cell: aligned, never overlapping */
    int *place = sb_xmalloc(sizeof *place * (size_t)(n ? n : 1));
    memcpy(place, s->order, sizeof *place * (size_t)n);
    qsort(place, (size_t)n, sizeof *place, cmp_tile);
    uint64_t z = 0;
    for (int k = 0; k < n; k++) {
        lamp *l = &s->lamps[place[k]];
        l->z = z;
        z += (uint64_t)cells(l, l->tile);
    }
    free(place);
    sb_count(&f->counters, &atlas_counters[C_SHADOWED], n);
    sb_count(&f->counters, &atlas_counters[C_DROPPED], in_view - n);
    sb_count(&f->counters, &atlas_counters[C_DOWNSCALED], downscaled);
    sb_count(&f->counters, &atlas_counters[C_OCCUPANCY], (double)z / capacity);
    return n;
}

/* Where face k of a lamp's tiles lies: the Z-order cell of its tile size (every lamp before it took whole cells
 * of that size or larger, so its first tile starts one). */
static void face_rect(const lamp *l, int k, int *x, int *y) {
    uint64_t per = (uint64_t)(l->tile / MIN_TILE) * (l->tile / MIN_TILE), zt = l->z / per + (uint64_t)k;
    *x = unzip(zt) * l->tile;
    *y = unzip(zt >> 1) * l->tile;
}

/* ---- the tiles ---- */

/* Whether a box reaches into the lamp's range. */
static bool in_range(const sb_aabb *b, const void *region) {
    const lamp *l = region;
    return sb_aabb_dist2(b, l->pos) <= l->range * l->range;
}

/* Whether a moved caster's box, before or after the move, reaches into the lamp's range. */
static bool mover_reaches(const lamp *l, const sb_frame *f) {
    if (l->range <= 0) return f->moved_count > 0;
    return sb_frame_moved_meets(f, in_range, l);
}

/* Every kept lamp a moved caster reaches forgets its tiles: every frame, for every lamp, whether or not the frame
 * draws it (an evaluation pass draws one), since what moved is told once, from one frame to the next. */
static void invalidate_moved(atlas_state *s, const sb_frame *f) {
    if (f->bypass_cache || !f->moved_count) return;
    for (int i = 0; i < s->count; i++)
        if (s->lamps[i].valid && mover_reaches(&s->lamps[i], f)) s->lamps[i].valid = false;
}

static bool kept(const atlas_state *s, const lamp *l, const sb_frame *f) {
    return s->d->cache && !f->bypass_cache && l->valid && l->kz == l->z && l->ktile == l->tile &&
           !memcmp(&l->kpos, &l->pos, sizeof l->pos);
}

/* Another lamp's kept tiles that this lamp's place overlaps are forgotten. */
static void forget_under(atlas_state *s, const lamp *l) {
    uint64_t a0 = l->z, a1 = l->z + (uint64_t)cells(l, l->tile);
    for (int i = 0; i < s->count; i++) {
        lamp *o = &s->lamps[i];
        if (o == l || !o->valid) continue;
        uint64_t b0 = o->kz, b1 = o->kz + (uint64_t)cells(o, o->ktile);
        if (a0 < b1 && b0 < a1) o->valid = false;
    }
}

/* Sets tile k's uniforms on the depth program of variant a. */
static void set_tile(const atlas_state *s, const lamp *l, int a, int k) {
    bool paraboloid = l->faces == 2;
    const GLint *u = s->u[paraboloid][a];
    if (!paraboloid) {
        float m[16];
        sb_m4_to_float(l->face_vp[k], m);
        glUniformMatrix4fv(u[0], 1, GL_FALSE, m);
        return;
    }
    sb_lamp_paraboloid_uniforms(u, l->pos, l->near, l->far, k ? -1.0f : 1.0f);
}

/* Draws one lamp's tiles (casters culled per cube face, or to its range for the paraboloids); returns how many
 * tiles had casters. */
static int draw_tiles(atlas_state *s, lamp *l, sb_frame *f) {
    const sb_scene *sc = f->gpu->scene;
    int drawn = 0;
    sb_frame_shade_point(f, l->pos);   /* its single-sided draws keep the triangles facing it */
    bool paraboloid = l->faces == 2;
    if (paraboloid) glEnable(GL_CLIP_DISTANCE0);   /* each hemisphere clipped at its rim */
    for (int k = 0; k < l->faces; k++) {
        int x, y;
        face_rect(l, k, &x, &y);
        glViewport(x, y, l->tile, l->tile);
        glScissor(x, y, l->tile, l->tile);
        glClear(GL_DEPTH_BUFFER_BIT);
        double planes[6][4];
        if (!paraboloid) sb_frustum_planes(l->face_vp[k], planes);
        else sb_cube_planes(l->pos, l->far, planes);
        uint32_t n = sb_scene_collect(sc, (const double(*)[4])planes, 6, f->scratch);
        if (!n) continue;
        drawn++;
        for (int a = 0; a < 2 && s->depth_prog[paraboloid][a]; a++) {
            glUseProgram(s->depth_prog[paraboloid][a]);
            set_tile(s, l, a, k);
            for (uint32_t i = 0; i < n; i++)
                if (sb_draw_variant(f->gpu, f->scratch[i]) == a) sb_submit(f, f->scratch[i], 1);
            sb_submit_flush(f);
        }
    }
    glDisable(GL_CLIP_DISTANCE0);
    return drawn;
}

/* A lamp's record for the lookup (vis_atlas.glsl): the lamp and range; near, far, tile texels, kind; the tiles; the
 * cube's faces. */
static void write_record(const atlas_state *s, const lamp *l, float *r) {
    float size = (float)s->d->size;
    memset(r, 0, sizeof(float) * LREC * 4);
    r[0] = (float)l->pos.x, r[1] = (float)l->pos.y, r[2] = (float)l->pos.z, r[3] = (float)l->range;
    r[4] = (float)l->near, r[5] = (float)l->far, r[6] = (float)l->tile;
    r[7] = l->faces == 1 ? 2.0f : l->faces == 2 ? 1.0f : 0.0f;   /* the lookup: 0 cube, 1 paraboloids, 2 one spot tile */
    for (int k = 0; l->tile && k < l->faces; k++) {
        int x, y;
        face_rect(l, k, &x, &y);
        float *q = r + 4 * (2 + k);
        q[0] = x / size, q[1] = y / size, q[2] = l->tile / size;
        if (l->faces != 2) sb_m4_to_float(l->face_vp[k], r + 4 * (8 + 4 * k));
    }
    float *c = r + 4 * 32;   /* a spot's cone, for the shading */
    if (l->cone > 0) c[0] = (float)l->dir.x, c[1] = (float)l->dir.y, c[2] = (float)l->dir.z, c[3] = (float)(1 - cos(l->cone));
}

static void atlas_frame(void *state, sb_frame *f) {
    atlas_state *s = state;
    const atlas_desc *d = s->d;
    /* the tiles of every lamp as a timed frame gives them; an evaluation pass draws and shades only the one it
       scores, at the place and size the frame gives it (dropped, downscaled: as timed frames see it) */
    int first, end;
    sb_frame_light_range(f, s->count, &first, &end);
    int only = f->eval_light ? first : -1;
    sb_stage_begin(f, &sb_stage_cascade);
    int n = allocate(s, f), rendered = 0, cached = 0;
    invalidate_moved(s, f);
    /* the stale check draws every tile afresh into an atlas of its own, leaving the kept one as it was */
    if (f->bypass_cache && !s->fresh_fbo) make_atlas(s, &s->fresh_tex, &s->fresh_fbo);
    GLuint atlas = f->bypass_cache ? s->fresh_tex : s->tex;
    glBindFramebuffer(GL_FRAMEBUFFER, f->bypass_cache ? s->fresh_fbo : s->fbo);
    sb_shadow_depth_state((float)d->slope);
    glDisable(GL_CULL_FACE);
    glEnable(GL_SCISSOR_TEST);
    glBindVertexArray(f->gpu->vao);
    for (int k = 0; k < n; k++) {
        lamp *l = &s->lamps[s->order[k]];
        if (only >= 0 && s->order[k] != only) continue;
        if (kept(s, l, f)) {
            cached += l->faces;
            continue;
        }
        rendered += draw_tiles(s, l, f);
        if (f->bypass_cache) continue;   /* the stale check's own atlas: the kept one's state unchanged */
        forget_under(s, l);
        l->valid = d->cache;
        l->kz = l->z, l->ktile = l->tile, l->kpos = l->pos;
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_SCISSOR_TEST);
    f->counters.cascades_rendered = rendered;
    f->counters.cascades_cached = cached;
    int tiles = 0;
    for (int k = 0; k < n; k++) tiles += s->lamps[s->order[k]].faces;
    f->counters.cascades_skipped = tiles - rendered - cached;
    /* the records of the lamps whose range reaches the view (those without tiles lit) */
    int shown = 0;
    for (int i = 0; i < s->count; i++)
        if ((only < 0 || i == only) && s->lamps[i].importance > 0) {
            s->shown_pos[shown] = s->lamps[i].pos, s->shown_range[shown] = s->lamps[i].range;
            write_record(s, &s->lamps[i], s->records + (size_t)shown++ * LREC * 4);
        }
    glBindBuffer(GL_TEXTURE_BUFFER, s->buf);
    if (shown) glBufferSubData(GL_TEXTURE_BUFFER, 0, (GLsizeiptr)shown * LREC * 16, s->records);
    sb_stage_end(f, &sb_stage_cascade);

    /* grid=on: each cluster's lamps among those records, as the camera pass will see them */
    if (d->grid) {
        sb_stage_begin(f, &sb_stage_clusters);
        uint32_t items = sb_lightgrid_build(&s->grid, f, s->shown_pos, s->shown_range, shown);
        sb_count(&f->counters, &atlas_counters[C_GRID], items);
        sb_stage_end(f, &sb_stage_clusters);
    }

    sb_stage_begin(f, &sb_stage_final);
    if (only >= 0) sb_frame_shade_light_of(f, s->lamps[only].light);   /* what the evaluation scores */
    glUseProgram(s->fp.prog);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, atlas);
    glUniform1i(s->u_atlas, 0);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_BUFFER, s->buf_tex);
    glUniform1i(s->u_lights, 1);
    glActiveTexture(GL_TEXTURE0);
    if (d->grid) sb_lightgrid_bind(&s->grid, 2);
    glUniform1i(s->u_count, shown);
    glUniform1f(s->u_bias, (float)d->bias);
    glUniform1f(s->u_normal, (float)d->normal);
    sb_final_pass(f, &s->fp, false);
    sb_stage_end(f, &sb_stage_final);
}

static void atlas_destroy(void *state) {
    atlas_state *s = state;
    sb_final_prog_free(&s->fp);
    for (int kp = 0; kp < 2; kp++)
        for (int a = 0; a < 2; a++)
            if (s->depth_prog[kp][a]) glDeleteProgram(s->depth_prog[kp][a]);
    if (s->fbo) glDeleteFramebuffers(1, &s->fbo);
    if (s->tex) glDeleteTextures(1, &s->tex);
    if (s->fresh_fbo) glDeleteFramebuffers(1, &s->fresh_fbo);
    if (s->fresh_tex) glDeleteTextures(1, &s->fresh_tex);
    if (s->buf_tex) glDeleteTextures(1, &s->buf_tex);
    sb_lightgrid_free(&s->grid);
    free(s->shown_pos);
    free(s->shown_range);
    if (s->buf) glDeleteBuffers(1, &s->buf);
    free(s->lamps);
    free(s->order);
    free(s->records);
}

/* An atlas that could not give every lamp in view the tiles its policy asked for: said, with exact counts. */
static void atlas_warn(const sb_counters *frames, int n, char *out, size_t len) {
    int short_frames = 0, dropped = 0, down = 0, lamps = 0;
    for (int i = 0; i < n; i++) {
        double c[C_COUNT] = {0};
        for (int k = 0; k < C_COUNT; k++) sb_counted(&frames[i], &atlas_counters[k], &c[k]);
        if (!(c[C_DROPPED] || c[C_DOWNSCALED])) continue;
        short_frames++;
        if (c[C_DROPPED] > dropped) dropped = (int)c[C_DROPPED];
        if (c[C_DOWNSCALED] > down) down = (int)c[C_DOWNSCALED];
        int inview = (int)(c[C_SHADOWED] + c[C_DROPPED]);
        if (inview > lamps) lamps = inview;
    }
    if (!short_frames) return;
    char what[128];
    if (dropped && down)
        snprintf(what, sizeof what, "up to %d lamp(s) dropped (lit without shadows) and up to %d downscaled", dropped, down);
    else if (dropped) snprintf(what, sizeof what, "up to %d lamp(s) dropped (lit without shadows)", dropped);
    else snprintf(what, sizeof what, "up to %d lamp(s) downscaled", down);
    snprintf(out, len, "atlas: %s, of up to %d in view, in %d of %d frames: a larger size= (or max_lights=) holds them",
             what, lamps, short_frames, n);
}

const sb_technique sb_technique_atlas = {
    .name = "atlas",
    .summary = "every lamp's shadows in one depth atlas, tiles sized by policy within a budget (HDRP's atlas)",
    .params = atlas_params,
    .param_count = (int)SB_COUNT(atlas_params),
    .desc_size = sizeof(atlas_desc),
    SB_STAGES(&sb_stage_cascade, &sb_stage_clusters, &sb_stage_final),
    .needs = SB_NEEDS_POINT_LIGHT,
    .lights = SB_LIGHTS_EVERY_LAMP,
    .state_size = sizeof(atlas_state),
    .check = atlas_check,
    .supported = atlas_supported,
    .shadow_bytes = atlas_shadow_bytes,
    .create = atlas_create,
    .frame = atlas_frame,
    .counters = atlas_counters,
    .counter_count = C_COUNT,
    .warn = atlas_warn,
    .destroy = atlas_destroy,
};
