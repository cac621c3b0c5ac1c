/* gltf_check.c - the glTF 2.0 rules checked on the raw JSON (see gltf_check.h).
 * Every message is "FILE: JSON-PATH: what is wrong". */
#define _XOPEN_SOURCE 700 /* realpath */
#include "gltf_check.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sbmath.h"

/* ---- the arrays of a document ---- */

enum {
    K_BUFFER, K_VIEW, K_ACCESSOR, K_MESH, K_NODE, K_SCENE, K_MATERIAL, K_CAMERA, K_SKIN, K_TEXTURE, K_IMAGE,
    K_SAMPLER, K_ANIMATION, K_LIGHT, K_COUNT
};
static const char *const array_key[K_COUNT] = {"buffers", "bufferViews", "accessors", "meshes", "nodes", "scenes",
                                               "materials", "cameras", "skins", "textures", "images", "samplers",
                                               "animations", "lights"};
static const char *const kind_name[K_COUNT] = {"buffer", "bufferView", "accessor", "mesh", "node", "scene",
                                               "material", "camera", "skin", "texture", "image", "sampler",
                                               "animation", "light"};

/* A JSON path ("/accessors/3/byteOffset"), cut at 199 characters. */
typedef struct jpath {
    char s[200];
} jpath;

typedef struct view_info {
    uint64_t buffer, off, len, stride;   /* stride 0: not given (tightly packed) */
} view_info;

typedef struct acc_info {
    bool has_view;
    uint64_t view, off, count, csize, ncomp, elem, stride;
    uint64_t tail;              /* bytes the last element needs: a matrix's last column without its padding */
    int ctype;
} acc_info;

typedef struct ck {
    const sb_gltf_check_desc *d;
    sb_err *err;
    const sb_json *arr[K_COUNT];
    uint64_t n[K_COUNT];
    uint64_t *buf_len;
    view_info *views;
    acc_info *accs;
    int64_t *parent;
    bool quantization;          /* KHR_mesh_quantization is used */
    uint8_t *used[K_COUNT];     /* accessors, bufferViews, buffers, lights something drawn or animated reads
                                   (mark_used); a part nobody reads is held leniently: left out, said */
    uint32_t rotations_normalised;
    jpath first_rotation;
    double first_rotation_len;
} ck;

static bool fail(ck *c, const char *path, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static bool fail(ck *c, const char *path, const char *fmt, ...) {
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return sb_fail(c->err, "%s: %s: %s", c->d->file, path, what);
}

static jpath at(const char *base, const char *key) {
    jpath p;
    size_t n = 0;
    for (const char *q = base; *q && n + 1 < sizeof p.s; q++) p.s[n++] = *q;
    if (n + 1 < sizeof p.s) p.s[n++] = '/';
    for (const char *q = key; *q && n + 1 < sizeof p.s; q++) p.s[n++] = *q;
    p.s[n] = 0;
    return p;
}

static jpath at_i(const char *base, uint64_t i) {
    char num[24];
    snprintf(num, sizeof num, "%llu", (unsigned long long)i);
    return at(base, num);
}

/* ---- typed fields ---- */

static bool field(ck *c, const sb_json *obj, const char *path, const char *key, sb_json_type want, bool required,
                  const sb_json **out) {
    const sb_json *v = sb_json_get(obj, key);
    *out = NULL;
    if (!v) return !required || fail(c, path, "'%s' is missing", key);
    if (v->type != want)
        return fail(c, at(path, key).s, "expected %s, found %s", sb_json_type_name(want), sb_json_type_name(v->type));
    *out = v;
    return true;
}

/* An integer value v in [lo, hi], exactly. */
static bool uint_value(ck *c, const sb_json *v, const char *path, uint64_t lo, uint64_t hi, uint64_t *out) {
    if (v->type != SB_JSON_NUMBER) return fail(c, path, "expected an integer, found %s", sb_json_type_name(v->type));
    if (sb_json_negative(v)) return fail(c, path, "%s is negative (expected an integer >= %llu)", v->text,
                                         (unsigned long long)lo);
    uint64_t x;
    if (!sb_json_u64(v, &x)) {
        if (v->num != floor(v->num)) return fail(c, path, "%s is not a whole number", v->text);
        return fail(c, path, "%s is too large (beyond 2^64 - 1)", v->text);
    }
    if (x < lo || x > hi)
        return fail(c, path, "%s is out of range %llu..%llu", v->text, (unsigned long long)lo, (unsigned long long)hi);
    *out = x;
    return true;
}

static bool get_uint(ck *c, const sb_json *obj, const char *path, const char *key, bool required, uint64_t def,
                     uint64_t lo, uint64_t hi, uint64_t *out) {
    const sb_json *v = sb_json_get(obj, key);
    *out = def;
    if (!v) return !required || fail(c, path, "'%s' is missing", key);
    return uint_value(c, v, at(path, key).s, lo, hi, out);
}

static bool index_value(ck *c, const sb_json *v, const char *path, int kind, int64_t *out) {
    uint64_t x = 0;
    if (!uint_value(c, v, path, 0, UINT64_MAX, &x)) return false;
    if (x >= c->n[kind])
        return fail(c, path, "%s %llu does not exist (the file has %llu)", kind_name[kind], (unsigned long long)x,
                    (unsigned long long)c->n[kind]);
    *out = (int64_t)x;
    return true;
}

/* An index into one of the document's arrays; -1 when absent. */
static bool get_index(ck *c, const sb_json *obj, const char *path, const char *key, bool required, int kind,
                      int64_t *out) {
    const sb_json *v = sb_json_get(obj, key);
    *out = -1;
    if (!v) return !required || fail(c, path, "'%s' is missing", key);
    return index_value(c, v, at(path, key).s, kind, out);
}

static bool number_value(ck *c, const sb_json *v, const char *path, double *out) {
    if (v->type != SB_JSON_NUMBER) return fail(c, path, "expected a number, found %s", sb_json_type_name(v->type));
    if (!isfinite(v->num)) return fail(c, path, "%s is not a finite number", v->text);
    *out = v->num;
    return true;
}

/* A number in [lo, hi] (open at an end when the flag says so). */
static bool get_number(ck *c, const sb_json *obj, const char *path, const char *key, bool required, double def,
                       double lo, bool lo_open, double hi, bool hi_open, double *out) {
    const sb_json *v = sb_json_get(obj, key);
    *out = def;
    if (!v) return !required || fail(c, path, "'%s' is missing", key);
    jpath p = at(path, key);
    if (!number_value(c, v, p.s, out)) return false;
    bool below = lo_open ? !(*out > lo) : !(*out >= lo), above = hi_open ? !(*out < hi) : !(*out <= hi);
    if (below || above) return fail(c, p.s, "%s is out of range %s%g, %g%s", v->text, lo_open ? "(" : "[", lo, hi,
                                    hi_open ? ")" : "]");
    return true;
}

/* An array of exactly n finite numbers; *present false when absent. */
static bool get_numbers(ck *c, const sb_json *obj, const char *path, const char *key, uint32_t n, double *out,
                        bool *present) {
    const sb_json *v;
    *present = false;
    if (!field(c, obj, path, key, SB_JSON_ARRAY, false, &v)) return false;
    if (!v) return true;
    jpath p = at(path, key);
    if (v->count != n) return fail(c, p.s, "expected %u numbers, found %u", n, v->count);
    for (uint32_t i = 0; i < n; i++)
        if (!number_value(c, &v->items[i], at_i(p.s, i).s, &out[i])) return false;
    *present = true;
    return true;
}

/* A string that must be one of "a|b|c" (choices) when choices is given. */
static bool get_choice(ck *c, const sb_json *obj, const char *path, const char *key, bool required,
                       const char *choices, const char **out) {
    const sb_json *v;
    *out = NULL;
    if (!field(c, obj, path, key, SB_JSON_STRING, required, &v)) return false;
    if (!v) return true;
    *out = v->text;
    if (!choices) return true;
    size_t n = strlen(v->text);
    for (const char *p = choices; *p;) {
        const char *bar = strchr(p, '|');
        size_t m = bar ? (size_t)(bar - p) : strlen(p);
        if (m == n && !strncmp(p, v->text, n)) return true;
        p += m + (bar ? 1 : 0);
    }
    return fail(c, at(path, key).s, "\"%s\" is not one of %s", v->text, choices);
}

/* Every item of an optional array is an index of `kind`. */
static bool index_list(ck *c, const sb_json *obj, const char *path, const char *key, int kind, const sb_json **out) {
    const sb_json *v;
    if (!field(c, obj, path, key, SB_JSON_ARRAY, false, &v)) return false;
    if (out) *out = v;
    if (!v) return true;
    jpath p = at(path, key);
    for (uint32_t i = 0; i < v->count; i++) {
        int64_t x;
        if (!index_value(c, &v->items[i], at_i(p.s, i).s, kind, &x)) return false;
    }
    return true;
}

/* ---- safe arithmetic ---- */

static bool fits(uint64_t off, uint64_t len, uint64_t size) { return off <= size && len <= size - off; }

static bool mul_add(uint64_t a, uint64_t b, uint64_t add, uint64_t *out) {
    uint64_t m;
    return !__builtin_mul_overflow(a, b, &m) && !__builtin_add_overflow(m, add, out);
}

/* ---- URIs ---- */

static int hexv(char ch) {
    return ch >= '0' && ch <= '9' ? ch - '0' : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10 : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10 : -1;
}

bool sb_uri_decode(const char *src, char *dst, size_t len) {
    size_t n = 0;
    for (const char *s = src; *s; s++) {
        char ch = *s;
        if (ch == '%') {
            int a = hexv(s[1]), b = a >= 0 ? hexv(s[2]) : -1;
            if (b < 0) return false;
            ch = (char)(a * 16 + b);
            if (!ch) return false;
            s += 2;
        }
        if (n + 1 >= len) return false;
        dst[n++] = ch;
    }
    dst[n] = 0;
    return true;
}

bool sb_file_confined(const char *base_dir, const char *path, bool allow_external, char *out, size_t outlen,
                      sb_err *err) {
    char joined[2 * PATH_MAX + 2], real[PATH_MAX], root[PATH_MAX];
    if (path[0] == '/') snprintf(joined, sizeof joined, "%s", path);
    else snprintf(joined, sizeof joined, "%s/%s", base_dir, path);
    if (!realpath(joined, real)) return sb_fail(err, "cannot open \"%s\": %s", path, strerror(errno));
    struct stat st;
    if (stat(real, &st) != 0) return sb_fail(err, "cannot open \"%s\": %s", path, strerror(errno));
    if (!S_ISREG(st.st_mode))
        return sb_fail(err, "\"%s\" is %s, not a regular file", path,
                       S_ISDIR(st.st_mode) ? "a directory" : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                                                                                                       : "special");
    if (!allow_external) {
        if (!realpath(base_dir, root)) return sb_fail(err, "cannot resolve the scene's folder %s: %s", base_dir, strerror(errno));
        size_t rl = strlen(root);
        bool inside = !strncmp(real, root, rl) && (real[rl] == '/' || (rl == 1 && root[0] == '/'));
        if (!inside)
            return sb_fail(err, "\"%s\" resolves to %s, outside the scene's folder %s (--allow-external-uris reads it)",
                           path, real, root);
    }
    if (strlen(real) >= outlen) return sb_fail(err, "\"%s\": path too long", path);
    memcpy(out, real, strlen(real) + 1);
    return true;
}

bool sb_uri_resolve(const char *base_dir, const char *uri, bool allow_external, char *out, size_t outlen,
                    sb_err *err) {
    char decoded[PATH_MAX];
    if (!sb_uri_decode(uri, decoded, sizeof decoded)) return sb_fail(err, "\"%s\" is not a valid URI (bad %%-escape)", uri);
    if (strstr(decoded, "://"))
        return sb_fail(err, "\"%s\": only data: URIs and paths relative to the scene's folder are read", uri);
    return sb_file_confined(base_dir, decoded, allow_external, out, outlen, err);
}

/* Whether path, relative to the folder root (or absolute), stays inside root once its "." and ".." are taken
 * as written (no link followed); where: the path it names. */
static bool lexically_inside(const char *root, const char *path, char where[PATH_MAX]) {
    char joined[2 * PATH_MAX + 2];
    if (path[0] == '/') snprintf(joined, sizeof joined, "%s", path);
    else snprintf(joined, sizeof joined, "%s/%s", root, path);
    size_t n = 0;   /* the normalised path in where */
    where[0] = 0;
    for (char *save = NULL, *part = strtok_r(joined, "/", &save); part; part = strtok_r(NULL, "/", &save)) {
        if (!strcmp(part, ".")) continue;
        if (!strcmp(part, "..")) {
            while (n > 0 && where[n - 1] != '/') n--;
            if (n > 0) n--;
            where[n] = 0;
            continue;
        }
        n += (size_t)snprintf(where + n, PATH_MAX - n, "/%s", part);
        if (n >= PATH_MAX) return false;
    }
    if (!where[0]) snprintf(where, PATH_MAX, "/");
    size_t rl = strlen(root);
    return !strncmp(where, root, rl) && (where[rl] == '/' || where[rl] == 0 || (rl == 1 && root[0] == '/'));
}

/* A uri: a data: URI must be base64; a path must be one (valid escapes, no scheme) and, when `open` (a buffer),
 * name a file inside the scene's folder. An image's file is opened, and confined, only when an alpha test reads
 * it (gltf_load.cc): a texture nothing reads never refuses a file. */
static bool check_uri(ck *c, const sb_json *obj, const char *path, bool open, bool *has) {
    const sb_json *v;
    *has = false;
    if (!field(c, obj, path, "uri", SB_JSON_STRING, false, &v)) return false;
    if (!v) return true;
    *has = true;
    if (!strncmp(v->text, "data:", 5)) {
        if (!strstr(v->text, ";base64,")) return fail(c, at(path, "uri").s, "a data: URI must be base64");
        return true;
    }
    char decoded[PATH_MAX];
    if (!open) {
        if (!sb_uri_decode(v->text, decoded, sizeof decoded))
            return fail(c, at(path, "uri").s, "\"%s\" is not a valid URI (bad %%-escape)", v->text);
        if (strstr(decoded, "://"))
            return fail(c, at(path, "uri").s, "\"%s\": only data: URIs and paths relative to the scene's folder are read",
                        v->text);
        char where[PATH_MAX], root[PATH_MAX];   /* confined by its text: a file not opened is not resolved */
        if (!c->d->allow_external_uris && realpath(c->d->base_dir, root) && !lexically_inside(root, decoded, where))
            return fail(c, at(path, "uri").s, "\"%s\" resolves to %s, outside the scene's folder %s "
                        "(--allow-external-uris reads it)", v->text, where, root);
        return true;
    }
    char resolved[PATH_MAX];
    sb_err e;
    if (!sb_uri_resolve(c->d->base_dir, v->text, c->d->allow_external_uris, resolved, sizeof resolved, &e))
        return fail(c, at(path, "uri").s, "%s", e.msg);
    return true;
}

/* ---- the checks, array by array ---- */

static bool check_asset(ck *c, const sb_json *root) {
    const sb_json *asset;
    if (!field(c, root, "/", "asset", SB_JSON_OBJECT, true, &asset)) return false;
    const char *version;
    if (!get_choice(c, asset, "/asset", "version", true, NULL, &version)) return false;
    if (strncmp(version, "2.", 2) != 0)
        return fail(c, "/asset/version", "glTF \"%s\" is not supported (2.x is)", version);
    return true;
}

/* ---- what is read: parts nothing reads never refuse a file ---- */

/* Marks index v (a JSON number) of kind k used, when it is one. */
static void mark(uint8_t *used, uint64_t n, const sb_json *v) {
    uint64_t i;
    if (used && v && v->type == SB_JSON_NUMBER && sb_json_u64(v, &i) && i < n) used[i] = 1;
}

/* Every member value of an object (a primitive's attributes, a morph target) marked. */
static void mark_values(uint8_t *used, uint64_t n, const sb_json *obj) {
    for (uint32_t k = 0; obj && obj->type == SB_JSON_OBJECT && k < obj->count; k++) mark(used, n, &obj->items[k]);
}

/* A member of a member of an object, or NULL. */
static const sb_json *get2(const sb_json *o, const char *a, const char *b) {
    const sb_json *x = o && o->type == SB_JSON_OBJECT ? sb_json_get(o, a) : NULL;
    return x && x->type == SB_JSON_OBJECT ? sb_json_get(x, b) : NULL;
}

static void mark_meshes(ck *c, uint8_t *acc, uint8_t *view) {
    for (uint64_t m = 0; m < c->n[K_MESH]; m++) {
        const sb_json *prims = sb_json_get(&c->arr[K_MESH]->items[m], "primitives");
        for (uint32_t k = 0; prims && prims->type == SB_JSON_ARRAY && k < prims->count; k++) {
            const sb_json *p = &prims->items[k], *targets = p->type == SB_JSON_OBJECT ? sb_json_get(p, "targets") : NULL;
            if (p->type != SB_JSON_OBJECT) continue;
            mark_values(acc, c->n[K_ACCESSOR], sb_json_get(p, "attributes"));
            mark(acc, c->n[K_ACCESSOR], sb_json_get(p, "indices"));
            for (uint32_t t = 0; targets && targets->type == SB_JSON_ARRAY && t < targets->count; t++)
                mark_values(acc, c->n[K_ACCESSOR], &targets->items[t]);
            const sb_json *draco = get2(p, "extensions", "KHR_draco_mesh_compression");
            mark(view, c->n[K_VIEW], draco && draco->type == SB_JSON_OBJECT ? sb_json_get(draco, "bufferView") : NULL);
        }
    }
}

/* What something drawn or animated reads: the accessors of primitives (attributes, indices, morph targets),
 * skins and animation samplers; the bufferViews of those (sparse ones too), of images and of Draco; the
 * buffers of those views; the lights nodes name. */
static void mark_used(ck *c) {
    for (int k = 0; k < K_COUNT; k++) c->used[k] = sb_xcalloc(c->n[k] + 1, 1);
    uint8_t *acc = c->used[K_ACCESSOR], *view = c->used[K_VIEW];
    mark_meshes(c, acc, view);
    for (uint64_t i = 0; i < c->n[K_SKIN]; i++) mark(acc, c->n[K_ACCESSOR], sb_json_get(&c->arr[K_SKIN]->items[i], "inverseBindMatrices"));
    for (uint64_t i = 0; i < c->n[K_ANIMATION]; i++) {
        const sb_json *ss = sb_json_get(&c->arr[K_ANIMATION]->items[i], "samplers");
        for (uint32_t k = 0; ss && ss->type == SB_JSON_ARRAY && k < ss->count; k++)
            if (ss->items[k].type == SB_JSON_OBJECT) {
                mark(acc, c->n[K_ACCESSOR], sb_json_get(&ss->items[k], "input"));
                mark(acc, c->n[K_ACCESSOR], sb_json_get(&ss->items[k], "output"));
            }
    }
    for (uint64_t i = 0; i < c->n[K_ACCESSOR]; i++) {
        if (!acc[i]) continue;
        const sb_json *a = &c->arr[K_ACCESSOR]->items[i];
        mark(view, c->n[K_VIEW], sb_json_get(a, "bufferView"));
        const sb_json *sp = sb_json_get(a, "sparse");
        if (sp && sp->type == SB_JSON_OBJECT) {
            mark(view, c->n[K_VIEW], get2(sp, "indices", "bufferView"));
            mark(view, c->n[K_VIEW], get2(sp, "values", "bufferView"));
        }
    }
    for (uint64_t i = 0; i < c->n[K_IMAGE]; i++) mark(view, c->n[K_VIEW], sb_json_get(&c->arr[K_IMAGE]->items[i], "bufferView"));
    for (uint64_t i = 0; i < c->n[K_VIEW]; i++)
        if (view[i]) mark(c->used[K_BUFFER], c->n[K_BUFFER], sb_json_get(&c->arr[K_VIEW]->items[i], "buffer"));
    for (uint64_t i = 0; i < c->n[K_NODE]; i++) {
        const sb_json *lp = get2(&c->arr[K_NODE]->items[i], "extensions", "KHR_lights_punctual");
        mark(c->used[K_LIGHT], c->n[K_LIGHT], lp && lp->type == SB_JSON_OBJECT ? sb_json_get(lp, "light") : NULL);
    }
}

/* A part that failed its check: refused when something reads it; else left out, with what is wrong said. */
static bool lenient(ck *c, int kind, uint64_t i, bool ok) {
    if (ok || c->used[kind][i]) return ok;
    const char *msg = c->err->msg, *file = c->d->file;
    size_t fl = strlen(file);
    if (!strncmp(msg, file, fl) && !strncmp(msg + fl, ": ", 2)) msg += fl + 2;   /* the file is said once */
    if (c->d->unused) sb_gltf_note(c->d->unused, c->d->unused_len, "%s (nothing reads this %s)", msg, kind_name[kind]);
    return true;
}

static bool check_buffers(ck *c) {
    c->buf_len = sb_xcalloc(c->n[K_BUFFER] + 1, sizeof(uint64_t));
    for (uint64_t i = 0; i < c->n[K_BUFFER]; i++) {
        const sb_json *b = &c->arr[K_BUFFER]->items[i];
        jpath p = at_i("/buffers", i);
        if (!get_uint(c, b, p.s, "byteLength", true, 0, 1, UINT64_MAX, &c->buf_len[i])) return false;
        bool has_uri;
        if (!lenient(c, K_BUFFER, i, check_uri(c, b, p.s, true, &has_uri))) return false;
        if (!has_uri && (!c->d->glb || i != 0)) {
            /* no bytes anywhere: refused if a bufferView something reads reads it, else left out */
            for (uint64_t v = 0; v < c->n[K_VIEW]; v++) {
                uint64_t bi;
                const sb_json *bv = sb_json_get(&c->arr[K_VIEW]->items[v], "buffer");
                if (bv && sb_json_u64(bv, &bi) && bi == i && c->used[K_VIEW][v])
                    return fail(c, p.s, "no uri (only the first buffer of a .glb may omit it), and bufferView %llu reads it",
                                (unsigned long long)v);
            }
            if (c->d->unused) sb_gltf_note(c->d->unused, c->d->unused_len, "%s: a buffer with no uri that nothing reads", p.s);
            continue;
        }
        if (!has_uri) {
            if (c->buf_len[i] > c->d->bin_size)
                return fail(c, at(p.s, "byteLength").s, "%llu is beyond the .glb's BIN chunk of %llu bytes",
                            (unsigned long long)c->buf_len[i], (unsigned long long)c->d->bin_size);
        }
    }
    return true;
}

static bool check_view(ck *c, uint64_t i);

static bool check_views(ck *c) {
    c->views = sb_xcalloc(c->n[K_VIEW] + 1, sizeof(view_info));
    for (uint64_t i = 0; i < c->n[K_VIEW]; i++)
        if (!lenient(c, K_VIEW, i, check_view(c, i))) return false;
    return true;
}

static bool check_view(ck *c, uint64_t i) {
    {
        const sb_json *v = &c->arr[K_VIEW]->items[i];
        view_info *vi = &c->views[i];
        jpath p = at_i("/bufferViews", i);
        int64_t buf;
        if (!get_index(c, v, p.s, "buffer", true, K_BUFFER, &buf)) return false;
        vi->buffer = (uint64_t)buf;
        if (!get_uint(c, v, p.s, "byteOffset", false, 0, 0, UINT64_MAX, &vi->off)) return false;
        if (!get_uint(c, v, p.s, "byteLength", true, 0, 1, UINT64_MAX, &vi->len)) return false;
        if (!get_uint(c, v, p.s, "byteStride", false, 0, 4, 252, &vi->stride)) return false;
        if (vi->stride % 4)
            return fail(c, at(p.s, "byteStride").s, "%llu is not a multiple of 4", (unsigned long long)vi->stride);
        if (!fits(vi->off, vi->len, c->buf_len[vi->buffer]))
            return fail(c, p.s, "byteOffset %llu + byteLength %llu run past the end of buffer %llu (%llu bytes)",
                        (unsigned long long)vi->off, (unsigned long long)vi->len, (unsigned long long)vi->buffer,
                        (unsigned long long)c->buf_len[vi->buffer]);
    }
    return true;
}

static uint64_t component_size(uint64_t ctype) {
    switch (ctype) {
    case 5120: case 5121: return 1;
    case 5122: case 5123: return 2;
    case 5125: case 5126: return 4;
    default: return 0;
    }
}

/* Bytes of one element; matrix columns start on 4-byte boundaries (glTF 2.0, 3.6.2.4), so a matrix of 1- or
 * 2-byte components is padded after each column: *tail is what the last element needs, its last column
 * unpadded (a MAT3 of bytes: 12 bytes an element, 11 for the last). */
static uint64_t element_size(const char *type, uint64_t csize, uint64_t *ncomp, uint64_t *tail) {
    static const struct { const char *name; uint64_t n, cols; } types[] = {
        {"SCALAR", 1, 0}, {"VEC2", 2, 0}, {"VEC3", 3, 0}, {"VEC4", 4, 0}, {"MAT2", 4, 2}, {"MAT3", 9, 3}, {"MAT4", 16, 4}};
    for (size_t k = 0; k < SB_COUNT(types); k++) {
        if (strcmp(type, types[k].name)) continue;
        *ncomp = types[k].n;
        if (!types[k].cols) return *tail = types[k].n * csize;
        uint64_t rows = types[k].cols * csize, col = (rows + 3) / 4 * 4;
        *tail = (types[k].cols - 1) * col + rows;
        return types[k].cols * col;
    }
    return *tail = 0;
}

/* A range of `count` elements every `stride` bytes from `off` in bufferView `view`, the last of which needs
 * `elem` bytes. */
static bool check_range(ck *c, const char *path, uint64_t view, uint64_t off, uint64_t count, uint64_t elem,
                        uint64_t stride, uint64_t csize) {
    const view_info *v = &c->views[view];
    uint64_t need;
    if (!mul_add(stride, count - 1, elem, &need))
        return fail(c, path, "count %llu of %llu-byte elements overflows 64 bits", (unsigned long long)count,
                    (unsigned long long)elem);
    if (!fits(off, need, v->len))
        return fail(c, path, "byteOffset %llu + %llu bytes (count %llu, stride %llu) run past the end of bufferView %llu (%llu bytes)",
                    (unsigned long long)off, (unsigned long long)need, (unsigned long long)count,
                    (unsigned long long)stride, (unsigned long long)view, (unsigned long long)v->len);
    if (off % csize)
        return fail(c, at(path, "byteOffset").s, "%llu is not a multiple of the component size %llu",
                    (unsigned long long)off, (unsigned long long)csize);
    if ((v->off % csize + off % csize) % csize)
        return fail(c, path, "offset in the buffer (bufferView %llu at %llu + byteOffset %llu) is not a multiple of the component size %llu",
                    (unsigned long long)view, (unsigned long long)v->off, (unsigned long long)off,
                    (unsigned long long)csize);
    return true;
}

static bool check_sparse(ck *c, const sb_json *sparse, const char *path, const acc_info *a) {
    uint64_t count;
    if (!get_uint(c, sparse, path, "count", true, 0, 1, a->count < INT32_MAX ? a->count : INT32_MAX, &count)) return false;
    const sb_json *ind, *val;
    if (!field(c, sparse, path, "indices", SB_JSON_OBJECT, true, &ind)) return false;
    if (!field(c, sparse, path, "values", SB_JSON_OBJECT, true, &val)) return false;
    jpath pi = at(path, "indices"), pv = at(path, "values");
    int64_t iv, vv;
    uint64_t ioff, voff, ictype;
    if (!get_index(c, ind, pi.s, "bufferView", true, K_VIEW, &iv)) return false;
    if (!get_uint(c, ind, pi.s, "byteOffset", false, 0, 0, INT32_MAX, &ioff)) return false; /* the library keeps an int */
    if (!get_uint(c, ind, pi.s, "componentType", true, 0, 0, UINT64_MAX, &ictype)) return false;
    if (ictype != 5121 && ictype != 5123 && ictype != 5125)
        return fail(c, at(pi.s, "componentType").s, "%llu is not 5121, 5123 or 5125 (unsigned byte, short or int)",
                    (unsigned long long)ictype);
    if (c->views[iv].stride) return fail(c, pi.s, "bufferView %lld of sparse indices must not have a byteStride", (long long)iv);
    uint64_t isize = component_size(ictype);
    if (!check_range(c, pi.s, (uint64_t)iv, ioff, count, isize, isize, isize)) return false;
    if (!get_index(c, val, pv.s, "bufferView", true, K_VIEW, &vv)) return false;
    if (!get_uint(c, val, pv.s, "byteOffset", false, 0, 0, INT32_MAX, &voff)) return false;
    return check_range(c, pv.s, (uint64_t)vv, voff, count, a->tail, a->elem, a->csize);
}

static bool check_accessor(ck *c, uint64_t i);

static bool check_accessors(ck *c) {
    c->accs = sb_xcalloc(c->n[K_ACCESSOR] + 1, sizeof(acc_info));
    for (uint64_t i = 0; i < c->n[K_ACCESSOR]; i++)
        if (!lenient(c, K_ACCESSOR, i, check_accessor(c, i))) return false;
    return true;
}

static bool check_accessor(ck *c, uint64_t i) {
    {
        const sb_json *a = &c->arr[K_ACCESSOR]->items[i];
        acc_info *ai = &c->accs[i];
        jpath p = at_i("/accessors", i);
        int64_t view;
        uint64_t ctype;
        const char *type;
        if (!get_index(c, a, p.s, "bufferView", false, K_VIEW, &view)) return false;
        if (!get_uint(c, a, p.s, "byteOffset", false, 0, 0, UINT64_MAX, &ai->off)) return false;
        if (!get_uint(c, a, p.s, "componentType", true, 0, 0, UINT64_MAX, &ctype)) return false;
        if (!get_uint(c, a, p.s, "count", true, 0, 1, UINT64_MAX, &ai->count)) return false;
        if (!get_choice(c, a, p.s, "type", true, "SCALAR|VEC2|VEC3|VEC4|MAT2|MAT3|MAT4", &type)) return false;
        const sb_json *norm;
        if (!field(c, a, p.s, "normalized", SB_JSON_BOOL, false, &norm)) return false;
        ai->csize = component_size(ctype);
        if (!ai->csize)
            return fail(c, at(p.s, "componentType").s, "%llu is not a glTF component type (5120, 5121, 5122, 5123, 5125, 5126)",
                        (unsigned long long)ctype);
        ai->ctype = (int)ctype;
        ai->elem = element_size(type, ai->csize, &ai->ncomp, &ai->tail);
        ai->has_view = view >= 0;
        if (ai->has_view) {
            ai->view = (uint64_t)view;
            uint64_t st = c->views[view].stride;
            if (st && st < ai->elem)
                return fail(c, p.s, "byteStride %llu of bufferView %lld is smaller than its %llu-byte %s elements",
                            (unsigned long long)st, (long long)view, (unsigned long long)ai->elem, type);
            ai->stride = st ? st : ai->elem;
            if (!check_range(c, p.s, ai->view, ai->off, ai->count, ai->tail, ai->stride, ai->csize)) return false;
        } else {
            if (ai->off) return fail(c, at(p.s, "byteOffset").s, "given without a bufferView");
            uint64_t bytes; /* zeros (and sparse values) only: bound what may be allocated */
            if (!mul_add(ai->count, ai->elem, 0, &bytes) || bytes > (1ull << 32))
                return fail(c, at(p.s, "count").s, "%llu elements without a bufferView exceed 4 GiB",
                            (unsigned long long)ai->count);
        }
        const sb_json *sparse;
        if (!field(c, a, p.s, "sparse", SB_JSON_OBJECT, false, &sparse)) return false;
        if (sparse && !check_sparse(c, sparse, at(p.s, "sparse").s, ai)) return false;
    }
    return true;
}

/* KHR_draco_mesh_compression on a primitive: its bufferView and attribute ids. */
static bool check_draco(ck *c, const sb_json *prim, const char *path) {
    const sb_json *ext, *dr, *attrs;
    if (!field(c, prim, path, "extensions", SB_JSON_OBJECT, false, &ext)) return false;
    if (!ext) return true;
    jpath pe = at(path, "extensions"), pd = at(pe.s, "KHR_draco_mesh_compression");
    if (!field(c, ext, pe.s, "KHR_draco_mesh_compression", SB_JSON_OBJECT, false, &dr)) return false;
    if (!dr) return true;
    int64_t view;
    uint64_t id;
    if (!get_index(c, dr, pd.s, "bufferView", true, K_VIEW, &view) ||
        !field(c, dr, pd.s, "attributes", SB_JSON_OBJECT, true, &attrs))
        return false;
    for (uint32_t k = 0; k < attrs->count; k++)
        if (!uint_value(c, &attrs->items[k], at(at(pd.s, "attributes").s, attrs->items[k].key).s, 0, UINT32_MAX, &id))
            return false;
    return true;
}

static bool check_primitive(ck *c, const sb_json *prim, const char *path) {
    const sb_json *attrs;
    if (!field(c, prim, path, "attributes", SB_JSON_OBJECT, true, &attrs)) return false;
    jpath pa = at(path, "attributes");
    uint64_t count = 0;
    for (uint32_t k = 0; k < attrs->count; k++) {
        const sb_json *v = &attrs->items[k];
        jpath pk = at(pa.s, v->key);
        int64_t acc = 0;
        if (!index_value(c, v, pk.s, K_ACCESSOR, &acc)) return false;
        const acc_info *ai = &c->accs[acc];
        if (k > 0 && ai->count != count)
            return fail(c, pk.s, "accessor %lld has %llu elements, the primitive's other attributes %llu", (long long)acc,
                        (unsigned long long)ai->count, (unsigned long long)count);
        count = ai->count;
        if (ai->has_view && (ai->off % 4 || ai->stride % 4))
            return fail(c, pk.s, "accessor %lld: a vertex attribute's byteOffset (%llu) and stride (%llu) must be multiples of 4",
                        (long long)acc, (unsigned long long)ai->off, (unsigned long long)ai->stride);
        if (!strcmp(v->key, "POSITION")) {
            if (ai->ncomp != 3 || ai->elem != 3 * ai->csize) return fail(c, pk.s, "accessor %lld is not a VEC3", (long long)acc);
            if (ai->ctype != 5126 && !c->quantization)
                return fail(c, pk.s, "accessor %lld: positions must be float (other types need KHR_mesh_quantization)",
                            (long long)acc);
        }
    }
    int64_t ind, mat;
    if (!get_index(c, prim, path, "indices", false, K_ACCESSOR, &ind)) return false;
    if (ind >= 0) {
        const acc_info *ai = &c->accs[ind];
        jpath pi = at(path, "indices");
        if (ai->ncomp != 1 || (ai->ctype != 5121 && ai->ctype != 5123 && ai->ctype != 5125))
            return fail(c, pi.s, "accessor %lld is not a SCALAR of unsigned byte, short or int", (long long)ind);
        if (ai->has_view && c->views[ai->view].stride)
            return fail(c, pi.s, "accessor %lld: bufferView %llu of indices must not have a byteStride", (long long)ind,
                        (unsigned long long)ai->view);
    }
    if (!get_index(c, prim, path, "material", false, K_MATERIAL, &mat)) return false;
    if (!check_draco(c, prim, path)) return false;
    uint64_t mode;
    if (!get_uint(c, prim, path, "mode", false, 4, 0, 6, &mode)) return false;
    const sb_json *targets;
    if (!field(c, prim, path, "targets", SB_JSON_ARRAY, false, &targets)) return false;
    for (uint32_t t = 0; targets && t < targets->count; t++) {
        jpath pt = at_i(at(path, "targets").s, t);
        const sb_json *tg = &targets->items[t];
        if (tg->type != SB_JSON_OBJECT) return fail(c, pt.s, "expected an object");
        for (uint32_t k = 0; k < tg->count; k++) {
            int64_t acc;
            if (!index_value(c, &tg->items[k], at(pt.s, tg->items[k].key).s, K_ACCESSOR, &acc)) return false;
        }
    }
    return true;
}

static bool check_meshes(ck *c) {
    for (uint64_t i = 0; i < c->n[K_MESH]; i++) {
        const sb_json *m = &c->arr[K_MESH]->items[i], *prims;
        jpath p = at_i("/meshes", i);
        if (!field(c, m, p.s, "primitives", SB_JSON_ARRAY, true, &prims)) return false;
        jpath pp = at(p.s, "primitives");
        for (uint32_t k = 0; k < prims->count; k++) {
            jpath pk = at_i(pp.s, k);
            if (prims->items[k].type != SB_JSON_OBJECT) return fail(c, pk.s, "expected an object");
            if (!check_primitive(c, &prims->items[k], pk.s)) return false;
        }
    }
    return true;
}

static bool check_transform(ck *c, const sb_json *n, const char *path) {
    double m[16], q[4], v3[3];
    bool has;
    if (!get_numbers(c, n, path, "matrix", 16, m, &has)) return false;
    if (has && (fabs(m[3]) > 1e-6 || fabs(m[7]) > 1e-6 || fabs(m[11]) > 1e-6 || fabs(m[15] - 1) > 1e-6))
        return fail(c, at(path, "matrix").s, "not decomposable to translation, rotation and scale: its last row is (%g, %g, %g, %g), not (0, 0, 0, 1)",
                    m[3], m[7], m[11], m[15]);
    if (!get_numbers(c, n, path, "translation", 3, v3, &has)) return false;
    if (!get_numbers(c, n, path, "scale", 3, v3, &has)) return false;
    if (!get_numbers(c, n, path, "rotation", 4, q, &has)) return false;
    if (has) {
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (len < 1e-6) return fail(c, at(path, "rotation").s, "a zero-length quaternion is not a rotation");
        if (fabs(len - 1) > 1e-3 && c->rotations_normalised++ == 0) {
            c->first_rotation = at(path, "rotation");
            c->first_rotation_len = len;
        }
    }
    return true;
}

static bool check_nodes(ck *c) {
    c->parent = sb_xmalloc(sizeof(int64_t) * (c->n[K_NODE] + 1));
    for (uint64_t i = 0; i < c->n[K_NODE]; i++) c->parent[i] = -1;
    for (uint64_t i = 0; i < c->n[K_NODE]; i++) {
        const sb_json *n = &c->arr[K_NODE]->items[i], *children, *ext, *lp;
        jpath p = at_i("/nodes", i);
        int64_t x;
        if (!get_index(c, n, p.s, "mesh", false, K_MESH, &x) || !get_index(c, n, p.s, "camera", false, K_CAMERA, &x) ||
            !get_index(c, n, p.s, "skin", false, K_SKIN, &x))
            return false;
        if (!check_transform(c, n, p.s)) return false;
        if (!index_list(c, n, p.s, "children", K_NODE, &children)) return false;
        for (uint32_t k = 0; children && k < children->count; k++) {
            uint64_t ch;
            sb_json_u64(&children->items[k], &ch);
            jpath pc = at_i(at(p.s, "children").s, k);
            if (ch == i) return fail(c, pc.s, "node %llu is its own child (a cycle)", (unsigned long long)i);
            if (c->parent[ch] == (int64_t)i)
                return fail(c, pc.s, "node %llu is listed twice", (unsigned long long)ch);
            if (c->parent[ch] >= 0)
                return fail(c, pc.s, "node %llu has two parents (nodes %lld and %llu)", (unsigned long long)ch,
                            (long long)c->parent[ch], (unsigned long long)i);
            c->parent[ch] = (int64_t)i;
        }
        if (!field(c, n, p.s, "extensions", SB_JSON_OBJECT, false, &ext)) return false;
        if (ext && !field(c, ext, at(p.s, "extensions").s, "KHR_lights_punctual", SB_JSON_OBJECT, false, &lp)) return false;
        if (ext && lp && !get_index(c, lp, at(at(p.s, "extensions").s, "KHR_lights_punctual").s, "light", true, K_LIGHT, &x))
            return false;
    }
    /* a real cycle: a walk up the (single) parents that comes back to itself */
    uint8_t *state = sb_xcalloc(c->n[K_NODE] + 1, 1);
    bool ok = true;
    for (uint64_t i = 0; ok && i < c->n[K_NODE]; i++) {
        if (state[i]) continue;
        int64_t j = (int64_t)i;
        while (j >= 0 && state[j] == 0) {
            state[j] = 1;
            j = c->parent[j];
        }
        if (j >= 0 && state[j] == 1)
            ok = fail(c, at(at_i("/nodes", (uint64_t)j).s, "children").s, "the node graph has a cycle through node %lld",
                      (long long)j);
        for (j = (int64_t)i; j >= 0 && state[j] == 1; j = c->parent[j]) state[j] = 2;
    }
    free(state);
    /* each node's depth, in linear time (a walk up stops at a node whose depth is known, then the path is given
       its depths): a chain deeper than SB_GLTF_MAX_DEPTH is refused, naming the limit */
    int64_t *depth = sb_xmalloc(sizeof(int64_t) * (c->n[K_NODE] + 1)), *up = NULL;
    size_t nup = 0, cap = 0;
    for (uint64_t i = 0; i < c->n[K_NODE]; i++) depth[i] = -1;
    for (uint64_t i = 0; ok && i < c->n[K_NODE]; i++) {
        nup = 0;
        int64_t j = (int64_t)i;
        for (; j >= 0 && depth[j] < 0; j = c->parent[j]) {
            if (nup == cap) up = sb_xrealloc(up, sizeof *up * (cap = cap ? 2 * cap : 64));
            up[nup++] = j;
        }
        int64_t d = j >= 0 ? depth[j] : 0;   /* a root is 1 level deep */
        for (size_t k = nup; k-- > 0;) depth[up[k]] = ++d;
        if (depth[i] > SB_GLTF_MAX_DEPTH)
            ok = fail(c, at_i("/nodes", i).s, "the node graph is %lld levels deep here, deeper than the %d levels "
                                              "shadowbench reads", (long long)depth[i], SB_GLTF_MAX_DEPTH);
    }
    free(up);
    free(depth);
    return ok;
}

static bool check_scenes(ck *c, const sb_json *root) {
    for (uint64_t i = 0; i < c->n[K_SCENE]; i++) {
        const sb_json *s = &c->arr[K_SCENE]->items[i], *nodes;
        jpath p = at_i("/scenes", i);
        if (!index_list(c, s, p.s, "nodes", K_NODE, &nodes)) return false;
        for (uint32_t k = 0; nodes && k < nodes->count; k++) {
            uint64_t nd;
            sb_json_u64(&nodes->items[k], &nd);
            if (c->parent[nd] >= 0)
                return fail(c, at_i(at(p.s, "nodes").s, k).s, "node %llu is not a root node (it is a child of node %lld)",
                            (unsigned long long)nd, (long long)c->parent[nd]);
        }
    }
    int64_t sc;
    return get_index(c, root, "", "scene", false, K_SCENE, &sc);
}

static bool check_light(ck *c, uint64_t i);

static bool check_lights(ck *c) {
    for (uint64_t i = 0; i < c->n[K_LIGHT]; i++)
        if (!lenient(c, K_LIGHT, i, check_light(c, i))) return false;
    return true;
}

static bool check_light(ck *c, uint64_t i) {
    {
        const sb_json *l = &c->arr[K_LIGHT]->items[i], *spot;
        jpath p = at_i("/extensions/KHR_lights_punctual/lights", i);
        const char *type;
        double color[3], v, inner, outer;
        bool has;
        if (!get_choice(c, l, p.s, "type", true, "directional|point|spot", &type)) return false;
        if (!get_numbers(c, l, p.s, "color", 3, color, &has)) return false;
        for (int k = 0; has && k < 3; k++)
            if (color[k] < 0 || color[k] > 1) return fail(c, at_i(at(p.s, "color").s, (uint64_t)k).s, "%g is out of range [0, 1]", color[k]);
        if (!get_number(c, l, p.s, "intensity", false, 1, 0, false, INFINITY, true, &v)) return false;
        if (!get_number(c, l, p.s, "range", false, 1, 0, true, INFINITY, true, &v)) return false;
        if (!field(c, l, p.s, "spot", SB_JSON_OBJECT, !strcmp(type, "spot"), &spot)) return false;
        if (spot) {
            jpath ps = at(p.s, "spot");
            if (!get_number(c, spot, ps.s, "outerConeAngle", false, SB_PI / 4, 0, true, SB_PI / 2, false, &outer)) return false;
            if (!get_number(c, spot, ps.s, "innerConeAngle", false, 0, 0, false, outer, true, &inner)) return false;
        }
    }
    return true;
}

static bool check_camera(ck *c, uint64_t i) {
    const sb_json *cam = &c->arr[K_CAMERA]->items[i], *o;
    jpath p = at_i("/cameras", i);
    const char *type;
    double znear, zfar, v;
    if (!get_choice(c, cam, p.s, "type", true, "perspective|orthographic", &type)) return false;
    bool persp = !strcmp(type, "perspective");
    if (!field(c, cam, p.s, type, SB_JSON_OBJECT, true, &o)) return false;
    jpath po = at(p.s, type);
    if (persp) {
        if (!get_number(c, o, po.s, "yfov", true, 0, 0, true, SB_PI, true, &v)) return false;
        if (!get_number(c, o, po.s, "aspectRatio", false, 1, 0, true, INFINITY, true, &v)) return false;
        if (!get_number(c, o, po.s, "znear", true, 0, 0, true, INFINITY, true, &znear)) return false;
        if (!get_number(c, o, po.s, "zfar", false, INFINITY, znear, true, INFINITY, false, &zfar)) return false;
    } else {
        if (!get_number(c, o, po.s, "xmag", true, 0, -INFINITY, true, INFINITY, true, &v)) return false;
        if (!get_number(c, o, po.s, "ymag", true, 0, -INFINITY, true, INFINITY, true, &v)) return false;
        if (!get_number(c, o, po.s, "znear", true, 0, 0, false, INFINITY, true, &znear)) return false;
        if (!get_number(c, o, po.s, "zfar", true, 0, znear, true, INFINITY, true, &zfar)) return false;
    }
    return true;
}

/* Cameras draw nothing: one that breaks a rule is a note, refused only where a path uses it. */
static bool check_cameras(ck *c) {
    for (uint64_t i = 0; i < c->n[K_CAMERA]; i++) {
        if (c->arr[K_CAMERA]->items[i].type != SB_JSON_OBJECT) return fail(c, at_i("/cameras", i).s, "expected an object");
        sb_err why;
        ck one = *c;
        one.err = &why;
        size_t skip = strlen(c->d->file) + 2;   /* the note is about this file: without its name */
        if (!check_camera(&one, i) && c->d->unused)
            sb_gltf_note(c->d->unused, c->d->unused_len, "%s (no path uses it here; one that does is refused)",
                         strlen(why.msg) > skip ? why.msg + skip : why.msg);
    }
    return true;
}

static bool check_materials(ck *c) {
    for (uint64_t i = 0; i < c->n[K_MATERIAL]; i++) {
        const sb_json *m = &c->arr[K_MATERIAL]->items[i], *pbr, *tex, *ds;
        jpath p = at_i("/materials", i);
        const char *mode;
        double v, f[4];
        bool has;
        if (!get_choice(c, m, p.s, "alphaMode", false, "OPAQUE|MASK|BLEND", &mode)) return false;
        if (!get_number(c, m, p.s, "alphaCutoff", false, 0.5, 0, false, INFINITY, true, &v)) return false;
        if (!field(c, m, p.s, "doubleSided", SB_JSON_BOOL, false, &ds)) return false;
        if (!field(c, m, p.s, "pbrMetallicRoughness", SB_JSON_OBJECT, false, &pbr)) return false;
        if (!pbr) continue;
        jpath pp = at(p.s, "pbrMetallicRoughness");
        if (!get_numbers(c, pbr, pp.s, "baseColorFactor", 4, f, &has)) return false;
        for (int k = 0; has && k < 4; k++)
            if (f[k] < 0 || f[k] > 1)
                return fail(c, at_i(at(pp.s, "baseColorFactor").s, (uint64_t)k).s, "%g is out of range [0, 1]", f[k]);
        if (!field(c, pbr, pp.s, "baseColorTexture", SB_JSON_OBJECT, false, &tex)) return false;
        if (tex) {
            jpath pt = at(pp.s, "baseColorTexture");
            int64_t t;
            uint64_t set;
            if (!get_index(c, tex, pt.s, "index", true, K_TEXTURE, &t)) return false;
            if (!get_uint(c, tex, pt.s, "texCoord", false, 0, 0, 31, &set)) return false;
        }
    }
    return true;
}

static bool check_textures_images(ck *c) {
    for (uint64_t i = 0; i < c->n[K_TEXTURE]; i++) {
        const sb_json *t = &c->arr[K_TEXTURE]->items[i];
        jpath p = at_i("/textures", i);
        int64_t x;
        if (!get_index(c, t, p.s, "source", false, K_IMAGE, &x) || !get_index(c, t, p.s, "sampler", false, K_SAMPLER, &x))
            return false;
    }
    for (uint64_t i = 0; i < c->n[K_IMAGE]; i++) {
        const sb_json *im = &c->arr[K_IMAGE]->items[i];
        jpath p = at_i("/images", i);
        int64_t view;
        bool has_uri;
        if (!check_uri(c, im, p.s, false, &has_uri)) return false;
        if (!get_index(c, im, p.s, "bufferView", false, K_VIEW, &view)) return false;
        if (has_uri && view >= 0) return fail(c, p.s, "has both a uri and a bufferView");
    }
    return true;
}

static bool check_skins(ck *c) {
    for (uint64_t i = 0; i < c->n[K_SKIN]; i++) {
        const sb_json *s = &c->arr[K_SKIN]->items[i], *joints;
        jpath p = at_i("/skins", i);
        int64_t ibm, root;
        if (!field(c, s, p.s, "joints", SB_JSON_ARRAY, true, &joints)) return false;
        if (joints->count == 0) return fail(c, at(p.s, "joints").s, "a skin needs at least one joint");
        if (!index_list(c, s, p.s, "joints", K_NODE, NULL)) return false;
        /* each node once (glTF's uniqueItems): a joint listed twice gets two inverse bind matrices for one node */
        unsigned char *seen = sb_xcalloc((size_t)c->n[K_NODE] / 8 + 1, 1);
        for (uint32_t k = 0; k < joints->count; k++) {
            uint64_t jn;
            sb_json_u64(&joints->items[k], &jn);
            if (seen[jn / 8] & (1u << (jn % 8))) {
                free(seen);
                return fail(c, at_i(at(p.s, "joints").s, k).s, "node %llu is listed twice (a skin's joints are unique)",
                            (unsigned long long)jn);
            }
            seen[jn / 8] |= (unsigned char)(1u << (jn % 8));
        }
        free(seen);
        if (!get_index(c, s, p.s, "skeleton", false, K_NODE, &root)) return false;
        if (!get_index(c, s, p.s, "inverseBindMatrices", false, K_ACCESSOR, &ibm)) return false;
        if (ibm >= 0) {
            const acc_info *a = &c->accs[ibm];
            if (a->ncomp != 16 || a->ctype != 5126 || a->count < joints->count)
                return fail(c, at(p.s, "inverseBindMatrices").s, "accessor %lld must hold %u float MAT4s", (long long)ibm,
                            joints->count);
        }
    }
    return true;
}

static bool check_animations(ck *c) {
    for (uint64_t i = 0; i < c->n[K_ANIMATION]; i++) {
        const sb_json *an = &c->arr[K_ANIMATION]->items[i], *samplers, *channels;
        jpath p = at_i("/animations", i);
        if (!field(c, an, p.s, "samplers", SB_JSON_ARRAY, true, &samplers)) return false;
        if (!field(c, an, p.s, "channels", SB_JSON_ARRAY, true, &channels)) return false;
        for (uint32_t k = 0; k < samplers->count; k++) {
            const sb_json *s = &samplers->items[k];
            jpath ps = at_i(at(p.s, "samplers").s, k);
            int64_t x;
            const char *interp;
            if (s->type != SB_JSON_OBJECT) return fail(c, ps.s, "expected an object");
            if (!get_index(c, s, ps.s, "input", true, K_ACCESSOR, &x) || !get_index(c, s, ps.s, "output", true, K_ACCESSOR, &x) ||
                !get_choice(c, s, ps.s, "interpolation", false, "LINEAR|STEP|CUBICSPLINE", &interp))
                return false;
        }
        for (uint32_t k = 0; k < channels->count; k++) {
            const sb_json *ch = &channels->items[k], *target;
            jpath pc = at_i(at(p.s, "channels").s, k);
            uint64_t smp;
            int64_t node;
            const char *path;
            if (ch->type != SB_JSON_OBJECT) return fail(c, pc.s, "expected an object");
            if (!get_uint(c, ch, pc.s, "sampler", true, 0, 0, samplers->count ? samplers->count - 1 : 0, &smp)) return false;
            if (!samplers->count) return fail(c, at(pc.s, "sampler").s, "the animation has no samplers");
            if (!field(c, ch, pc.s, "target", SB_JSON_OBJECT, true, &target)) return false;
            jpath pt = at(pc.s, "target");
            if (!get_index(c, target, pt.s, "node", false, K_NODE, &node)) return false;
            const sb_json *ext = sb_json_get(target, "extensions"), *tp = sb_json_get(target, "path");
            bool pointer = ext && sb_json_get(ext, "KHR_animation_pointer");
            if (pointer || (tp && tp->type == SB_JSON_STRING && !strcmp(tp->text, "pointer"))) {
                /* animates what we do not (with KHR_animation_pointer declared or not): left out, said */
                if (pointer && !get_choice(c, target, pt.s, "path", true, "pointer", &path)) return false;
                if (c->d->unused)
                    sb_gltf_note(c->d->unused, c->d->unused_len, "%s: %s is not applied", pc.s,
                                 pointer ? "KHR_animation_pointer" : "a \"pointer\" channel");
                continue;
            }
            if (!get_choice(c, target, pt.s, "path", true, "translation|rotation|scale|weights", &path)) return false;
        }
    }
    return true;
}

/* The top-level arrays (and the lights of KHR_lights_punctual): arrays of objects. */
static bool collect_arrays(ck *c, const sb_json *root) {
    for (int k = 0; k < K_COUNT; k++) {
        const sb_json *holder = root;
        jpath p = {"/"};
        if (k == K_LIGHT) {
            const sb_json *ext, *lp;
            if (!field(c, root, "", "extensions", SB_JSON_OBJECT, false, &ext)) return false;
            if (ext && !field(c, ext, "/extensions", "KHR_lights_punctual", SB_JSON_OBJECT, false, &lp)) return false;
            if (!ext || !lp) continue;
            holder = lp;
            snprintf(p.s, sizeof p.s, "/extensions/KHR_lights_punctual");
        }
        const sb_json *a;
        if (!field(c, holder, k == K_LIGHT ? p.s : "", array_key[k], SB_JSON_ARRAY, false, &a)) return false;
        if (!a) continue;
        for (uint32_t i = 0; i < a->count; i++)
            if (a->items[i].type != SB_JSON_OBJECT)
                return fail(c, at_i(at(k == K_LIGHT ? p.s : "", array_key[k]).s, i).s, "expected an object, found %s",
                            sb_json_type_name(a->items[i].type));
        c->arr[k] = a;
        c->n[k] = a->count;
    }
    const sb_json *used;
    if (!field(c, root, "", "extensionsUsed", SB_JSON_ARRAY, false, &used)) return false;
    for (uint32_t i = 0; used && i < used->count; i++)
        if (used->items[i].type == SB_JSON_STRING && !strcmp(used->items[i].text, "KHR_mesh_quantization"))
            c->quantization = true;
    return true;
}

/* A required extension is one a loader must apply or refuse the file. Those
 * shadowbench applies, and those that change nothing a shadow depends on
 * (shading, texture formats: an alpha mask in a format it cannot decode is
 * reported by the loader), pass; any other is refused. */
static bool check_required(ck *c, const sb_json *root) {
    static const char *const applied[] = {"KHR_lights_punctual", "KHR_mesh_quantization", "KHR_texture_transform",
                                          "EXT_mesh_gpu_instancing", "KHR_texture_basisu", "EXT_texture_webp",
                                          "EXT_texture_avif", "MSFT_texture_dds", "KHR_xmp_json_ld"};
    const sb_json *req;
    if (!field(c, root, "", "extensionsRequired", SB_JSON_ARRAY, false, &req)) return false;
    for (uint32_t i = 0; req && i < req->count; i++) {
        jpath p = at_i("/extensionsRequired", i);
        const sb_json *v = &req->items[i];
        if (v->type != SB_JSON_STRING) return fail(c, p.s, "expected a string, found %s", sb_json_type_name(v->type));
        bool ok = !strncmp(v->text, "KHR_materials_", 14);
        for (size_t k = 0; k < sizeof applied / sizeof applied[0]; k++) ok |= !strcmp(v->text, applied[k]);
        if (ok) continue;
        if (!strcmp(v->text, "KHR_draco_mesh_compression")) {
            if (SB_HAVE_DRACO) continue;
            return fail(c, p.s, "the file requires KHR_draco_mesh_compression and this shadowbench was built without "
                        "Draco (libdraco-dev)");
        }
        if (!strcmp(v->text, "EXT_meshopt_compression"))
            return fail(c, p.s, "the file requires EXT_meshopt_compression: meshopt-compressed buffers are not decoded "
                        "(re-export it without meshopt compression)");
        return fail(c, p.s, "the file requires the extension %s, which shadowbench does not apply", v->text);
    }
    return true;
}

/* Morph targets of a primitive (0 without). */
static uint32_t target_count(const sb_json *prim) {
    const sb_json *t = sb_json_get(prim, "targets");
    return t && t->type == SB_JSON_ARRAY ? t->count : 0;
}

/* The node rules that tie a node to its mesh and skin (glTF 2.0, 5.25 node):
 * a node with `skin` or `weights` has a mesh; every primitive of a skinned
 * node's mesh has JOINTS_0 and WEIGHTS_0; a node's `weights` has one weight
 * per morph target of each of its mesh's primitives (and so does a mesh's
 * own `weights`). All refused with the JSON path: a loader that went on would
 * pose or morph something else than the file's author saw. */
static bool check_node_mesh_rules(ck *c) {
    for (uint64_t i = 0; i < c->n[K_MESH]; i++) {
        const sb_json *m = &c->arr[K_MESH]->items[i], *w = sb_json_get(m, "weights"), *prims = sb_json_get(m, "primitives");
        if (!w || w->type != SB_JSON_ARRAY || !prims) continue;
        for (uint32_t k = 0; k < prims->count; k++)
            if (target_count(&prims->items[k]) != w->count)
                return fail(c, at(at_i("/meshes", i).s, "weights").s,
                            "%u weight(s), but primitive %u has %u morph target(s)", w->count, k,
                            target_count(&prims->items[k]));
    }
    for (uint64_t i = 0; i < c->n[K_NODE]; i++) {
        const sb_json *n = &c->arr[K_NODE]->items[i];
        jpath p = at_i("/nodes", i);
        const sb_json *skin = sb_json_get(n, "skin"), *weights = sb_json_get(n, "weights"), *mesh = sb_json_get(n, "mesh");
        if (skin && !mesh) return fail(c, at(p.s, "skin").s, "a node with a skin has a mesh to skin (none here)");
        if (weights && !mesh) return fail(c, at(p.s, "weights").s, "a node with morph weights has a mesh (none here)");
        if (!mesh) continue;
        uint64_t mi;
        sb_json_u64(mesh, &mi);
        const sb_json *prims = sb_json_get(&c->arr[K_MESH]->items[mi], "primitives");
        for (uint32_t k = 0; prims && k < prims->count; k++) {
            const sb_json *attrs = sb_json_get(&prims->items[k], "attributes");
            jpath pk = at_i(at(at_i("/meshes", mi).s, "primitives").s, k);
            if (skin && (!sb_json_get(attrs, "JOINTS_0") || !sb_json_get(attrs, "WEIGHTS_0")))
                return fail(c, at(pk.s, "attributes").s,
                            "node %llu skins this mesh, but this primitive has no %s (a skinned mesh's primitives "
                            "all have JOINTS_0 and WEIGHTS_0)",
                            (unsigned long long)i, sb_json_get(attrs, "JOINTS_0") ? "WEIGHTS_0" : "JOINTS_0");
            if (weights && weights->type == SB_JSON_ARRAY && target_count(&prims->items[k]) != weights->count)
                return fail(c, at(p.s, "weights").s, "%u weight(s), but its mesh %llu's primitive %u has %u morph target(s)",
                            weights->count, (unsigned long long)mi, k, target_count(&prims->items[k]));
        }
    }
    return true;
}

/* A skin used by a node of a scene has all its joints in that scene (glTF
 * 2.0, 3.7.3 skins): refused with the joint's path. */
static bool check_skin_joints_in_scene(ck *c) {
    uint8_t *in = sb_xmalloc(c->n[K_NODE] + 1);
    /* each node's root, found once in linear time (a chain of a million nodes: each walk ends where one before
       did, and the path is given the root it found) */
    int64_t *root = sb_xmalloc(sizeof(int64_t) * (c->n[K_NODE] + 1));
    for (uint64_t i = 0; i < c->n[K_NODE]; i++) root[i] = -1;
    for (uint64_t i = 0; i < c->n[K_NODE]; i++) {
        int64_t j = (int64_t)i;
        while (root[j] < 0 && c->parent[j] >= 0) j = c->parent[j];
        int64_t r = root[j] >= 0 ? root[j] : j;
        for (int64_t k = (int64_t)i; root[k] < 0; k = c->parent[k] >= 0 ? c->parent[k] : k) {
            root[k] = r;
            if (c->parent[k] < 0) break;
        }
    }
    bool ok = true;
    for (uint64_t sc = 0; ok && sc < c->n[K_SCENE]; sc++) {
        const sb_json *roots = sb_json_get(&c->arr[K_SCENE]->items[sc], "nodes");
        /* a node is in the scene when the walk up its parents ends at one of the scene's roots */
        memset(in, 0, c->n[K_NODE] + 1);
        for (uint32_t k = 0; roots && k < roots->count; k++) {
            uint64_t r;
            sb_json_u64(&roots->items[k], &r);
            in[r] = 1;
        }
        for (uint64_t i = 0; i < c->n[K_NODE]; i++)
            if (in[root[i]] == 1) in[i] = in[i] ? in[i] : 2;
        for (uint64_t i = 0; ok && i < c->n[K_NODE]; i++) {
            const sb_json *skin = in[i] ? sb_json_get(&c->arr[K_NODE]->items[i], "skin") : NULL;
            if (!skin) continue;
            uint64_t si;
            sb_json_u64(skin, &si);
            const sb_json *joints = sb_json_get(&c->arr[K_SKIN]->items[si], "joints");
            for (uint32_t k = 0; ok && joints && k < joints->count; k++) {
                uint64_t jn;
                sb_json_u64(&joints->items[k], &jn);
                if (!in[jn])
                    ok = fail(c, at_i(at(at_i("/skins", si).s, "joints").s, k).s,
                              "joint node %llu is not in scene %llu, which draws node %llu with this skin",
                              (unsigned long long)jn, (unsigned long long)sc, (unsigned long long)i);
            }
        }
    }
    free(root);
    free(in);
    return ok;
}

void sb_gltf_note(char *list, size_t len, const char *fmt, ...) {
    char note[SB_ERR_LEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(note, sizeof note, fmt, ap);
    va_end(ap);
    size_t n = strlen(list);
    if (n + strlen(note) + 3 < len) snprintf(list + n, len - n, "%s%s", n ? "; " : "", note);
}

bool sb_gltf_check_camera(const sb_json *root, const sb_gltf_check_desc *d, uint64_t k, sb_err *err) {
    ck c = {.d = d, .err = err};
    bool ok = root->type == SB_JSON_OBJECT && collect_arrays(&c, root) && (k >= c.n[K_CAMERA] || check_camera(&c, k));
    return ok;
}

uint8_t *sb_gltf_used_buffers(const sb_json *root) {
    sb_gltf_check_desc d = {.file = ""};
    sb_err err;
    ck c = {.d = &d, .err = &err};
    if (root->type != SB_JSON_OBJECT || !collect_arrays(&c, root)) return NULL;
    mark_used(&c);
    for (int k = 0; k < K_COUNT; k++)
        if (k != K_BUFFER) free(c.used[k]);
    return c.used[K_BUFFER];
}

bool sb_gltf_check(const sb_json *root, const sb_gltf_check_desc *d, sb_err *err) {
    ck c = {.d = d, .err = err};
    if (root->type != SB_JSON_OBJECT) return fail(&c, "/", "the document is %s, not an object", sb_json_type_name(root->type));
    bool ok = check_asset(&c, root) && check_required(&c, root) && collect_arrays(&c, root) && (mark_used(&c), true) &&
              check_buffers(&c) && check_views(&c) &&
              check_accessors(&c) && check_meshes(&c) && check_nodes(&c) && check_scenes(&c, root) && check_lights(&c) &&
              check_cameras(&c) && check_materials(&c) && check_textures_images(&c) && check_skins(&c) &&
              check_node_mesh_rules(&c) && check_skin_joints_in_scene(&c) && check_animations(&c);
    if (ok && c.rotations_normalised)
        sb_log("%s: %u node rotation(s) are not unit quaternions and are normalised, first %s (length %.6g)", d->file,
               c.rotations_normalised, c.first_rotation.s, c.first_rotation_len);
    free(c.buf_len);
    free(c.views);
    free(c.accs);
    free(c.parent);
    for (int k = 0; k < K_COUNT; k++) free(c.used[k]);
    return ok;
}

/* ---- .glb container ---- */

static uint32_t le32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

bool sb_glb_split(const unsigned char *data, uint64_t size, const char *file, const char **json, uint64_t *json_len,
                  const unsigned char **bin, uint64_t *bin_len, uint64_t *used, char *unused, size_t unused_len,
                  sb_err *err) {
    *bin = NULL;
    *bin_len = 0;
    if (size < 20 || memcmp(data, "glTF", 4) != 0) return sb_fail(err, "%s: not a .glb file (no 'glTF' header)", file);
    uint32_t version = le32(data + 4), length = le32(data + 8);
    if (version != 2) return sb_fail(err, "%s: .glb container version %u (expected 2)", file, version);
    if (length > size)
        return sb_fail(err, "%s: the .glb header says %u bytes, the file has %llu (truncated?)", file, length,
                       (unsigned long long)size);
    if (length < size && unused)   /* padding after the container: nothing in it is read */
        sb_gltf_note(unused, unused_len, "%llu byte(s) after the .glb's declared length of %u",
                     (unsigned long long)(size - length), length);
    size = length;
    if (used) *used = length;
    uint32_t len0 = le32(data + 12), type0 = le32(data + 16);
    if (type0 != 0x4E4F534Au) return sb_fail(err, "%s: the first .glb chunk is not JSON", file);
    if (!fits(20, len0, size))
        return sb_fail(err, "%s: the .glb JSON chunk of %u bytes runs past the end of the file", file, len0);
    *json = (const char *)data + 20;
    *json_len = len0;
    uint64_t next = 20 + (uint64_t)len0;
    if (size - next >= 8) {
        uint32_t len1 = le32(data + next), type1 = le32(data + next + 4);
        if (type1 == 0x004E4942u) {
            if (!fits(next + 8, len1, size))
                return sb_fail(err, "%s: the .glb BIN chunk of %u bytes runs past the end of the file", file, len1);
            *bin = data + next + 8;
            *bin_len = len1;
        }
    }
    return true;
}
