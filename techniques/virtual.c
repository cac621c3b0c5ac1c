/* virtual.c - virtual shadow maps for the sun (the scheme Unreal Engine 5 ships, on GL 4.5 without sparse
 * textures, as Blender EEVEE's page atlas does).
 *
 * The light sees the scene through a clipmap: `levels` virtual maps of res x res texels around the camera,
 * each level's texel twice the one below it, the coarsest covering the scene twice over. A level is cut into
 * pages of `page` texels; only pages a visible pixel needs are ever rendered, at the level whose texel matches
 * the pixel's footprint (times 2^lod). A frame:
 *
 *   zpass    the camera's depth (reused by the final pass);
 *   minmax   marking: a compute pass puts each pixel back in the world and sets the bit of the page it needs
 *            (virtual_mark.comp); the bits are read back (the frame waits for them: a GPU-driven allocator
 *            would not, see docs/techniques.md);
 *   cascade  the pages: a needed page already in the pool (cache=on: the same level, page and light since it
 *            was drawn) is kept; the others get a slot of the physical pool (`pool` MiB: an atlas of slots, a
 *            slot being a page with a border of BORDER texels so filter taps stay inside), free slots first,
 *            then the least recently needed, coarse levels before fine ones; each is drawn with its own
 *            orthographic view into its slot (one viewport a page), its casters culled to the page over the
 *            BVH. The page table (slot + 1 for each resident page of every level's window) is uploaded;
 *   final    the lookup through the table (vis_virtual.glsl).
 *
 * Pages are keyed by their absolute place in the level's page grid, so a camera that moves keeps every page it
 * still needs; a sun that moves invalidates all of them, a caster that moves the pages its light-space box
 * overlaps before and after the move (pages_invalidated). A pool too small for a frame's pages has the finest
 * level's pages give way to their parents a level coarser until the rest fit (pool_overflow counts the pages
 * given up; the run warns): their pixels are looked up in the parent, never in another page's texels. */
#include <stdlib.h>
#include <string.h>

#include "lightfit.h"
#include "shaders.h"

typedef struct virtual_desc {
    int res, page, pool, levels, filter, cache, split;
    double lod, bias, slope, normal;
} virtual_desc;

enum { FILTER_NONE, FILTER_HW, FILTER_PCF3 };
enum { BORDER = 2, MAX_LEVELS = 16, MAX_PAGES = 512, MAX_SLOTS = 65535 /* a table entry is 16 bits */ };

static const sb_param_def virtual_params[] = {
    SB_PARAM_I(virtual_desc, res, 16384, 256, 65536, "texels per side of each clipmap level's virtual map",
               .tune = "512,1024,2048", .role = SB_PARAM_RES),
    SB_PARAM_I(virtual_desc, page, 128, 16, 1024, "texels per side of a page (a power of two dividing res)"),
    SB_PARAM_I(virtual_desc, pool, 128, 1, 4096, "MiB the pages and their table may hold (32-bit depth)"),
    SB_PARAM_I(virtual_desc, levels, 16, 1, MAX_LEVELS,
               "clipmap levels: the coarsest's texel is a pixel's footprint across the scene, each finer one's half"),
    SB_PARAM_F(virtual_desc, lod, -1.5, -3, 4, "resolution bias: a level's texel is at most 2^lod pixel footprints"),
    SB_PARAM_FA(virtual_desc, bias, 1, 0, 100, "constant depth bias, in texels of the level"),
    SB_PARAM_FA(virtual_desc, slope, 0.5, 0, 100, "slope-scaled bias (glPolygonOffset factor)"),
    SB_PARAM_FA(virtual_desc, normal, 0.25, 0, 100, "normal offset, in texels of the level"),
    SB_PARAM_E(virtual_desc, filter, hw, "none|hw|pcf3", "shadow filter", .tune = "none,hw,pcf3"),
    SB_PARAM_E(virtual_desc, cache, on, "off|on",
               "keep a page across frames while its level, place and light hold and no moved caster's light-space box "
               "overlaps it", .role = SB_PARAM_CACHE),
    SB_PARAM_E_LATE(virtual_desc, split, off, "off|on",
                    "cache=on: pages hold the still casters only, kept while nothing still changes; each frame a page a "
                    "moving caster overlaps is copied and the moving casters drawn over the copy (UE5's static and "
                    "dynamic cache)"),
};

/* Its counters (columns of their own: a partition of the pages needed, drawn or kept for themselves or given up;
 * the stand-ins drawn or kept in their place counted apart, inside rendered and cached). */
enum { C_NEEDED, C_RENDERED, C_CACHED, C_OVERFLOW, C_STAND_IN, C_INVALIDATED, C_DYNAMIC, C_COUNT };
static const sb_counter_def virtual_counters[C_COUNT] = {
    [C_NEEDED] = {.name = "pages_needed", .unit = "count", .stats = SB_STAT_MEAN,
                  .doc = "virtual: pages the frame's visible pixels need (empty: no virtual map)"},
    [C_RENDERED] = {.name = "pages_rendered", .unit = "count", .stats = SB_STAT_MEAN,
                    .doc = "virtual: needed pages drawn this frame (not in the pool, or cache=off)"},
    [C_CACHED] = {.name = "pages_cached", .unit = "count", .stats = SB_STAT_MEAN, .flags = SB_LOWER_WORSE,
                  .doc = "virtual: needed pages kept from an earlier frame (the same level, place and light)"},
    [C_OVERFLOW] = {.name = "pool_overflow", .unit = "count", .stats = SB_STAT_MEAN | SB_STAT_MAX,
                    .doc = "virtual: needed pages the pool had no slot for, given up (their pixels use the page one "
                           "level coarser)"},
    [C_STAND_IN] = {.name = "pages_stand_in", .unit = "count", .stats = SB_STAT_MEAN,
                    .doc = "virtual: coarser pages drawn or kept in place of pages given up (counted in "
                           "pages_rendered and pages_cached: rendered + cached - stand_in + pool_overflow = needed)"},
    [C_INVALIDATED] = {.name = "pages_invalidated", .unit = "count", .stats = SB_STAT_MEAN, .moving = true,
                       .doc = "virtual cache=on: kept pages dropped because a moved caster's light-space box, before "
                              "or after the move, overlaps them (empty: nothing moves, or no virtual map)"},
    [C_DYNAMIC] = {.name = "pages_dynamic", .unit = "count", .stats = SB_STAT_MEAN, .moving = true,
                   .doc = "virtual split=on: pages a moving caster's light-space box overlaps, copied from the kept "
                          "still page with the moving casters drawn over the copy this frame (0 without split)"},
};

/* The pool's layout, from the parameters alone (the GPU-memory check, shadow_mb and create share it). */
typedef struct pool_layout {
    int pages;                  /* per side of a level: res / page */
    int slot;                   /* texels per side of a slot: page + 2 BORDER */
    int slots, slots_x, rows;   /* slots in all, per atlas row, rows */
    double table_bytes;         /* the page table (16 bits a page of every level) and the request bits */
    double bytes;               /* all of it: atlas and table */
} pool_layout;

static pool_layout layout_of(const virtual_desc *d) {
    pool_layout p = {.pages = d->res / d->page, .slot = d->page + 2 * BORDER};
    double entries = (double)d->levels * p.pages * p.pages;
    p.table_bytes = ceil(entries / 2) * 4 + ceil(entries / 32) * 4;   /* 16-bit entries in uints; request bits */
    double slot_bytes = 4.0 * p.slot * p.slot;
    double room = (double)d->pool * 1048576.0 - p.table_bytes;
    int n = room > 0 ? (int)fmin(floor(room / slot_bytes), MAX_SLOTS) : 0;
    p.slots_x = n > 0 ? (int)ceil(sqrt((double)n)) : 0;
    p.rows = n > 0 ? n / p.slots_x : 0;
    p.slots = p.slots_x * p.rows;
    p.bytes = p.slots * slot_bytes + p.table_bytes;
    return p;
}

static bool virtual_check(const void *desc, sb_err *err) {
    const virtual_desc *d = desc;
    if (d->page & (d->page - 1))
        return sb_fail(err, "page=%d is not a power of two (valid: 16, 32, 64, 128, 256, 512, 1024)", d->page);
    if (d->res % d->page)
        return sb_fail(err, "res=%d is not a multiple of page=%d (valid: res = k x %d, up to %d pages a side)", d->res,
                       d->page, d->page, MAX_PAGES);
    if (d->res / d->page > MAX_PAGES)
        return sb_fail(err, "res=%d holds %d pages a side at page=%d: at most %d (valid: res <= %d)", d->res,
                       d->res / d->page, d->page, MAX_PAGES, MAX_PAGES * d->page);
    if (d->split && !d->cache)
        return sb_fail(err, "split=on needs cache=on (the still pages it keeps are the cache)");
    pool_layout p = layout_of(d);
    if (p.slots < 1)
        return sb_fail(err, "pool=%d MiB holds no page of %d texels with its table (valid: pool >= %.0f MiB here)",
                       d->pool, d->page, ceil((p.table_bytes + 4.0 * p.slot * p.slot) / 1048576.0));
    return true;
}

static double virtual_shadow_bytes(const sb_technique *t, const void *desc) {
    (void)t;
    return layout_of(desc).bytes;
}

static bool virtual_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    const virtual_desc *d = desc;
    pool_layout p = layout_of(d);
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (p.slots_x * p.slot > max_size || p.rows * p.slot > max_size)
        return sb_fail(why, "virtual:pool=%d: an atlas of %dx%d texels exceeds GL_MAX_TEXTURE_SIZE %d of %s", d->pool,
                       p.slots_x * p.slot, p.rows * p.slot, max_size, rc->gpu->ctx->renderer);
    char who[96];
    snprintf(who, sizeof who, "virtual:pool=%d", d->pool);
    return sb_gpu_memory_fits(rc->gpu, p.bytes, who, "page pool", why);
}

typedef struct page_key {
    int level;
    int64_t x, y;               /* the page's place in its level's grid (absolute: page x covers [x, x+1) pages) */
    bool stand_in;              /* needed only for a finer page the pool had no room for */
} page_key;

/* The clipmap's uniforms (virtual_common.glsl) in one program: the marking's or the lookup's. */
typedef struct clip_locs {
    GLint light, eye, fwd, foot, texel0, win;
} clip_locs;

static clip_locs clip_locations(GLuint prog) {
    return (clip_locs){glGetUniformLocation(prog, "u_vlight"), glGetUniformLocation(prog, "u_veye"),
                       glGetUniformLocation(prog, "u_vfwd"), glGetUniformLocation(prog, "u_vfoot"),
                       glGetUniformLocation(prog, "u_vtexel0"), glGetUniformLocation(prog, "u_vwin")};
}

typedef struct virtual_state {
    virtual_desc d;
    pool_layout p;
    int words;                  /* request bits, in uints */
    GLuint atlas, fbo, req_buf, table_buf;
    GLuint depth_prog[2];
    GLint u_vp[2];
    GLuint mark_prog;
    GLint m_depth, m_inv, m_margin;
    clip_locs mark_clip, final_clip;
    sb_final_prog fp;
    GLint u_atlas, u_atlas_texel, u_vdepth, u_vrange, u_bias, u_normal, u_light;
    /* the clipmap: from the scene and the light */
    sb_v3 sun;                  /* the light the pool's pages were drawn under */
    sb_m4 lview;
    double texel0, zn, zf;
    int64_t origin[MAX_LEVELS][2];  /* this frame: each level's window corner, in pages */
    /* the pool */
    page_key *slot_key;         /* level -1: the slot holds nothing valid */
    int *slot_used;             /* the frame (count) that last needed it */
    int *hash, hash_cap;        /* slot + 1 by key, open addressing, rebuilt each frame */
    uint32_t *req;
    uint16_t *table;
    page_key *need, *missing;
    int *free_slots;
    int frame_no;
    bool fitted;
    /* split=on: this frame's copies of pages with the moving casters drawn over them (the page, its copy's slot) */
    page_key *over_key;
    int *over_slot, *over_keep, nover;   /* the page's slot, and where its still page is kept aside (-1: given up) */
} virtual_state;

/* World size of a pixel per unit of view depth, times 2^lod: the footprint a level's texel is matched to. */
static double foot_per_depth(const virtual_state *s, const sb_frame *f) {
    return 2 * tan(f->cam.fov_deg * SB_PI / 360) / f->gpu->height * pow(2.0, s->d.lod);
}

static uint64_t key_hash(page_key k) {
    uint64_t h = (uint64_t)k.level * 0x9E3779B97F4A7C15ull ^ (uint64_t)k.x * 0xC2B2AE3D27D4EB4Full ^
                 (uint64_t)k.y * 0x165667B19E3779F9ull;
    return h ^ (h >> 29);
}
static bool key_eq(page_key a, page_key b) { return a.level == b.level && a.x == b.x && a.y == b.y; }

static void hash_rebuild(virtual_state *s) {
    memset(s->hash, 0, sizeof(int) * (size_t)s->hash_cap);
    for (int i = 0; i < s->p.slots; i++) {
        if (s->slot_key[i].level < 0) continue;
        uint64_t h = key_hash(s->slot_key[i]) & (uint64_t)(s->hash_cap - 1);
        while (s->hash[h]) h = (h + 1) & (uint64_t)(s->hash_cap - 1);
        s->hash[h] = i + 1;
    }
}

static int hash_find(const virtual_state *s, page_key k) {
    for (uint64_t h = key_hash(k) & (uint64_t)(s->hash_cap - 1); s->hash[h]; h = (h + 1) & (uint64_t)(s->hash_cap - 1))
        if (key_eq(s->slot_key[s->hash[h] - 1], k)) return s->hash[h] - 1;
    return -1;
}

static void invalidate(virtual_state *s) {
    for (int i = 0; i < s->p.slots; i++) s->slot_key[i].level = -1, s->slot_used[i] = -1;
}

static bool make_programs(virtual_state *s, const sb_gpu *g, sb_err *err) {
    char defs[256];
    snprintf(defs, sizeof defs,
             "#define SB_LEVELS %d\n#define SB_PAGES %d\n#define SB_PAGE %d\n#define SB_SLOT %d\n#define SB_BORDER %d\n"
             "#define SB_SLOTS_X %d\n#define SB_FILTER %d\n",
             s->d.levels, s->p.pages, s->d.page, s->p.slot, BORDER, s->p.slots_x, s->d.filter);
    const char *mark[] = {sb_shader_virtual_common_glsl, sb_shader_virtual_mark_comp};
    const sb_shader_src ms[] = {{GL_COMPUTE_SHADER, mark, 2}};
    if (!(s->mark_prog = sb_gpu_link("virtual page marking", defs, ms, 1, err))) return false;
    s->m_depth = glGetUniformLocation(s->mark_prog, "u_depth");
    s->m_inv = glGetUniformLocation(s->mark_prog, "u_inv_view_proj");
    s->m_margin = glGetUniformLocation(s->mark_prog, "u_margin");
    s->mark_clip = clip_locations(s->mark_prog);
    const char *fs[] = {sb_shader_depth_frag};
    const char *vs[] = {sb_shader_virtual_depth_vert};
    const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, 1}, {GL_FRAGMENT_SHADER, fs, 1}};
    for (int a = 0; a < (g->scene->alpha_tested_draws ? 2 : 1); a++) {   /* opaque casters, then alpha-tested */
        if (!(s->depth_prog[a] = sb_gpu_link(a ? "virtual page depth (alpha-tested draws)" : "virtual page depth",
                                             a ? "" : sb_opaque_define(g), st, 2, err)))
            return false;
        s->u_vp[a] = glGetUniformLocation(s->depth_prog[a], "u_vp");
    }
    const char *vis[] = {sb_shader_virtual_common_glsl, sb_shader_vis_virtual_glsl};
    if (!sb_final_prog_create_parts(&s->fp, g, "virtual", vis, 2, defs, err)) return false;
    const char *names[] = {"u_atlas", "u_atlas_texel", "u_vdepth", "u_vrange", "u_bias", "u_normal", "u_light"};
    GLint *locs[] = {&s->u_atlas, &s->u_atlas_texel, &s->u_vdepth, &s->u_vrange, &s->u_bias, &s->u_normal, &s->u_light};
    for (size_t i = 0; i < SB_COUNT(names); i++) *locs[i] = glGetUniformLocation(s->fp.prog, names[i]);
    s->final_clip = clip_locations(s->fp.prog);
    return true;
}

/* The clipmap of this light and camera: depth spans the scene's (every page of every level compares alike);
 * the coarsest level's texel is the footprint of a pixel as far away as the scene is wide (the farthest a camera
 * in the scene sees it; its window also covers the scene twice over at least), and each finer level halves it.
 * Fitted at the first frame (the camera's field of view) and again when the light moves. */
static void fit_clipmap(virtual_state *s, const sb_frame *f) {
    const sb_gpu *g = f->gpu;
    const sb_aabb *b = &g->scene->bounds;
    s->sun = g->sun;
    s->lview = sb_light_view(g->sun);
    sb_v3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    for (int k = 0; k < 8; k++) {
        sb_v3 q = sb_m4_point(s->lview, sb_aabb_corner(b, k));
        lo = sb_v3_min(lo, q);
        hi = sb_v3_max(hi, q);
    }
    double extent = fmax(fmax(hi.x - lo.x, hi.y - lo.y), 1e-6);
    double far = sb_v3_len(sb_v3_sub(b->hi, b->lo)) * foot_per_depth(s, f);
    s->texel0 = fmax(2 * extent / s->d.res, far) / pow(2.0, s->d.levels - 1);
    double pad = 1e-4 * (hi.z - lo.z) + 1e-6;
    s->zn = -hi.z - pad;   /* light-space z grows toward the light */
    s->zf = -lo.z + pad;
    s->fitted = true;
}

static bool virtual_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    virtual_state *s = state;
    const sb_gpu *g = rc->gpu;
    s->d = *(const virtual_desc *)desc;
    s->p = layout_of(&s->d);
    int entries = s->d.levels * s->p.pages * s->p.pages;
    s->words = (entries + 31) / 32;
    s->slot_key = sb_xcalloc((size_t)s->p.slots, sizeof *s->slot_key);
    s->slot_used = sb_xcalloc((size_t)s->p.slots, sizeof *s->slot_used);
    for (s->hash_cap = 16; s->hash_cap < 2 * s->p.slots; s->hash_cap *= 2) {}
    s->hash = sb_xcalloc((size_t)s->hash_cap, sizeof *s->hash);
    s->req = sb_xcalloc((size_t)s->words, sizeof *s->req);
    s->table = sb_xcalloc((size_t)entries + 1, sizeof *s->table);
    s->need = sb_xcalloc((size_t)entries, sizeof *s->need);
    s->missing = sb_xcalloc((size_t)entries, sizeof *s->missing);
    s->free_slots = sb_xcalloc((size_t)s->p.slots, sizeof *s->free_slots);
    s->over_key = sb_xcalloc((size_t)entries + 1, sizeof *s->over_key);
    s->over_slot = sb_xcalloc((size_t)entries + 1, sizeof *s->over_slot);
    s->over_keep = sb_xcalloc((size_t)entries + 1, sizeof *s->over_keep);
    invalidate(s);

    s->atlas = sb_shadow_texture(GL_TEXTURE_2D, GL_DEPTH_COMPONENT32F, s->p.slots_x * s->p.slot, s->p.rows * s->p.slot,
                                 1, s->d.filter == FILTER_HW);
    glGenFramebuffers(1, &s->fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, s->atlas, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return sb_fail(err, "virtual:pool=%d: the page atlas's framebuffer is incomplete", s->d.pool);
    GLuint bufs[2];
    glGenBuffers(2, bufs);
    s->req_buf = bufs[0];
    s->table_buf = bufs[1];
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s->req_buf);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)s->words * 4, NULL, GL_DYNAMIC_READ);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s->table_buf);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(entries + 1) / 2 * 4, NULL, GL_DYNAMIC_DRAW);
    return make_programs(s, g, err) && sb_gl_check("virtual", err);
}

static double level_texel(const virtual_state *s, int l) { return s->texel0 * ldexp(1.0, l); }

/* Each level's window: pages x pages around the camera, its corner on the page grid. */
static void place_windows(virtual_state *s, const sb_frame *f) {
    sb_v3 c = sb_m4_point(s->lview, sb_v3_sub(f->cam.pos, f->gpu->scene->origin));
    for (int l = 0; l < s->d.levels; l++) {
        double span = s->d.page * level_texel(s, l);
        s->origin[l][0] = (int64_t)floor(c.x / span) - s->p.pages / 2;
        s->origin[l][1] = (int64_t)floor(c.y / span) - s->p.pages / 2;
    }
}

/* The uniforms marking and lookup share (virtual_common.glsl), into the bound program whose locations are c. */
static void set_clipmap_uniforms(const virtual_state *s, const sb_frame *f, const clip_locs *c) {
    float m[16], win[MAX_LEVELS][2];
    sb_m4_to_float(s->lview, m);
    glUniformMatrix4fv(c->light, 1, GL_FALSE, m);
    sb_v3 eye = sb_v3_sub(f->cam.pos, f->gpu->scene->origin);
    glUniform3f(c->eye, (float)eye.x, (float)eye.y, (float)eye.z);
    glUniform3f(c->fwd, (float)f->cam.forward.x, (float)f->cam.forward.y, (float)f->cam.forward.z);
    glUniform1f(c->foot, (float)foot_per_depth(s, f));
    glUniform1f(c->texel0, (float)s->texel0);
    for (int l = 0; l < s->d.levels; l++) {
        double span = s->d.page * level_texel(s, l);
        win[l][0] = (float)(s->origin[l][0] * span);
        win[l][1] = (float)(s->origin[l][1] * span);
    }
    glUniform2fv(c->win, s->d.levels, &win[0][0]);
}

/* Marking: the pages the frame's pixels need, read back into s->req. */
static void mark_pages(virtual_state *s, sb_frame *f) {
    const sb_gpu *g = f->gpu;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s->req_buf);
    glClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, NULL);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, s->req_buf);
    glUseProgram(s->mark_prog);
    set_clipmap_uniforms(s, f, &s->mark_clip);
    sb_m4 inv;
    float m[16];
    sb_m4_invert(f->view_proj, &inv);
    sb_m4_to_float(inv, m);
    glUniformMatrix4fv(s->m_inv, 1, GL_FALSE, m);
    glUniform1f(s->m_margin, 1.0f);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g->depth_tex);
    glUniform1i(s->m_depth, 1);
    glDispatchCompute((GLuint)(g->width + 7) / 8, (GLuint)(g->height + 7) / 8, 1);
    glActiveTexture(GL_TEXTURE0);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)s->words * 4, s->req);
}

static int64_t half_down(int64_t v) { return v >= 0 ? v / 2 : -((-v + 1) / 2); }

static int by_place(const void *a, const void *b) {
    const page_key *p = a, *q = b;
    if (p->level != q->level) return p->level - q->level;
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    if (p->y != q->y) return p->y < q->y ? -1 : 1;
    return p->stand_in - q->stand_in;   /* a page needed for itself before its stand-in twin */
}

/* A frame needing more pages than the pool has slots: the finest level's pages give way to their parents (the
 * page of the next level holding each; the grids nest), level after level, until the rest fit. The pixels of
 * a page given up look it up one level coarser (vis_virtual.glsl). Returns the pages needed for themselves
 * that were given up. */
static int coarsen_to_fit(virtual_state *s, int *needed) {
    int n = *needed, given_up = 0;
    while (n > s->p.slots) {
        int finest = s->d.levels;
        for (int j = 0; j < n; j++)
            if (s->need[j].level < finest) finest = s->need[j].level;
        if (finest >= s->d.levels - 1) break;   /* the coarsest level alone: what fits is drawn (update_pool) */
        for (int j = 0; j < n; j++) {
            page_key *k = &s->need[j];
            if (k->level != finest) continue;
            given_up += !k->stand_in;
            *k = (page_key){finest + 1, half_down(k->x), half_down(k->y), true};
        }
        qsort(s->need, (size_t)n, sizeof *s->need, by_place);
        int m = 0;
        for (int j = 0; j < n; j++)
            if (!m || !key_eq(s->need[m - 1], s->need[j])) s->need[m++] = s->need[j];
        n = m;
    }
    *needed = n;
    return given_up;
}

static int by_level_down(const void *a, const void *b) {   /* coarse levels first: they cover the most */
    return ((const page_key *)b)->level - ((const page_key *)a)->level;
}

static const virtual_state *g_sort_state;
static int by_staleness(const void *a, const void *b) {   /* empty slots first, then the least recently needed */
    const virtual_state *s = g_sort_state;
    int ia = *(const int *)a, ib = *(const int *)b;
    int va = s->slot_key[ia].level >= 0, vb = s->slot_key[ib].level >= 0;
    if (va != vb) return va - vb;
    if (s->slot_used[ia] != s->slot_used[ib]) return s->slot_used[ia] < s->slot_used[ib] ? -1 : 1;
    return ia - ib;
}

/* Which casters a page's draw takes: all, the still ones (split=on's kept pages), the moving ones (its copies). */
enum { CASTERS_ALL, CASTERS_STILL, CASTERS_MOVING };

/* Page k's window with its border, in light space: x0, y0, x1, y1 (as light_rect's). */
static void page_rect(const virtual_state *s, page_key k, double r[4]) {
    double t = level_texel(s, k.level), pg = s->d.page;
    r[0] = ((double)k.x * pg - BORDER) * t, r[2] = ((double)(k.x + 1) * pg + BORDER) * t;
    r[1] = ((double)k.y * pg - BORDER) * t, r[3] = ((double)(k.y + 1) * pg + BORDER) * t;
}

/* Whether two light-space windows (x0, y0, x1, y1) overlap. */
static bool rects_meet(const double a[4], const double b[4]) {
    return a[2] >= b[0] && a[0] <= b[2] && a[3] >= b[1] && a[1] <= b[3];
}

/* The orthographic view of page k's window with its border. */
static sb_m4 page_view(const virtual_state *s, page_key k) {
    double r[4];
    page_rect(s, k, r);
    return sb_m4_mul(sb_m4_ortho(r[0], r[2], r[1], r[3], s->zn, s->zf), s->lview);
}

/* Draws page k into slot i: the page's window with its border, its casters (of the kind asked) culled over the
 * BVH; `clear`: the slot is cleared first (a copy keeps what it holds). */
static void render_page(virtual_state *s, sb_frame *f, page_key k, int i, int casters, bool clear) {
    const sb_gpu *g = f->gpu;
    sb_m4 vp = page_view(s, k);
    double planes[6][4];
    sb_frustum_planes(vp, planes);
    int sx = (i % s->p.slots_x) * s->p.slot, sy = (i / s->p.slots_x) * s->p.slot;
    glViewport(sx, sy, s->p.slot, s->p.slot);
    glScissor(sx, sy, s->p.slot, s->p.slot);
    if (clear) glClear(GL_DEPTH_BUFFER_BIT);
    uint32_t n = sb_scene_collect(g->scene, (const double(*)[4])planes, 4, f->scratch);   /* x and y: depth spans all */
    float m[16];
    sb_m4_to_float(vp, m);
    for (int a = 0; a < 2 && s->depth_prog[a]; a++) {
        glUseProgram(s->depth_prog[a]);
        glUniformMatrix4fv(s->u_vp[a], 1, GL_FALSE, m);
        for (uint32_t j = 0; j < n; j++) {
            uint32_t d = f->scratch[j];
            bool moving = g->scene->draws[d].motion != SB_DRAW_STILL;
            if (sb_draw_variant(g, d) != a || (casters == CASTERS_STILL && moving) || (casters == CASTERS_MOVING && !moving))
                continue;
            sb_submit(f, d, 1);
        }
        sb_submit_flush(f);
    }
}

/* The light-space window of a box (origin-relative): its x and y across the light's view. */
static void light_rect(const virtual_state *s, const sb_aabb *b, double r[4]) {
    sb_aabb l = sb_aabb_transform(s->lview, b);
    r[0] = l.lo.x, r[1] = l.lo.y, r[2] = l.hi.x, r[3] = l.hi.y;
}



/* Casters that moved since the last frame: every kept page whose window (with its border) a moved caster's
 * light-space box overlaps, before or after the move, is dropped (UE5's rule; depth does not matter: a page's
 * view spans the scene's depth). Returns how many. */
static int invalidate_moved(virtual_state *s, const sb_frame *f) {
    /* each moved box's window once a frame (before and after its move), then every kept page against them: with
       hundreds of movers, placing the boxes again for each page would be the frame's CPU time */
    const sb_scene *sc = f->gpu->scene;
    double (*rects)[4] = sb_xmalloc(sizeof *rects * 2 * (f->moved_count + 1));
    for (uint32_t i = 0; i < f->moved_count; i++) {
        light_rect(s, &f->moved_from[i], rects[2 * i]);
        light_rect(s, &sc->draws[f->moved[i]].box, rects[2 * i + 1]);
    }
    int dropped = 0;
    for (int i = 0; i < s->p.slots; i++) {
        page_key k = s->slot_key[i];
        if (k.level < 0) continue;
        double pr[4];
        page_rect(s, k, pr);
        for (uint32_t j = 0; j < 2 * f->moved_count; j++)
            if (rects_meet(rects[j], pr)) {
                s->slot_key[i].level = -1, s->slot_used[i] = -1;
                dropped++;
                break;
            }
    }
    free(rects);
    return dropped;
}

/* What became of a frame's pages: drawn, kept from before, left out for want of a slot; of the drawn and the kept,
 * the stand-ins (a coarser page held in place of pages given up). */
typedef struct pool_tally {
    int drawn, left_out, left_out_own, stand_ins;
} pool_tally;

/* The GL state every page's draw shares. */
static void pages_begin(virtual_state *s, const sb_frame *f) {
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo);
    glEnable(GL_SCISSOR_TEST);
    sb_shadow_depth_state((float)s->d.slope);
    glEnable(GL_DEPTH_CLAMP);   /* casters toward the light stay, at depth 0 */
    glBindVertexArray(f->gpu->vao);
}

static void pages_end(void) {
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    glDisable(GL_SCISSOR_TEST);
}

/* Keeps the needed pages the pool holds, gives the others slots and draws them (with the casters asked). */
static void update_pool(virtual_state *s, sb_frame *f, int needed, int casters, pool_tally *t) {
    int cur = ++s->frame_no, nmiss = 0;
    hash_rebuild(s);
    for (int j = 0; j < needed; j++) {
        int i = hash_find(s, s->need[j]);
        if (i >= 0) s->slot_used[i] = cur;
        else s->missing[nmiss++] = s->need[j];
    }
    int nfree = 0;
    for (int i = 0; i < s->p.slots; i++)
        if (s->slot_used[i] != cur) s->free_slots[nfree++] = i;
    g_sort_state = s;
    qsort(s->free_slots, (size_t)nfree, sizeof *s->free_slots, by_staleness);
    qsort(s->missing, (size_t)nmiss, sizeof *s->missing, by_level_down);
    int drawn = nmiss < nfree ? nmiss : nfree;
    *t = (pool_tally){.drawn = drawn, .left_out = nmiss - drawn};
    for (int j = 0; j < needed; j++) t->stand_ins += s->need[j].stand_in;
    for (int j = drawn; j < nmiss; j++) {   /* left out: the coarsest first were drawn, these last */
        t->left_out_own += !s->missing[j].stand_in;
        t->stand_ins -= s->missing[j].stand_in;
    }
    if (!drawn) return;
    pages_begin(s, f);
    for (int j = 0; j < drawn; j++) {
        int i = s->free_slots[j];
        s->slot_key[i] = s->missing[j];
        s->slot_used[i] = cur;
        render_page(s, f, s->missing[j], i, casters, true);
    }
    pages_end();
}

/* The depth of slot `from` into slot `to` (the atlas's texels, the border too). */
static void copy_slot(const virtual_state *s, int from, int to) {
    glCopyImageSubData(s->atlas, GL_TEXTURE_2D, 0, (from % s->p.slots_x) * s->p.slot, (from / s->p.slots_x) * s->p.slot,
                       0, s->atlas, GL_TEXTURE_2D, 0, (to % s->p.slots_x) * s->p.slot, (to / s->p.slots_x) * s->p.slot, 0,
                       s->p.slot, s->p.slot, 1);
}

/* split=on: every needed page a moving caster's light-space box overlaps is kept aside in a slot no page of this
 * frame needs, and the moving casters are drawn over it in its own slot; after the frame the still page is put
 * back and the spare slot is free again (the pages stay kept with the still casters alone).
 * A page with no slot to spare is drawn with every caster in its own slot and given up after the frame, never
 * shown without its moving casters. Returns the pages the moving casters were drawn for. */
static int overlay_moving(virtual_state *s, sb_frame *f, int needed) {
    const sb_scene *sc = f->gpu->scene;
    s->nover = 0;
    hash_rebuild(s);   /* the pages update_pool just drew too */
    double (*rects)[4] = sb_xmalloc(sizeof *rects * (sc->moving_draws + 1));
    uint32_t nr = 0;
    for (uint32_t d = 0; d < sc->draw_count; d++)
        if (sc->draws[d].motion != SB_DRAW_STILL) light_rect(s, &sc->draws[d].box, rects[nr++]);
    int spare = 0, drawn = 0;
    for (int j = 0; j < needed; j++) {
        page_key k = s->need[j];
        int i = hash_find(s, k);
        if (i < 0) continue;   /* left out for want of a slot */
        double pr[4];
        page_rect(s, k, pr);
        bool over = false;
        for (uint32_t r = 0; r < nr && !over; r++)
            over = rects_meet(rects[r], pr);
        if (!over) continue;
        if (!drawn++) pages_begin(s, f);
        while (spare < s->p.slots && s->slot_used[spare] == s->frame_no) spare++;
        if (spare == s->p.slots) {   /* no slot to spare: the page itself, every caster, not kept */
            render_page(s, f, k, i, CASTERS_ALL, true);
            s->over_key[s->nover] = k, s->over_slot[s->nover] = i, s->over_keep[s->nover++] = -1;
            continue;
        }
        /* the still page kept aside in the spare slot, the moving casters drawn over it where it is (the same
           place in the atlas as any draw of that page: the same rasterization), put back after the frame */
        int c = spare++;
        s->slot_key[c].level = -1, s->slot_used[c] = s->frame_no;
        copy_slot(s, i, c);
        render_page(s, f, k, i, CASTERS_MOVING, false);
        s->over_key[s->nover] = k, s->over_slot[s->nover] = i, s->over_keep[s->nover++] = c;
    }
    if (drawn) pages_end();
    free(rects);
    return drawn;
}

/* The stale check (bypass_cache): every needed page the pool kept is drawn again with every caster, in its own
 * slot (a page rasterized at another place in the atlas can differ by a texel at an edge, on llvmpipe and on a
 * GPU alike: that would be no staleness), and the frame then forgets them all (virtual_frame). */
static void redraw_in_place(virtual_state *s, sb_frame *f, int needed) {
    hash_rebuild(s);
    pages_begin(s, f);
    for (int j = 0; j < needed; j++) {
        int i = hash_find(s, s->need[j]);
        if (i >= 0) render_page(s, f, s->need[j], i, CASTERS_ALL, true);
    }
    pages_end();
}

/* After the frame: each still page put back from where it was kept aside, that slot free again; a page drawn
 * whole in its own slot (no slot to spare) given up. */
static void overlay_done(virtual_state *s) {
    for (int o = 0; o < s->nover; o++) {
        int i = s->over_slot[o], c = s->over_keep[o];
        if (c < 0) {
            s->slot_key[i].level = -1, s->slot_used[i] = -1;
            continue;
        }
        copy_slot(s, c, i);
        s->slot_key[c].level = -1, s->slot_used[c] = -1;
    }
    s->nover = 0;
}

/* The page table: slot + 1 for every resident page inside its level's window this frame. */
static void upload_table(virtual_state *s) {
    int P = s->p.pages;
    size_t entries = (size_t)s->d.levels * P * P;
    memset(s->table, 0, sizeof(uint16_t) * entries);
    for (int i = 0; i < s->p.slots; i++) {
        page_key k = s->slot_key[i];
        if (k.level < 0) continue;
        int64_t x = k.x - s->origin[k.level][0], y = k.y - s->origin[k.level][1];
        if (x >= 0 && y >= 0 && x < P && y < P) s->table[((size_t)k.level * P + (size_t)y) * P + (size_t)x] = (uint16_t)(i + 1);
    }
    for (int o = 0; o < s->nover; o++) {   /* split=on: this frame's copies with the moving casters */
        page_key k = s->over_key[o];
        int64_t x = k.x - s->origin[k.level][0], y = k.y - s->origin[k.level][1];
        if (x >= 0 && y >= 0 && x < P && y < P)
            s->table[((size_t)k.level * P + (size_t)y) * P + (size_t)x] = (uint16_t)(s->over_slot[o] + 1);
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s->table_buf);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(entries + 1) / 2 * 4, s->table);
}

static void virtual_frame(void *state, sb_frame *f) {
    virtual_state *s = state;
    const sb_gpu *g = f->gpu;

    sb_stage_begin(f, &sb_stage_zpass);
    sb_zpass(f);
    sb_stage_end(f, &sb_stage_zpass);

    sb_stage_begin(f, &sb_stage_minmax);
    if (!s->fitted || memcmp(&s->sun, &g->sun, sizeof s->sun)) {   /* a light that moved: every page again */
        invalidate(s);
        fit_clipmap(s, f);
    }
    /* split=on keeps pages of the still casters: a moving one never invalidates them, it is drawn over copies */
    const bool split = s->d.split && !f->bypass_cache && sb_scene_moves(g->scene);
    if (!s->d.cache) invalidate(s);
    else if (f->moved_count && !split && !f->bypass_cache)
        sb_count(&f->counters, &virtual_counters[C_INVALIDATED], invalidate_moved(s, f));
    place_windows(s, f);
    mark_pages(s, f);
    int needed = 0, P = s->p.pages;
    for (int w = 0; w < s->words; w++)
        for (uint32_t bits = s->req[w]; bits; bits &= bits - 1) {
            int e = w * 32 + __builtin_ctz(bits), l = e / (P * P), y = e / P % P, x = e % P;
            s->need[needed++] = (page_key){l, s->origin[l][0] + x, s->origin[l][1] + y, false};
        }
    sb_stage_end(f, &sb_stage_minmax);

    sb_stage_begin(f, &sb_stage_cascade);
    int held = needed, given_up = coarsen_to_fit(s, &held);
    pool_tally t = {0};
    update_pool(s, f, held, split ? CASTERS_STILL : CASTERS_ALL, &t);
    if (split) sb_count(&f->counters, &virtual_counters[C_DYNAMIC], overlay_moving(s, f, held));
    if (f->bypass_cache) redraw_in_place(s, f, held);
    upload_table(s);
    const double counts[] = {[C_NEEDED] = needed, [C_RENDERED] = t.drawn, [C_CACHED] = held - t.drawn - t.left_out,
                             [C_OVERFLOW] = given_up + t.left_out_own, [C_STAND_IN] = t.stand_ins};
    for (int k = C_NEEDED; k <= C_STAND_IN; k++) sb_count(&f->counters, &virtual_counters[k], counts[k]);
    sb_stage_end(f, &sb_stage_cascade);

    sb_stage_begin(f, &sb_stage_final);
    glUseProgram(s->fp.prog);
    set_clipmap_uniforms(s, f, &s->final_clip);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, s->table_buf);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, s->atlas);
    glUniform1i(s->u_atlas, 0);
    glUniform2f(s->u_atlas_texel, 1.0f / (float)(s->p.slots_x * s->p.slot), 1.0f / (float)(s->p.rows * s->p.slot));
    sb_m4 proj = sb_m4_ortho(-1, 1, -1, 1, s->zn, s->zf);   /* the depth every page's view writes */
    glUniform2f(s->u_vdepth, (float)(0.5 * proj.m[10]), (float)(0.5 * proj.m[14] + 0.5));
    glUniform1f(s->u_vrange, (float)(s->zf - s->zn));
    glUniform1f(s->u_bias, (float)s->d.bias);
    glUniform1f(s->u_normal, (float)s->d.normal);
    glUniform3f(s->u_light, (float)g->sun.x, (float)g->sun.y, (float)g->sun.z);
    sb_final_pass(f, &s->fp, true);
    sb_stage_end(f, &sb_stage_final);
    overlay_done(s);
    if (f->bypass_cache) invalidate(s);   /* ... and keeps none of them */
}

static void virtual_destroy(void *state) {
    virtual_state *s = state;
    sb_final_prog_free(&s->fp);
    GLuint progs[] = {s->mark_prog, s->depth_prog[0], s->depth_prog[1]};
    for (size_t i = 0; i < SB_COUNT(progs); i++)
        if (progs[i]) glDeleteProgram(progs[i]);
    GLuint bufs[] = {s->req_buf, s->table_buf};
    for (size_t i = 0; i < SB_COUNT(bufs); i++)
        if (bufs[i]) glDeleteBuffers(1, &bufs[i]);
    if (s->fbo) glDeleteFramebuffers(1, &s->fbo);
    if (s->atlas) glDeleteTextures(1, &s->atlas);
    free(s->slot_key);
    free(s->slot_used);
    free(s->hash);
    free(s->req);
    free(s->table);
    free(s->need);
    free(s->missing);
    free(s->free_slots);
    free(s->over_key);
    free(s->over_slot);
    free(s->over_keep);
    memset(s, 0, sizeof *s);
}

/* A pool that could not hold every page a frame needed drew some pixels from another level than theirs: said, with
 * the shortfall. */
static void virtual_warn(const sb_counters *frames, int n, char *out, size_t len) {
    int short_frames = 0, worst = 0, need = 0;
    for (int i = 0; i < n; i++) {
        double over = 0, needed = 0;
        if (!sb_counted(&frames[i], &virtual_counters[C_OVERFLOW], &over) || !over) continue;
        sb_counted(&frames[i], &virtual_counters[C_NEEDED], &needed);
        short_frames++;
        if (over > worst) worst = (int)over, need = (int)needed;
    }
    if (short_frames)
        snprintf(out, len, "pool_overflow: the page pool was short of up to %d of %d needed pages in %d of %d frames "
                 "(their pixels used the page one level coarser): a larger pool= holds them", worst, need, short_frames, n);
}

const sb_technique sb_technique_virtual = {
    .name = "virtual",
    .summary = "virtual shadow maps: a clipmap of page-cached virtual maps, pages drawn where pixels need them",
    .params = virtual_params,
    .param_count = (int)SB_COUNT(virtual_params),
    .desc_size = sizeof(virtual_desc),
    SB_STAGES(&sb_stage_zpass, &sb_stage_minmax, &sb_stage_cascade, &sb_stage_final),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(virtual_state),
    .check = virtual_check,
    .supported = virtual_supported,
    .shadow_bytes = virtual_shadow_bytes,
    .create = virtual_create,
    .frame = virtual_frame,
    .counters = virtual_counters,
    .counter_count = C_COUNT,
    .warn = virtual_warn,
    .destroy = virtual_destroy,
};
