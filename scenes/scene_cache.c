/* scene_cache.c - flattened scenes on disk, as keyed entries (see scene_cache.h). */
#define _GNU_SOURCE
#include "scene_cache.h"

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gltf_check.h"
#include "util.h"

/* Bump when what an entry holds changes meaning (the binary's identity covers layouts). */
#define SB_SCENE_CACHE_VERSION 6u   /* 2: draws carry their instancing (proto, transform, vertex range); 3: the
                                       dependencies relative to the scene's folder, the folder in the key; 4: a
                                       scene whose clips play, with them (sb_motion_write); 5: an instance's
                                       triangles are its proto's, held once; 6: no placement shared magnified
                                       from its proto */
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
static char g_scene_dir[4096];   /* the folder of the scene being loaded (a real path) */

static void deps_clear(void) {
    for (uint32_t i = 0; i < g_dep_count; i++) free(g_deps[i].path);
    free(g_deps);
    g_deps = NULL;
    g_dep_count = 0;
}

/* A dependency as the entry keeps it: relative to the scene's folder when inside it, else as it is. */
static const char *relative_to(const char *dir, const char *path) {
    size_t n = strlen(dir);
    if (n && !strncmp(path, dir, n) && path[n] == '/') return path + n + 1;
    return path;
}

void sb_scene_cache_note_file(const char *path, uint64_t hash) {
    if (!g_recording) return;
    g_deps = sb_xrealloc(g_deps, (g_dep_count + 1) * sizeof *g_deps);
    g_deps[g_dep_count++] = (dep){sb_strdup(relative_to(g_scene_dir, path)), hash};
}

void sb_scene_cache_begin(const char *scene_dir) {
    deps_clear();
    snprintf(g_scene_dir, sizeof g_scene_dir, "%s", scene_dir);
    g_recording = true;
    sb_log_capture(true);
}

/* ---- the key and the entry's name ---- */

uint64_t sb_scene_cache_key(const char *scene_dir, const void *opts, size_t opts_len, const void *bytes, size_t size) {
    uint64_t h = sb_hash_bytes(SB_FNV_SEED, bytes, size);
    uint32_t v = SB_SCENE_CACHE_VERSION;
    h = sb_fnv1a(h, &v, sizeof v);
    h = sb_fnv1a(h, scene_dir, strlen(scene_dir) + 1);
    h = sb_fnv1a(h, opts, opts_len);
    uint64_t id = sb_binary_identity();
    return sb_fnv1a(h, &id, sizeof id);
}

static bool entry_path(uint64_t key, char *out, size_t len) {
    char dir[3800];
    if (!sb_scene_cache_dir(dir, sizeof dir)) return false;
    return (size_t)snprintf(out, len, "%s/%016llx.sbscene", dir, (unsigned long long)key) < len;
}

/* ---- get and put ---- */

/* The parts an entry's checksum covers: everything after the header. */
typedef struct {
    char magic[8];
    uint64_t key, payload_hash, payload_size;
} header;

/* Whether every dependency the entry lists hashes as it did, found from the scene's folder. */
static bool deps_hold(sb_rbuf *r, const char *scene_dir) {
    uint32_t nd = sb_rbuf_take_u32(r);
    for (uint32_t i = 0; r->ok && i < nd; i++) {
        uint32_t len = sb_rbuf_take_u32(r);
        const char *p = sb_rbuf_take(r, len);
        const uint64_t *hp = sb_rbuf_take(r, sizeof(uint64_t));
        if (!p || !hp || len == 0 || len >= 2048) return r->ok = false;
        char rel[2048], dp[PATH_MAX];
        snprintf(rel, sizeof rel, "%.*s", (int)len, p);
        /* held to the rule the load held it to: a dependency kept as a path inside the scene's folder must still
           resolve inside it, as a regular file (a buffer since made a symlink out of the folder, or a FIFO, is a
           miss: the load then says why); one kept as an absolute path was read with --allow-external-uris, which
           is in the entry's key */
        sb_err e;
        size_t dn = 0;
        unsigned char *dd = sb_file_confined(scene_dir, rel, rel[0] == '/', dp, sizeof dp, &e)
                                ? sb_map_file(dp, &dn, false) : NULL;
        uint64_t want;
        memcpy(&want, hp, sizeof want);
        r->ok = dd && sb_hash_bytes(SB_FNV_SEED, dd, dn) == want;
        sb_unmap_file(dd, dn);
    }
    return r->ok;
}

bool sb_scene_cache_get(uint64_t key, const char *scene_dir, sb_scene_cache_read read, void *user) {
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
    sb_rbuf r = {data + (ok ? sizeof h : 0), ok ? n - sizeof h : 0, 0, ok, sizeof h};
    /* the other files the load read must be as they were, found from this scene's folder */
    deps_hold(&r, scene_dir);
    uint32_t log_len = sb_rbuf_take_u32(&r);
    const char *log = sb_rbuf_take(&r, log_len);
    if (!r.ok) {
        sb_unmap_file(data, n);
        return false;
    }
    if (!read(&r, data, n, user)) return false;   /* read has the mapping now */
    for (const char *l = log, *end = log + log_len; l && l < end;) {
        const char *nl = memchr(l, '\n', (size_t)(end - l));
        if (!nl) break;
        sb_log("%.*s", (int)(nl - l), l);
        l = nl + 1;
    }
    utimensat(AT_FDCWD, ep, NULL, 0);   /* recently used */
    return true;
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

void sb_scene_cache_put(uint64_t key, sb_scene_cache_write write, const void *user) {
    g_recording = false;
    sb_log_capture(false);
    char ep[4096], dir[3800];
    if (!write || !entry_path(key, ep, sizeof ep) || !sb_scene_cache_dir(dir, sizeof dir)) {
        deps_clear();
        return;
    }
    sb_wbuf b = {0};
    header h;
    memset(&h, 0, sizeof h);
    sb_wbuf_put(&b, &h, sizeof h);
    sb_wbuf_put_u32(&b, g_dep_count);
    for (uint32_t i = 0; i < g_dep_count; i++) {
        sb_wbuf_put_u32(&b, (uint32_t)strlen(g_deps[i].path));
        sb_wbuf_put(&b, g_deps[i].path, strlen(g_deps[i].path));
        sb_wbuf_put(&b, &g_deps[i].hash, sizeof g_deps[i].hash);
    }
    deps_clear();
    const char *log = sb_log_captured();
    sb_wbuf_put_u32(&b, (uint32_t)strlen(log));
    sb_wbuf_put(&b, log, strlen(log));
    write(&b, user);
    memcpy(h.magic, magic, sizeof magic);
    h.key = key;
    h.payload_size = b.n - sizeof h;
    h.payload_hash = sb_hash_bytes(SB_FNV_SEED, b.p + sizeof h, b.n - sizeof h);
    memcpy(b.p, &h, sizeof h);
    sb_err e;
    if (!sb_mkdir_p(dir, &e)) {
        sb_cache_unkept("the scene cache", e.msg);
    } else if (sb_write_cache_file_atomic(ep, b.p, b.n, "the scene cache")) {
        trim(dir);
    }
    sb_wbuf_free(&b);
}
