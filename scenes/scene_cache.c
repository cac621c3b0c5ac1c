/* scene_cache.c - flattened scenes on disk (see scene_cache.h). */
#define _GNU_SOURCE
#include "scene_cache.h"

#include <dirent.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* Bump when what an entry holds changes meaning (the binary's identity covers layouts). */
#define SB_SCENE_CACHE_VERSION 1u
static const char magic[8] = {'S', 'B', 'S', 'C', 'E', 'N', 'E', '1'};

bool sb_scene_cache_dir(char *out, size_t len) {
    const char *env = getenv("SB_SCENE_CACHE");
    if (env && *env) {
        if (!strcmp(env, "off")) return false;
        return (size_t)snprintf(out, len, "%s", env) < len;
    }
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    if (xdg && *xdg) return (size_t)snprintf(out, len, "%s/shadowbench/scenes", xdg) < len;
    if (home && *home) return (size_t)snprintf(out, len, "%s/.cache/shadowbench/scenes", home) < len;
    return false;
}

/* ---- the files a load read ---- */

typedef struct {
    char *path;
    uint64_t hash;
} dep;

static dep *g_deps;
static uint32_t g_dep_count;
static bool g_recording;

static void deps_clear(void) {
    for (uint32_t i = 0; i < g_dep_count; i++) free(g_deps[i].path);
    free(g_deps);
    g_deps = NULL;
    g_dep_count = 0;
}

void sb_scene_cache_note_file(const char *path, uint64_t hash) {
    if (!g_recording) return;
    g_deps = sb_xrealloc(g_deps, (g_dep_count + 1) * sizeof *g_deps);
    g_deps[g_dep_count++] = (dep){sb_strdup(path), hash};
}

void sb_scene_cache_begin(void) {
    deps_clear();
    g_recording = true;
    sb_log_capture(true);
}

/* ---- the key and the entry's name ---- */

uint64_t sb_scene_cache_key(const sb_scene_opts *opts, const void *bytes, size_t size) {
    sb_scene_opts o;
    memset(&o, 0, sizeof o);
    if (opts) o = *opts;
    uint64_t h = sb_hash_bytes(SB_FNV_SEED, bytes, size);
    uint32_t v = SB_SCENE_CACHE_VERSION;
    int flags[3] = {o.allow_external_uris, (int)o.blend, o.pose};
    h = sb_fnv1a(h, &v, sizeof v);
    h = sb_fnv1a(h, flags, sizeof flags);
    h = sb_fnv1a(h, &o.pose_time, sizeof o.pose_time);
    uint64_t id = sb_binary_identity();
    return sb_fnv1a(h, &id, sizeof id);
}

static bool entry_path(uint64_t key, char *out, size_t len) {
    char dir[3800];
    if (!sb_scene_cache_dir(dir, sizeof dir)) return false;
    return (size_t)snprintf(out, len, "%s/%016llx.sbscene", dir, (unsigned long long)key) < len;
}

/* ---- the scene's fields ---- */

typedef struct {
    sb_v3 origin, sun;
    sb_aabb bounds;
    uint64_t content_hash;
    sb_scene_features features;
    uint32_t vertex_count, index_count, draw_count, light_count, camera_count, material_count, texture_count,
        texel_count, alpha_tested_draws, single_sided_draws, nodes_drawn, plane_count, has_sun;
    char degenerate[128];
    struct {
        double n[3], d, area;
        uint32_t tri_count;
    } planes[SB_MAX_PLANES];
} scalars;

typedef struct {
    unsigned char *p;
    size_t n, cap;
} wbuf;

static void put(wbuf *b, const void *data, size_t n) {
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2;
        b->p = sb_xrealloc(b->p, b->cap);
    }
    if (n) memcpy(b->p + b->n, data, n);
    b->n += n;
}

static void put_u32(wbuf *b, uint32_t v) { put(b, &v, sizeof v); }

/* Arrays start on 16-byte boundaries of the file: a mapped entry is used in place. */
#define ALIGN 16
static void put_array(wbuf *b, const void *data, size_t n) {
    static const unsigned char zero[ALIGN] = {0};
    put(b, zero, (ALIGN - b->n % ALIGN) % ALIGN);
    put(b, data, n);
}

typedef struct {
    const unsigned char *p;
    size_t n, at;
    bool ok;
    size_t base;            /* offset of p in the file, for alignment */
} rbuf;

static const void *take(rbuf *r, size_t n) {
    if (!r->ok || n > r->n - r->at) {
        r->ok = false;
        return NULL;
    }
    const void *q = r->p + r->at;
    r->at += n;
    return q;
}

static uint32_t take_u32(rbuf *r) {
    const void *q = take(r, 4);
    uint32_t v = 0;
    if (q) memcpy(&v, q, 4);
    return v;
}

/* n elements of size sz where they lie in the mapped entry (NULL when n is 0
 * or the entry is short): the scene points into the mapping (sb_scene.cache_map). */
static void *take_array(rbuf *r, uint64_t n, size_t sz) {
    size_t pad = (ALIGN - (r->base + r->at) % ALIGN) % ALIGN;
    if (!take(r, pad)) return NULL;
    if (n > (r->n - r->at) / (sz ? sz : 1)) {
        r->ok = false;
        return NULL;
    }
    const void *q = take(r, (size_t)n * sz);
    return n ? (void *)q : NULL;
}

static void write_scene(wbuf *b, const sb_scene *s) {
    scalars c;
    memset(&c, 0, sizeof c);
    c.origin = s->origin;
    c.sun = s->sun;
    c.bounds = s->bounds;
    c.content_hash = s->content_hash;
    c.features = s->features;
    c.vertex_count = s->vertex_count;
    c.index_count = s->index_count;
    c.draw_count = s->draw_count;
    c.light_count = s->light_count;
    c.camera_count = s->camera_count;
    c.material_count = s->material_count;
    c.texture_count = s->texture_count;
    c.texel_count = s->texel_count;
    c.alpha_tested_draws = s->alpha_tested_draws;
    c.single_sided_draws = s->single_sided_draws;
    c.nodes_drawn = s->nodes_drawn;
    c.plane_count = s->plane_count;
    c.has_sun = s->has_sun;
    memcpy(c.degenerate, s->degenerate, sizeof c.degenerate);
    for (uint32_t i = 0; i < s->plane_count; i++) {
        memcpy(c.planes[i].n, s->planes[i].n, sizeof c.planes[i].n);
        c.planes[i].d = s->planes[i].d;
        c.planes[i].area = s->planes[i].area;
        c.planes[i].tri_count = s->planes[i].tri_count;
    }
    put_array(b, &c, sizeof c);
    put_array(b, s->vertices, (size_t)s->vertex_count * SB_VERTEX_BYTES);
    put_array(b, s->indices, (size_t)s->index_count * sizeof *s->indices);
    put_array(b, s->draws, (size_t)s->draw_count * sizeof *s->draws);
    put_array(b, s->lights, (size_t)s->light_count * sizeof *s->lights);
    put_array(b, s->cameras, (size_t)s->camera_count * sizeof *s->cameras);
    put_array(b, s->materials, (size_t)s->material_count * sizeof *s->materials);
    put_array(b, s->textures, (size_t)s->texture_count * sizeof *s->textures);
    put_array(b, s->texels, s->texel_count);
    for (uint32_t i = 0; i < s->plane_count; i++) put_array(b, s->planes[i].tris, (size_t)s->planes[i].tri_count * 4);
}

/* Fills a begun scene; false when the entry is short or inconsistent. */
static bool read_scene(rbuf *r, sb_scene *s) {
    const scalars *cp = take_array(r, 1, sizeof(scalars));
    if (!cp) return false;
    scalars c;
    memcpy(&c, cp, sizeof c);
    if (c.plane_count > SB_MAX_PLANES || c.material_count == 0) return false;
    s->origin = c.origin;
    s->sun = c.sun;
    s->bounds = c.bounds;
    s->content_hash = c.content_hash;
    s->features = c.features;
    s->alpha_tested_draws = c.alpha_tested_draws;
    s->single_sided_draws = c.single_sided_draws;
    s->nodes_drawn = c.nodes_drawn;
    s->has_sun = c.has_sun != 0;
    memcpy(s->degenerate, c.degenerate, sizeof s->degenerate);
    s->degenerate[sizeof s->degenerate - 1] = 0;
    s->vertices = take_array(r, c.vertex_count, SB_VERTEX_BYTES);
    s->vertex_count = s->vertex_cap = c.vertex_count;
    s->indices = take_array(r, c.index_count, sizeof *s->indices);
    s->index_count = s->index_cap = c.index_count;
    s->draws = take_array(r, c.draw_count, sizeof *s->draws);
    s->draw_count = s->draw_cap = c.draw_count;
    s->lights = take_array(r, c.light_count, sizeof *s->lights);
    s->light_count = c.light_count;
    s->cameras = take_array(r, c.camera_count, sizeof *s->cameras);
    s->camera_count = c.camera_count;
    free(s->materials);   /* sb_scene_begin's */
    s->materials = take_array(r, c.material_count, sizeof *s->materials);
    s->material_count = s->materials ? c.material_count : 0;
    s->textures = take_array(r, c.texture_count, sizeof *s->textures);
    s->texture_count = c.texture_count;
    s->texels = take_array(r, c.texel_count, 1);
    s->texel_count = c.texel_count;
    for (uint32_t i = 0; i < c.plane_count; i++) {
        sb_plane *p = &s->planes[i];
        memcpy(p->n, c.planes[i].n, sizeof p->n);
        p->d = c.planes[i].d;
        p->area = c.planes[i].area;
        p->tris = take_array(r, c.planes[i].tri_count, 4);
        p->tri_count = c.planes[i].tri_count;
        s->plane_count = i + 1;
    }
    if (!r->ok || r->at != r->n || !s->materials || s->index_count % 3) return false;
    for (uint32_t i = 0; i < s->index_count; i++)
        if (s->indices[i] >= s->vertex_count) return false;
    for (uint32_t i = 0; i < s->draw_count; i++) {
        const sb_draw *d = &s->draws[i];
        if (d->first_index > s->index_count || d->index_count > s->index_count - d->first_index ||
            d->material >= s->material_count)
            return false;
    }
    for (uint32_t i = 0; i < s->plane_count; i++)
        for (uint32_t k = 0; k < s->planes[i].tri_count; k++)
            if (s->planes[i].tris[k] >= s->index_count / 3) return false;
    for (uint32_t i = 0; i < s->material_count; i++)
        if (s->materials[i].texture >= (int32_t)s->texture_count) return false;
    for (uint32_t i = 0; i < s->texture_count; i++)
        if ((uint64_t)s->textures[i].w * s->textures[i].h > s->texel_count - (uint64_t)s->textures[i].offset ||
            s->textures[i].offset > s->texel_count)
            return false;
    return true;
}

/* ---- get and put ---- */

/* The parts an entry's checksum covers: everything after the header. */
typedef struct {
    char magic[8];
    uint64_t key, payload_hash, payload_size;
} header;

bool sb_scene_cache_get(sb_scene *s, const char *path, const sb_scene_opts *opts, uint64_t key) {
    char ep[4096];
    if (!entry_path(key, ep, sizeof ep)) return false;
    size_t n = 0;
    unsigned char *data = sb_map_file(ep, &n, true);
    if (!data) return false;
    header h;
    bool ok = n >= sizeof h;
    if (ok) memcpy(&h, data, sizeof h);
    ok = ok && !memcmp(h.magic, magic, sizeof magic) && h.key == key && h.payload_size == n - sizeof h &&
         sb_hash_bytes(SB_FNV_SEED, data + sizeof h, n - sizeof h) == h.payload_hash;
    rbuf r = {data + (ok ? sizeof h : 0), ok ? n - sizeof h : 0, 0, ok, sizeof h};
    /* the other files the load read must be as they were */
    uint32_t nd = take_u32(&r);
    for (uint32_t i = 0; r.ok && i < nd; i++) {
        uint32_t len = take_u32(&r);
        const char *p = take(&r, len);
        const uint64_t *hp = take(&r, sizeof(uint64_t));
        if (!p || !hp || len == 0 || len >= 4096) {
            r.ok = false;
            break;
        }
        char dp[4096];
        memcpy(dp, p, len);
        dp[len] = 0;
        size_t dn = 0;
        unsigned char *dd = sb_map_file(dp, &dn, false);
        uint64_t want;
        memcpy(&want, hp, sizeof want);
        r.ok = dd && sb_hash_bytes(SB_FNV_SEED, dd, dn) == want;
        sb_unmap_file(dd, dn);
    }
    uint32_t log_len = take_u32(&r);
    const char *log = take(&r, log_len);
    sb_scene t;
    sb_scene_begin(&t);
    t.cache_map = data;
    t.cache_map_len = n;
    if (r.ok && read_scene(&r, &t)) {
        t.file = sb_strdup(path);
        if (opts) t.opts = *opts;
        t.from_cache = true;
        sb_bvh_build(&t);
        *s = t;
        for (const char *l = log, *end = log + log_len; l && l < end;) {
            const char *nl = memchr(l, '\n', (size_t)(end - l));
            if (!nl) break;
            sb_log("%.*s", (int)(nl - l), l);
            l = nl + 1;
        }
        utimensat(AT_FDCWD, ep, NULL, 0);   /* recently used */
        return true;
    }
    sb_scene_free(&t);   /* unmaps */
    return false;
}

typedef struct {
    char *name;
    time_t mtime;
    off_t size;
} entry;

static int cmp_entry(const void *a, const void *b) {
    const entry *x = a, *y = b;
    return x->mtime < y->mtime ? -1 : x->mtime > y->mtime;
}

/* Least recently used entries out until the folder is under the limit. */
static void trim(const char *dir) {
    DIR *d = opendir(dir);
    if (!d) return;
    entry *es = NULL;
    size_t n = 0;
    uint64_t total = 0;
    for (struct dirent *de; (de = readdir(d));) {
        size_t len = strlen(de->d_name);
        if (len < 9 || strcmp(de->d_name + len - 8, ".sbscene")) continue;
        char p[4400];
        snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
        struct stat st;
        if (stat(p, &st) != 0) continue;
        es = sb_xrealloc(es, (n + 1) * sizeof *es);
        es[n++] = (entry){sb_strdup(p), st.st_mtime, st.st_size};
        total += (uint64_t)st.st_size;
    }
    closedir(d);
    if (n) qsort(es, n, sizeof *es, cmp_entry);
    for (size_t i = 0; i < n; i++) {
        if (total > SB_SCENE_CACHE_MAX_BYTES && unlink(es[i].name) == 0) total -= (uint64_t)es[i].size;
        free(es[i].name);
    }
    free(es);
}

void sb_scene_cache_put(const sb_scene *s, uint64_t key, bool ok) {
    g_recording = false;
    sb_log_capture(false);
    char ep[4096], dir[3800];
    if (!ok || !entry_path(key, ep, sizeof ep) || !sb_scene_cache_dir(dir, sizeof dir)) {
        deps_clear();
        return;
    }
    wbuf b = {0};
    header h;
    memset(&h, 0, sizeof h);
    put(&b, &h, sizeof h);
    put_u32(&b, g_dep_count);
    for (uint32_t i = 0; i < g_dep_count; i++) {
        put_u32(&b, (uint32_t)strlen(g_deps[i].path));
        put(&b, g_deps[i].path, strlen(g_deps[i].path));
        put(&b, &g_deps[i].hash, sizeof g_deps[i].hash);
    }
    deps_clear();
    const char *log = sb_log_captured();
    put_u32(&b, (uint32_t)strlen(log));
    put(&b, log, strlen(log));
    write_scene(&b, s);
    memcpy(h.magic, magic, sizeof magic);
    h.key = key;
    h.payload_size = b.n - sizeof h;
    h.payload_hash = sb_hash_bytes(SB_FNV_SEED, b.p + sizeof h, b.n - sizeof h);
    memcpy(b.p, &h, sizeof h);
    sb_err e;
    if (sb_mkdir_p(dir, &e) && sb_write_file_atomic(ep, b.p, b.n, &e)) trim(dir);
    free(b.p);
}
