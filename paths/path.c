/* path.c - keyframe parsing, centripetal Catmull-Rom + slerp, built-in paths. */
#include "path.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "gltf_load.h"
#include "motion.h"
#include "scene_load.h"

/* An animated glTF camera as a path: a key at every time its node's animations key. */
static bool camera_path(sb_path *p, const char *file, int cam, const sb_scene_opts *opts, sb_err *err) {
    sb_camera_keys ck;
    memset(&ck, 0, sizeof ck);
    if (!sb_gltf_camera_keys(&ck, file, cam, opts, err)) {
        free(ck.keys);
        return false;
    }
    if (ck.fov_deg > 0) p->fov_deg = ck.fov_deg;
    p->znear = ck.znear;
    p->zfar = ck.zfar;
    p->key_count = ck.key_count;
    p->keys = sb_xcalloc((size_t)ck.key_count, sizeof *p->keys);
    for (int i = 0; i < ck.key_count; i++) p->keys[i] = (sb_path_key){ck.keys[i].t, ck.keys[i].pos, ck.keys[i].rot, 0};
    free(ck.keys);
    return true;
}

static bool add_key(sb_path *p, int *cap, sb_path_key k) {
    if (p->key_count == *cap) {
        *cap = *cap ? *cap * 2 : 16;
        p->keys = sb_xrealloc(p->keys, (size_t)*cap * sizeof *p->keys);
    }
    p->keys[p->key_count++] = k;
    return true;
}

/* A key or look line's numbers v[1..nt-1] as a key; false: said. */
static bool path_key(bool is_key, const double *v, int nt, const char *name, int lineno, sb_path_key *k, sb_err *err) {
    const int want = is_key ? 9 : 8;
    *k = (sb_path_key){0};
    k->t = v[1];
    k->pos = sb_v3_make(v[2], v[3], v[4]);
    if (is_key) {
        sb_quat q = {v[5], v[6], v[7], v[8]};
        double l = sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
        if (l < 1e-6) return sb_fail(err, "%s:%d: orientation quaternion has zero length", name, lineno);
        k->rot = sb_quat_norm(q);
    } else {
        sb_v3 dir = sb_v3_sub(sb_v3_make(v[5], v[6], v[7]), k->pos);
        if (sb_v3_len(dir) < 1e-12) return sb_fail(err, "%s:%d: look target equals the position", name, lineno);
        k->rot = sb_quat_look(dir, sb_v3_make(0, 1, 0));
    }
    if (nt == want + 1) {
        k->fov_deg = v[want];
        if (k->fov_deg <= 0 || k->fov_deg >= 179) return sb_fail(err, "%s:%d: fov must be in (0, 179) degrees", name, lineno);
    }
    return true;
}

/* One line of a path file (its comment cut): a directive and its numbers into p; false: said. */
static bool path_line(sb_path *p, int *cap, char *buf, const char *name, int lineno, sb_err *err) {
    char *tok[16];
    int nt = 0;
    for (char *t = strtok(buf, " \t\r,"); t && nt < 16; t = strtok(NULL, " \t\r,")) tok[nt++] = t;
    if (nt == 0) return true;
    double v[16];
    for (int i = 1; i < nt; i++) {
        if (!sb_parse_double(tok[i], &v[i]))
            return sb_fail(err, "%s:%d: '%s' is not a finite number (field %d of '%s')", name, lineno, tok[i], i + 1,
                           tok[0]);
        /* beyond this, interpolation overflows (found by fuzzing); far beyond any scene */
        if (fabs(v[i]) > SB_PATH_MAX_COORD)
            return sb_fail(err, "%s:%d: '%s' is out of range (field %d of '%s': |value| <= %g)", name, lineno, tok[i],
                           i + 1, tok[0], SB_PATH_MAX_COORD);
    }
    if (strcmp(tok[0], "fov") == 0 || strcmp(tok[0], "near") == 0 || strcmp(tok[0], "far") == 0) {
        if (nt != 2 || v[1] <= 0 || (tok[0][0] == 'f' && tok[0][1] == 'o' && v[1] >= 179))
            return sb_fail(err, "%s:%d: expected '%s VALUE' with a positive value%s", name, lineno, tok[0],
                           tok[0][1] == 'o' ? " below 179 degrees" : "");
        if (tok[0][1] == 'o') p->fov_deg = v[1];
        else if (tok[0][1] == 'e') p->znear = v[1];
        else p->zfar = v[1];
        return true;
    }
    bool is_key = strcmp(tok[0], "key") == 0, is_look = strcmp(tok[0], "look") == 0;
    if (!is_key && !is_look)
        return sb_fail(err, "%s:%d: unknown directive '%s' (expected key, look, fov, near or far)", name, lineno, tok[0]);
    int want = is_key ? 9 : 8;
    if (nt != want && nt != want + 1)
        return sb_fail(err, "%s:%d: '%s' takes %s, got %d numbers", name, lineno, tok[0],
                       is_key ? "T PX PY PZ QX QY QZ QW [FOV]" : "T PX PY PZ TX TY TZ [FOV]", nt - 1);
    sb_path_key k;
    if (!path_key(is_key, v, nt, name, lineno, &k, err)) return false;
    if (p->key_count > 0 && !(k.t > p->keys[p->key_count - 1].t))
        return sb_fail(err, "%s:%d: time %g does not increase (previous key at %g)", name, lineno, k.t,
                       p->keys[p->key_count - 1].t);
    return add_key(p, cap, k);
}

bool sb_path_parse(sb_path *p, const char *name, const char *text, sb_err *err) {
    memset(p, 0, sizeof *p);
    p->file = sb_strdup(name);
    p->fov_deg = 60;
    p->content_hash = sb_fnv1a(SB_FNV_SEED, text, strlen(text));
    int cap = 0, lineno = 0;
    bool ok = true;
    for (const char *line = text; ok && *line;) {
        lineno++;
        const char *eol = strchr(line, '\n');
        size_t len = eol ? (size_t)(eol - line) : strlen(line);
        char buf[1024];
        if (len >= sizeof buf) {
            ok = sb_fail(err, "%s:%d: line too long", name, lineno);
            break;
        }
        memcpy(buf, line, len);
        buf[len] = 0;
        line = eol ? eol + 1 : line + len;
        char *hash = strchr(buf, '#');
        if (hash) *hash = 0;
        ok = path_line(p, &cap, buf, name, lineno, err);
    }
    if (ok && p->key_count == 0) ok = sb_fail(err, "%s: no keyframes (expected 'key' or 'look' lines)", name);
    if (ok && p->znear > 0 && p->zfar > 0 && p->zfar <= p->znear)
        ok = sb_fail(err, "%s: far (%g) must exceed near (%g)", name, p->zfar, p->znear);
    if (!ok) sb_path_free(p);
    return ok;
}

/* ---- built-in paths stay outside the model ---- */

static void camera_axes(sb_camera *c);

#define SB_PATH_CLEARANCE 0.01  /* no surface nearer the camera than this share of the scene's diagonal */
#define SB_PATH_VIEW 0.05       /* the view's centre ray travels at least this share before its first hit */

/* Whether a camera at pos (world) looking along fwd stands outside the model:
 * no surface within the clearance in 14 directions (axes and diagonals), none
 * of those rays starting inside a closed surface, and the centre ray free for
 * a share of the scene. */
static bool view_clear(const sb_scene *s, sb_v3 pos, sb_v3 fwd, double diag) {
    sb_scene_sync_vertices(s);   /* the triangles at the pose the scene holds */
    sb_v3 o = sb_v3_sub(pos, s->origin);
    for (int k = 0; k < 14; k++) {
        sb_v3 d = k < 6 ? sb_v3_make(k == 0 ? 1 : k == 1 ? -1 : 0, k == 2 ? 1 : k == 3 ? -1 : 0, k == 4 ? 1 : k == 5 ? -1 : 0)
                        : sb_v3_norm(sb_v3_make((k - 6) & 1 ? 1 : -1, (k - 6) & 2 ? 1 : -1, (k - 6) & 4 ? 1 : -1));
        bool inside = false;
        double t = sb_scene_raycast(s, o, d, INFINITY, &inside);
        if (inside || t < SB_PATH_CLEARANCE * diag) return false;
    }
    return !(sb_scene_raycast(s, o, sb_v3_norm(fwd), SB_PATH_VIEW * diag, NULL) < SB_PATH_VIEW * diag);
}

/* Raises the keys around every sampled view that is not clear (looking at
 * the same targets) until all are, or a cap. Returns the views still not clear. */
static int keep_outside(sb_path *p, const sb_scene *s, const sb_v3 *targets) {
    sb_v3 e = sb_v3_sub(s->bounds.hi, s->bounds.lo);
    double diag = sb_v3_len(e), step = 0.02 * diag;
    int bad = 0;
    for (int round = 0; round < 80; round++) {
        bad = 0;
        for (int i = 0; i + 1 < p->key_count; i++)
            for (int j = 0; j <= 8; j++) {
                sb_camera c;
                memset(&c, 0, sizeof c);
                double t = p->keys[i].t + (p->keys[i + 1].t - p->keys[i].t) * j / 8;
                sb_path_eval(p, t, &c.pos, &c.rot, &c.fov_deg);
                camera_axes(&c);
                if (view_clear(s, c.pos, c.forward, diag)) continue;
                bad++;
                for (int k = i; k <= i + 1; k++) {
                    if (j == 0 && k == i + 1) continue; /* a key's own view moves only that key */
                    if (j == 8 && k == i) continue;
                    p->keys[k].pos.y += step;
                    p->keys[k].rot = sb_quat_look(sb_v3_sub(targets[k], p->keys[k].pos), sb_v3_make(0, 1, 0));
                }
            }
        if (!bad) break;
    }
    return bad;
}

/* Built-in paths from the scene bounds (world space). */
static void builtin_path(sb_path *p, const char *kind, const sb_scene *s) {
    memset(p, 0, sizeof *p);
    p->file = sb_strdup(kind);
    p->fov_deg = 60;
    p->content_hash = sb_fnv1a(SB_FNV_SEED, kind, strlen(kind));
    sb_v3 lo = sb_v3_add(s->bounds.lo, s->origin), hi = sb_v3_add(s->bounds.hi, s->origin);
    sb_v3 c = sb_v3_scale(sb_v3_add(lo, hi), 0.5);
    sb_v3 e = sb_v3_sub(hi, lo);
    double r = 0.5 * fmax(e.x, e.z);
    int n = strcmp(kind, "orbit") == 0 ? 9 : 6;
    sb_v3 targets[9];
    p->keys = sb_xcalloc((size_t)n, sizeof *p->keys);
    p->key_count = n;
    for (int i = 0; i < n; i++) {
        double u = (double)i / (n - 1);
        sb_v3 pos, target;
        if (n == 9) { /* orbit: a full circle at 1.2 radii, 30 degrees up */
            double a = u * 2 * SB_PI;
            pos = sb_v3_make(c.x + 1.2 * r * sin(a), hi.y + 0.6 * r, c.z + 1.2 * r * cos(a));
            target = c;
        } else { /* auto: low across the scene, then up and out to a wide view */
            double h = lo.y + e.y * 0.3 + u * u * (e.y + 1.2 * r);
            pos = sb_v3_make(c.x + (u - 0.5) * 1.4 * r, h + 0.02 * r, c.z - (0.8 - 1.6 * u * u) * r);
            target = sb_v3_make(c.x + (0.5 - u) * 0.4 * r, lo.y + e.y * 0.2, c.z + 0.3 * r);
        }
        p->keys[i].t = 10.0 * u;
        p->keys[i].pos = pos;
        p->keys[i].rot = sb_quat_look(sb_v3_sub(target, pos), sb_v3_make(0, 1, 0));
        targets[i] = target;
    }
    if (keep_outside(p, s, targets))
        sb_log("%s: the %s path could not be kept clear of the model everywhere", s->file, kind);
}

bool sb_path_load(sb_path *p, const char *spec, const sb_scene *scene, sb_err *err) {
    memset(p, 0, sizeof *p);
    if (strcmp(spec, "auto") == 0 || strcmp(spec, "orbit") == 0) {
        if (!scene) return sb_fail(err, "%s: a built-in path needs a scene", spec);
        builtin_path(p, spec, scene);
        return true;
    }
    const char *hash = strstr(spec, "#camera=");
    if (hash) {
        char file[PATH_MAX];
        snprintf(file, sizeof file, "%.*s", (int)(hash - spec), spec);
        long cam;
        if (!sb_parse_int(hash + 8, &cam) || cam < 0 || cam > INT_MAX)
            return sb_fail(err, "%s: expected FILE#camera=INDEX", spec);
        p->fov_deg = 60;
        if (!camera_path(p, file, (int)cam, scene ? &scene->opts : NULL, err)) {
            sb_path_free(p);
            return false;
        }
        p->file = sb_strdup(spec);
        p->content_hash = sb_fnv1a(SB_FNV_SEED, spec, strlen(spec));
        if (scene) p->content_hash ^= scene->content_hash;
        return true;
    }
    char resolved[PATH_MAX];
    const char *file = spec;
    if (sb_resolve_bundled(spec, ".path", resolved, sizeof resolved)) file = resolved;
    char *text = sb_read_file(file, NULL, err);
    if (!text) return false;
    bool ok = sb_path_parse(p, file, text, err);
    free(text);
    return ok;
}

void sb_path_free(sb_path *p) {
    free(p->file);
    free(p->keys);
    memset(p, 0, sizeof *p);
}

double sb_path_duration(const sb_path *p) {
    return p->key_count ? p->keys[p->key_count - 1].t - p->keys[0].t : 0;
}

sb_v3 sb_catmull_rom(sb_v3 p0, sb_v3 p1, sb_v3 p2, sb_v3 p3, double u) {
    /* centripetal parameterisation (alpha = 0.5), Barry-Goldman pyramid */
    double t0 = 0;
    double t1 = t0 + fmax(sqrt(sb_v3_len(sb_v3_sub(p1, p0))), 1e-9);
    double t2 = t1 + fmax(sqrt(sb_v3_len(sb_v3_sub(p2, p1))), 1e-9);
    double t3 = t2 + fmax(sqrt(sb_v3_len(sb_v3_sub(p3, p2))), 1e-9);
    double t = t1 + (t2 - t1) * u;
    sb_v3 a1 = sb_v3_add(sb_v3_scale(p0, (t1 - t) / (t1 - t0)), sb_v3_scale(p1, (t - t0) / (t1 - t0)));
    sb_v3 a2 = sb_v3_add(sb_v3_scale(p1, (t2 - t) / (t2 - t1)), sb_v3_scale(p2, (t - t1) / (t2 - t1)));
    sb_v3 a3 = sb_v3_add(sb_v3_scale(p2, (t3 - t) / (t3 - t2)), sb_v3_scale(p3, (t - t2) / (t3 - t2)));
    sb_v3 b1 = sb_v3_add(sb_v3_scale(a1, (t2 - t) / (t2 - t0)), sb_v3_scale(a2, (t - t0) / (t2 - t0)));
    sb_v3 b2 = sb_v3_add(sb_v3_scale(a2, (t3 - t) / (t3 - t1)), sb_v3_scale(a3, (t - t1) / (t3 - t1)));
    return sb_v3_add(sb_v3_scale(b1, (t2 - t) / (t2 - t1)), sb_v3_scale(b2, (t - t1) / (t2 - t1)));
}

void sb_path_eval(const sb_path *p, double t, sb_v3 *pos, sb_quat *rot, double *fov) {
    int n = p->key_count;
    const sb_path_key *k = p->keys;
    double t0 = k[0].t;
    t += t0;
    int i = 0;
    if (n == 1 || t <= k[0].t) i = 0;
    else if (t >= k[n - 1].t) i = n - 1;
    else
        while (i + 1 < n && k[i + 1].t <= t) i++;
    double fa = k[i].fov_deg > 0 ? k[i].fov_deg : p->fov_deg;
    if (i >= n - 1 || t <= k[i].t) {
        *pos = k[i].pos;
        *rot = k[i].rot;
        *fov = fa;
        return;
    }
    double u = (t - k[i].t) / (k[i + 1].t - k[i].t);
    sb_v3 p1 = k[i].pos, p2 = k[i + 1].pos;
    /* end segments mirror the missing neighbour so the curve stays C1 at the ends */
    sb_v3 p0 = i > 0 ? k[i - 1].pos : sb_v3_sub(sb_v3_scale(p1, 2), p2);
    sb_v3 p3 = i + 2 < n ? k[i + 2].pos : sb_v3_sub(sb_v3_scale(p2, 2), p1);
    if (sb_v3_len(sb_v3_sub(p2, p1)) < 1e-12) *pos = p1;
    else *pos = sb_catmull_rom(p0, p1, p2, p3, u);
    *rot = sb_quat_slerp(k[i].rot, k[i + 1].rot, u);
    double fb = k[i + 1].fov_deg > 0 ? k[i + 1].fov_deg : p->fov_deg;
    *fov = fa + (fb - fa) * u;
}

double sb_path_progress(int i, int n) { return n > 1 ? (double)i / (n - 1) : 0.0; }

static void camera_axes(sb_camera *c) {
    c->rot = sb_quat_norm(c->rot);
    c->right = sb_quat_rotate(c->rot, sb_v3_make(1, 0, 0));
    c->up = sb_quat_rotate(c->rot, sb_v3_make(0, 1, 0));
    c->forward = sb_quat_rotate(c->rot, sb_v3_make(0, 0, -1));
}

sb_camera sb_camera_look(sb_v3 pos, sb_v3 dir, double fov_deg, double aspect, double znear, double zfar) {
    sb_camera c;
    memset(&c, 0, sizeof c);
    c.pos = pos;
    c.rot = sb_quat_look(dir, sb_v3_make(0, 1, 0));
    camera_axes(&c);
    c.fov_deg = fov_deg;
    c.aspect = aspect;
    c.znear = znear;
    c.zfar = zfar;
    return c;
}

sb_camera sb_path_camera(const sb_path *p, int i, int n, double aspect, const sb_scene *s) {
    return sb_path_camera_at(p, sb_path_progress(i, n) * sb_path_duration(p), aspect, s);
}

sb_camera sb_path_camera_at(const sb_path *p, double t, double aspect, const sb_scene *s) {
    sb_camera c;
    memset(&c, 0, sizeof c);
    sb_path_eval(p, t, &c.pos, &c.rot, &c.fov_deg);
    camera_axes(&c);
    c.aspect = aspect;
    c.znear = p->znear;
    c.zfar = p->zfar;
    if (s && (c.znear <= 0 || c.zfar <= 0)) {
        sb_v3 lo = sb_v3_add(s->bounds.lo, s->origin), hi = sb_v3_add(s->bounds.hi, s->origin);
        double diag = sb_v3_len(sb_v3_sub(hi, lo));
        double far = 0;
        for (int k = 0; k < 8; k++) {
            sb_v3 q = sb_v3_make(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
            far = fmax(far, sb_v3_dot(sb_v3_sub(q, c.pos), c.forward));
        }
        if (c.znear <= 0) c.znear = fmax(diag * 2e-4, 1e-6);
        if (c.zfar <= 0) c.zfar = fmax(far * 1.01, c.znear * 10);
    }
    if (c.znear <= 0) c.znear = 0.1;
    if (c.zfar <= c.znear) c.zfar = c.znear * 1000;
    return c;
}
