/* scene_load.c - a scene file (or a bundled name) made into a scene: through
 * the scene cache when the file was read before, else through the glTF loader
 * and sb_scene_finish, writing the cache's entry. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "scene_load.h"

#include "motion.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "blob.h"
#include "gltf_load.h"
#include "scene_cache.h"

/* ---- the scene's fields in an entry ---- */

typedef struct {
    sb_v3 origin, sun;
    sb_aabb bounds;
    uint64_t content_hash;
    sb_scene_features features;
    uint32_t vertex_count, index_count, draw_count, light_count, camera_count, material_count, texture_count,
        texel_count, alpha_tested_draws, single_sided_draws, nodes_drawn, plane_count, has_sun;
    uint32_t has_motion;         /* the clips that play follow the arrays (sb_motion_write) */
    char degenerate[128];
    char unused[512];
    struct {
        double n[3], d, area;
        uint32_t tri_count;
    } planes[SB_MAX_PLANES];
} scalars;

static void write_scene(sb_wbuf *b, const sb_scene *s) {
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
    c.has_motion = s->motion != NULL;
    memcpy(c.degenerate, s->degenerate, sizeof c.degenerate);
    memcpy(c.unused, s->unused, sizeof c.unused);
    for (uint32_t i = 0; i < s->plane_count; i++) {
        memcpy(c.planes[i].n, s->planes[i].n, sizeof c.planes[i].n);
        c.planes[i].d = s->planes[i].d;
        c.planes[i].area = s->planes[i].area;
        c.planes[i].tri_count = s->planes[i].tri_count;
    }
    sb_wbuf_put_array(b, &c, sizeof c);
    sb_wbuf_put_array(b, s->vertices, (size_t)s->vertex_count * SB_VERTEX_BYTES);
    sb_wbuf_put_array(b, s->indices, (size_t)s->index_count * sizeof *s->indices);
    sb_wbuf_put_array(b, s->draws, (size_t)s->draw_count * sizeof *s->draws);
    sb_wbuf_put_array(b, s->lights, (size_t)s->light_count * sizeof *s->lights);
    sb_wbuf_put_array(b, s->cameras, (size_t)s->camera_count * sizeof *s->cameras);
    sb_wbuf_put_array(b, s->materials, (size_t)s->material_count * sizeof *s->materials);
    sb_wbuf_put_array(b, s->textures, (size_t)s->texture_count * sizeof *s->textures);
    sb_wbuf_put_array(b, s->texels, s->texel_count);
    for (uint32_t i = 0; i < s->plane_count; i++) sb_wbuf_put_array(b, s->planes[i].tris, (size_t)s->planes[i].tri_count * 4);
    if (s->motion) sb_motion_write(s->motion, b);
}

/* Fills a begun scene; false when the entry is short or inconsistent. */
static bool read_scene(sb_rbuf *r, sb_scene *s) {
    const scalars *cp = sb_rbuf_take_array(r, 1, sizeof(scalars));
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
    memcpy(s->unused, c.unused, sizeof s->unused);
    s->unused[sizeof s->unused - 1] = 0;
    s->vertices = sb_rbuf_take_array(r, c.vertex_count, SB_VERTEX_BYTES);
    s->vertex_count = s->vertex_cap = c.vertex_count;
    s->indices = sb_rbuf_take_array(r, c.index_count, sizeof *s->indices);
    s->index_count = s->index_cap = c.index_count;
    s->draws = sb_rbuf_take_array(r, c.draw_count, sizeof *s->draws);
    s->draw_count = s->draw_cap = c.draw_count;
    s->lights = sb_rbuf_take_array(r, c.light_count, sizeof *s->lights);
    s->light_count = c.light_count;
    s->cameras = sb_rbuf_take_array(r, c.camera_count, sizeof *s->cameras);
    s->camera_count = c.camera_count;
    free(s->materials);   /* sb_scene_begin's */
    s->materials = sb_rbuf_take_array(r, c.material_count, sizeof *s->materials);
    s->material_count = s->materials ? c.material_count : 0;
    s->textures = sb_rbuf_take_array(r, c.texture_count, sizeof *s->textures);
    s->texture_count = c.texture_count;
    s->texels = sb_rbuf_take_array(r, c.texel_count, 1);
    s->texel_count = c.texel_count;
    for (uint32_t i = 0; i < c.plane_count; i++) {
        sb_plane *p = &s->planes[i];
        memcpy(p->n, c.planes[i].n, sizeof p->n);
        p->d = c.planes[i].d;
        p->area = c.planes[i].area;
        p->tris = sb_rbuf_take_array(r, c.planes[i].tri_count, 4);
        p->tri_count = c.planes[i].tri_count;
        s->plane_count = i + 1;
    }
    s->planes_found = true;   /* the writer searched before it wrote */
    if (c.has_motion && r->ok && s->vertices) {   /* the clips that play: posed from the rest pose held above */
        s->motion = sb_motion_read(r, s);
        if (!s->motion) return false;
        s->motion_free = sb_motion_free;
    }
    if (!r->ok || r->at != r->n || !s->materials || s->index_count % 3) return false;
    for (uint32_t i = 0; i < s->index_count; i++)
        if (s->indices[i] >= s->vertex_count) return false;
    for (uint32_t i = 0; i < s->draw_count; i++) {
        const sb_draw *d = &s->draws[i];
        if (d->first_index > s->index_count || d->index_count > s->index_count - d->first_index ||
            d->material >= s->material_count || d->first_vertex > s->vertex_count ||
            d->vertex_count > s->vertex_count - d->first_vertex || d->proto >= s->draw_count ||
            s->draws[d->proto].proto != d->proto || s->draws[d->proto].index_count != d->index_count ||
            (d->proto != i && (s->draws[d->proto].first_index != d->first_index ||
                               s->draws[d->proto].first_vertex != d->first_vertex)))
            return false;
        s->instance_draws += d->proto != i;
    }
    uint64_t placed = sb_scene_triangles(s);
    for (uint32_t i = 0; i < s->plane_count; i++)
        for (uint32_t k = 0; k < s->planes[i].tri_count; k++)
            if (s->planes[i].tris[k] >= placed) return false;
    for (uint32_t i = 0; i < s->material_count; i++)
        if (s->materials[i].texture >= (int32_t)s->texture_count) return false;
    for (uint32_t i = 0; i < s->texture_count; i++)
        if ((uint64_t)s->textures[i].w * s->textures[i].h > s->texel_count - (uint64_t)s->textures[i].offset ||
            s->textures[i].offset > s->texel_count)
            return false;
    return true;
}

/* ---- the scene cache's entries ---- */

/* The options that change what a load makes, as canonical bytes. */
static uint64_t cache_key(const char *scene_dir, const sb_scene_opts *opts, const void *bytes, size_t size) {
    sb_scene_opts o;
    memset(&o, 0, sizeof o);
    if (opts) o = *opts;
    struct {
        int flags[4];
        double pose_time;
        char anim_clips[256];
        double anim_speed;   /* in the content hash of a scene whose clips play (its entry holds that hash) */
    } k;
    memset(&k, 0, sizeof k);
    k.anim_speed = o.anim_speed > 0 ? o.anim_speed : 1;
    k.flags[0] = o.allow_external_uris;
    k.flags[1] = (int)o.blend;
    k.flags[2] = o.pose;
    k.flags[3] = (int)o.anim;
    k.pose_time = o.pose_time;
    memcpy(k.anim_clips, o.anim_clips, sizeof k.anim_clips);
    return sb_scene_cache_key(scene_dir, &k, sizeof k, bytes, size);
}

static void write_entry(sb_wbuf *b, const void *user) { write_scene(b, user); }

typedef struct {
    sb_scene *s;
    const char *path;
    const sb_scene_opts *opts;
} cached_load;

static bool read_entry(sb_rbuf *r, void *map, size_t len, void *user) {
    cached_load *cl = user;
    sb_scene t;
    sb_scene_begin(&t);
    t.cache_map = map;
    t.cache_map_len = len;
    if (!read_scene(r, &t)) {
        sb_scene_free(&t);   /* unmaps */
        return false;
    }
    t.file = sb_strdup(cl->path);
    if (cl->opts) t.opts = *cl->opts;
    t.from_cache = true;
    if (t.motion && !sb_motion_mark(t.motion, &t)) {   /* the draws each placement poses, and what stays still */
        sb_scene_free(&t);
        return false;
    }
    sb_scene_build_bvh(&t);
    *cl->s = t;
    return true;
}

static bool exe_dir(char *out, size_t len) {
    char buf[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
    if (n <= 0) return false;
    buf[n] = 0;
    char *slash = strrchr(buf, '/');
    if (!slash) return false;
    *slash = 0;
    if (strlen(buf) >= len) return false;
    memcpy(out, buf, strlen(buf) + 1);
    return true;
}

bool sb_resolve_bundled(const char *name, const char *ext, char *out, size_t outlen) {
    if (strchr(name, '/') || strchr(name, '.')) return false;
    char dirs[3][PATH_MAX];
    int nd = 0;
    const char *env = getenv("SB_DATA_DIR");
    if (env) snprintf(dirs[nd++], PATH_MAX, "%s", env);
    char ed[PATH_MAX - 64];
    if (exe_dir(ed, sizeof ed)) {
        snprintf(dirs[nd++], PATH_MAX, "%s", ed);
        snprintf(dirs[nd++], PATH_MAX, "%s/../share/shadowbench", ed);
    }
    for (int i = 0; i < nd; i++) {
        snprintf(out, outlen, "%s/%s%s", dirs[i], name, ext);
        if (access(out, R_OK) == 0) return true;
    }
    return false;
}

/* A lamp's range held to what the scene holds: the farthest corner of the scene's box from the lamp (twice that
 * where clips move things, which may leave the box as loaded). A range past it lights nothing more, but as a far
 * plane it spends the depth maps' precision on empty space (1e38: every caster clipped), so a range of 1e38 and
 * one of the scene's diagonal are the same lamp. Said once at load. */
static void fit_ranges(sb_scene *s) {
    int k = 0;
    for (uint32_t i = 0; i < s->light_count; i++) {
        sb_light *l = &s->lights[i];
        if (l->type == SB_LIGHT_DIRECTIONAL) continue;
        double reach = 0;
        for (int c = 0; c < 8; c++) {
            sb_v3 corner = sb_aabb_corner(&s->bounds, c);
            reach = fmax(reach, sb_v3_len(sb_v3_sub(corner, l->position)));
        }
        if (s->motion) reach *= 2;
        if (l->range > reach && reach > 0) {
            sb_log("%s: lamp %d: its range %g reaches past everything the scene holds: held to %.6g, the farthest "
                   "point of the scene's box from it%s", s->file, k, l->range, reach, s->motion ? " (twice: clips move "
                   "things)" : "");
            l->range = reach;
        }
        k++;
    }
}

/* The file read, its checks, tinygltf and the flattening: a load without the cache. */
static bool load_file(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err) {
    sb_scene_begin(s);
    s->file = sb_strdup(path);
    if (opts) s->opts = *opts;
    if (!sb_gltf_load(s, path, opts, err) || !sb_scene_finish(s, err)) {
        sb_scene_free(s);
        return false;
    }
    if (s->motion && !sb_motion_mark(s->motion, s)) {   /* clips that move nothing drawn (a camera, a light) */
        s->motion_free(s->motion);
        s->motion = NULL;
    }
    fit_ranges(s);
    if (s->motion) {   /* clips that play make other figures than the still scene: other run ids */
        struct {
            int mode;
            char clips[256];
            double speed;
        } a;
        memset(&a, 0, sizeof a);
        sb_motion_stats ms = sb_motion_statistics(s->motion);
        /* the clips by what plays, not by how they were named: every clip named is --anim all; "0" is "walk" */
        a.mode = ms.clips == s->features.clips ? SB_ANIM_ALL : SB_ANIM_LIST;
        for (uint32_t i = 0; a.mode == SB_ANIM_LIST && i < ms.clips; i++) {
            size_t l = strlen(a.clips);
            snprintf(a.clips + l, sizeof a.clips - l, "%s%s", i ? "," : "", sb_motion_clip(s->motion, i).name);
        }
        a.speed = s->opts.anim_speed > 0 ? s->opts.anim_speed : 1;
        s->content_hash = sb_fnv1a(s->content_hash, &a, sizeof a);
    }
    /* options that change what is drawn change the run ids (the defaults leave them as they were) */
    if (s->opts.blend != SB_BLEND_MASK && s->features.blend)
        s->content_hash = sb_fnv1a(s->content_hash, &s->opts.blend, sizeof s->opts.blend);
    if (s->opts.pose) s->content_hash = sb_fnv1a(s->content_hash, &s->opts.pose_time, sizeof s->opts.pose_time);
    return true;
}

/* The real path of the folder a file stands in; false when it cannot be found (then no cache). */
static bool real_folder(const char *path, char *out, size_t len) {
    char dir[PATH_MAX], real[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (!slash) snprintf(dir, sizeof dir, ".");
    else if (slash == dir) dir[1] = 0;
    else *slash = 0;
    if (!realpath(dir, real) || strlen(real) >= len) return false;
    memcpy(out, real, strlen(real) + 1);
    return true;
}

/* The scene's `anim` text: what plays (scene.h). */
static void anim_text(sb_scene *s) {
    s->anim[0] = 0;
    double speed = s->opts.anim_speed > 0 ? s->opts.anim_speed : 1;
    if (!s->features.clips || s->opts.pose) return;   /* a still file; --pose: in the content hash, no clip plays */
    if (!s->motion) {
        if (s->opts.anim == SB_ANIM_NONE) snprintf(s->anim, sizeof s->anim, "none");
        return;
    }
    sb_motion_stats ms = sb_motion_statistics(s->motion);
    if (ms.clips == s->features.clips && speed == 1) return;   /* the default: every clip as the file says */
    if (ms.clips == s->features.clips) snprintf(s->anim, sizeof s->anim, "all");
    for (uint32_t i = 0; ms.clips != s->features.clips && i < ms.clips; i++) {
        size_t l = strlen(s->anim);
        snprintf(s->anim + l, sizeof s->anim - l, "%s%s", i ? "," : "", sb_motion_clip(s->motion, i).name);
    }
    size_t l = strlen(s->anim);
    if (speed != 1) snprintf(s->anim + l, sizeof s->anim - l, " x%g", speed);
}

bool sb_scene_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err) {
    char resolved[PATH_MAX], dir[PATH_MAX];
    if (sb_resolve_bundled(path, ".glb", resolved, sizeof resolved)) path = resolved;
    double t0 = sb_now_ms();
    /* the cache is found by the file's bytes; a file that cannot be read gets its message from the load */
    size_t size = 0;
    char scene_dir[PATH_MAX];
    bool cache = sb_scene_cache_dir(dir, sizeof dir) && real_folder(path, scene_dir, sizeof scene_dir);
    void *bytes = cache ? sb_map_file(path, &size, false) : NULL;
    cache = bytes != NULL;
    uint64_t key = cache ? cache_key(scene_dir, opts, bytes, size) : 0;
    sb_unmap_file(bytes, size);
    bool ok;
    cached_load cl = {s, path, opts};
    if (cache && sb_scene_cache_get(key, scene_dir, read_entry, &cl)) {
        ok = true;
    } else {
        if (cache) sb_scene_cache_begin(scene_dir);
        ok = load_file(s, path, opts, err);
        if (cache && ok) sb_scene_find_planes(s);   /* an entry holds the planes, so a cached load never searches */
        /* a scene whose clips play is kept with them (its rest pose, channels, placements and skins; the key says
           which clips and at what speed) */
        if (cache) sb_scene_cache_put(key, ok && (!s->motion || isnan(s->pose_time)) ? write_entry : NULL, s);
    }
    if (ok) s->load_ms = sb_now_ms() - t0;
    if (ok) anim_text(s);
    return ok;
}
