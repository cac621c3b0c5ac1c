/* cameras.c - a run's cameras and lights for another renderer (see cameras.h). */
#include "cameras.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "blob.h"
#include "json.h"

static const char conventions[] =
    "right-handed, +Y up, world units of the scene; a camera looks along its -Z (glTF's); rotation is that "
    "camera's orientation as a unit quaternion (x, y, z, w); matrices are column-major (element [col * 4 + row], "
    "as glTF and OpenGL store them): view takes world to view space, projection view to OpenGL clip space (z in "
    "[-w, w]; depth 0 at near, 1 at far after the viewport transform); yfov is vertical, in radians; viewport is "
    "x, y, width, height in pixels, y up from the bottom row";

/* Frame i's camera and, for its twin, the camera --flicker-dt of path time later (as eval.c draws them). */
static sb_camera camera_of(const sb_cameras_req *r, int i, bool twin, double *t) {
    const int n = r->opts->frames;
    const double aspect = (double)r->opts->width / r->opts->height;
    *t = sb_path_progress(i, n) * sb_path_duration(r->path);
    if (!twin) return sb_path_camera(r->path, i, n, aspect, r->scene);
    *t += r->opts->flicker_dt;
    return sb_path_camera_at(r->path, *t, aspect, r->scene);
}

static bool has_twins(const sb_cameras_req *r) { return r->twins && r->opts->flicker_dt > 0; }

/* The sun a run of these options shades: the scene's, or --sun; false: none. */
static bool sun_of(const sb_cameras_req *r, sb_v3 *dir) {
    const sb_run_opts *o = r->opts;
    if (!r->scene->has_sun && !o->sun_override) return false;
    *dir = o->sun_override ? sb_sun_dir(o->sun_az, o->sun_el) : r->scene->sun;
    return true;
}

static int lamp_count(const sb_scene *s) {
    int count = 0;
    sb_scene_point_light(s, 0, &count);
    return count;
}

/* ---- JSON ---- */

static void jw_vec(sb_jw *j, const char *key, sb_v3 v) {
    sb_jw_key(j, key);
    sb_jw_arr(j);
    sb_jw_num_exact(j, v.x), sb_jw_num_exact(j, v.y), sb_jw_num_exact(j, v.z);
    sb_jw_end_arr(j);
}

static void jw_mat(sb_jw *j, const char *key, sb_m4 m) {
    sb_jw_key(j, key);
    sb_jw_arr(j);
    for (int k = 0; k < 16; k++) sb_jw_num_exact(j, m.m[k]);
    sb_jw_end_arr(j);
}

static void jw_camera(sb_jw *j, const sb_camera *cam, double t, int w, int h) {
    jw_vec(j, "position", cam->pos);
    jw_vec(j, "target", sb_v3_add(cam->pos, cam->forward));
    jw_vec(j, "up", cam->up);
    sb_jw_key(j, "rotation");
    sb_jw_arr(j);
    sb_jw_num_exact(j, cam->rot.x), sb_jw_num_exact(j, cam->rot.y), sb_jw_num_exact(j, cam->rot.z);
    sb_jw_num_exact(j, cam->rot.w);
    sb_jw_end_arr(j);
    sb_jw_key(j, "t"), sb_jw_num_exact(j, t);
    sb_jw_key(j, "yfov"), sb_jw_num_exact(j, cam->fov_deg * SB_PI / 180);
    sb_jw_key(j, "fov_deg"), sb_jw_num_exact(j, cam->fov_deg);
    sb_jw_key(j, "aspect"), sb_jw_num_exact(j, cam->aspect);
    sb_jw_key(j, "near"), sb_jw_num_exact(j, cam->znear);
    sb_jw_key(j, "far"), sb_jw_num_exact(j, cam->zfar);
    jw_mat(j, "view", sb_m4_view(cam->pos, cam->right, cam->up, cam->forward));
    jw_mat(j, "projection", sb_m4_perspective(cam->fov_deg * SB_PI / 180, cam->aspect, cam->znear, cam->zfar));
    sb_jw_key(j, "viewport");
    sb_jw_arr(j);
    sb_jw_num(j, 0), sb_jw_num(j, 0), sb_jw_num(j, w), sb_jw_num(j, h);
    sb_jw_end_arr(j);
}

static void json_document(const sb_cameras_req *r, sb_jw *j) {
    const sb_run_opts *o = r->opts;
    sb_jw_obj(j);
    sb_jw_kstr(j, "scene", r->scene_name);
    sb_jw_kstr(j, "path", r->path_name);
    sb_jw_kint(j, "frames", o->frames);
    sb_jw_kint(j, "width", o->width);
    sb_jw_kint(j, "height", o->height);
    sb_jw_kstr(j, "conventions", conventions);
    sb_v3 sun;
    sb_jw_key(j, "sun");
    if (sun_of(r, &sun)) {
        sb_jw_obj(j);
        jw_vec(j, "direction", sun);
        sb_jw_knum(j, "size_deg", o->sun_size);
        sb_jw_end_obj(j);
    } else {
        sb_jw_null(j);
    }
    sb_jw_key(j, "lamps");
    sb_jw_arr(j);
    for (int k = 0, n = lamp_count(r->scene); k < n; k++) {
        const sb_light *l = sb_scene_point_light(r->scene, k, NULL);
        sb_jw_obj(j);
        sb_jw_kint(j, "index", k);
        sb_jw_kstr(j, "type", l->type == SB_LIGHT_SPOT ? "spot" : "point");
        jw_vec(j, "position", sb_v3_add(l->position, r->scene->origin));
        sb_jw_key(j, "range"), sb_jw_num_exact(j, l->range > 0 ? l->range : 0);
        if (l->type == SB_LIGHT_SPOT) {
            jw_vec(j, "direction", l->direction);
            sb_jw_key(j, "cone"), sb_jw_num_exact(j, l->cone);
        }
        sb_jw_end_obj(j);
    }
    sb_jw_end_arr(j);
    sb_jw_key(j, "cameras");
    sb_jw_arr(j);
    for (int i = 0; i < o->frames; i++) {
        double t;
        sb_camera cam = camera_of(r, i, false, &t);
        sb_jw_obj(j);
        sb_jw_kint(j, "frame", i);
        sb_jw_key(j, "progress"), sb_jw_num_exact(j, sb_path_progress(i, o->frames));
        jw_camera(j, &cam, t, o->width, o->height);
        if (has_twins(r)) {
            sb_camera tw = camera_of(r, i, true, &t);
            sb_jw_key(j, "twin");
            sb_jw_obj(j);
            jw_camera(j, &tw, t, o->width, o->height);
            sb_jw_end_obj(j);
        }
        sb_jw_end_obj(j);
    }
    sb_jw_end_arr(j);
    sb_jw_end_obj(j);
}

/* ---- glTF ---- */

/* The float data of the document's one buffer, and its accessors (each over a bufferView of its own). */
typedef struct gacc {
    size_t at, bytes;
    int count, comps;
    float lo, hi;            /* a SCALAR's (an animation's input: glTF wants them) */
} gacc;

typedef struct gbuf {
    sb_wbuf bytes;
    gacc acc[8];
    int count;
} gbuf;

/* n items of `comps` floats; returns the accessor's index. */
static int gbuf_add(gbuf *g, const float *v, int n, int comps) {
    gacc *a = &g->acc[g->count];
    *a = (gacc){g->bytes.n, sizeof(float) * (size_t)n * (size_t)comps, n, comps, INFINITY, -INFINITY};
    sb_wbuf_put(&g->bytes, v, a->bytes);
    for (int i = 0; comps == 1 && i < n; i++) a->lo = fminf(a->lo, v[i]), a->hi = fmaxf(a->hi, v[i]);
    return g->count++;
}

static void gbuf_write(const gbuf *g, sb_jw *j) {
    static const char *const types[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    sb_jw_key(j, "bufferViews");
    sb_jw_arr(j);
    for (int k = 0; k < g->count; k++) {
        sb_jw_obj(j);
        sb_jw_kint(j, "buffer", 0);
        sb_jw_kint(j, "byteOffset", (long long)g->acc[k].at);
        sb_jw_kint(j, "byteLength", (long long)g->acc[k].bytes);
        sb_jw_end_obj(j);
    }
    sb_jw_end_arr(j);
    sb_jw_key(j, "accessors");
    sb_jw_arr(j);
    for (int k = 0; k < g->count; k++) {
        const gacc *a = &g->acc[k];
        sb_jw_obj(j);
        sb_jw_kint(j, "bufferView", k);
        sb_jw_kint(j, "componentType", 5126);   /* FLOAT */
        sb_jw_kint(j, "count", a->count);
        sb_jw_kstr(j, "type", types[a->comps]);
        if (a->comps == 1) {
            sb_jw_key(j, "min"), sb_jw_arr(j), sb_jw_num_exact(j, a->lo), sb_jw_end_arr(j);
            sb_jw_key(j, "max"), sb_jw_arr(j), sb_jw_num_exact(j, a->hi), sb_jw_end_arr(j);
        }
        sb_jw_end_obj(j);
    }
    sb_jw_end_arr(j);
    char *b64 = sb_xmalloc(4 * ((g->bytes.n + 2) / 3) + 1);
    sb_base64(g->bytes.p, g->bytes.n, b64);
    size_t ulen = strlen(b64) + 64;
    char *uri = sb_xmalloc(ulen);
    snprintf(uri, ulen, "data:application/octet-stream;base64,%s", b64);
    sb_jw_key(j, "buffers");
    sb_jw_arr(j);
    sb_jw_obj(j);
    sb_jw_kint(j, "byteLength", (long long)g->bytes.n);
    sb_jw_kstr(j, "uri", uri);
    sb_jw_end_obj(j);
    sb_jw_end_arr(j);
    free(uri);
    free(b64);
}

static void jw_floats(sb_jw *j, const char *key, const double *v, int n) {
    sb_jw_key(j, key);
    sb_jw_arr(j);
    for (int k = 0; k < n; k++) sb_jw_num_exact(j, (float)v[k]);
    sb_jw_end_arr(j);
}

/* A node carrying a light (KHR_lights_punctual: it shines along the node's -Z). */
static void light_node(sb_jw *j, const char *name, int light, const sb_v3 *pos, const sb_v3 *dir) {
    sb_jw_obj(j);
    sb_jw_kstr(j, "name", name);
    if (pos) jw_floats(j, "translation", (double[3]){pos->x, pos->y, pos->z}, 3);
    if (dir) {
        sb_quat q = sb_quat_look(*dir, fabs(dir->y) > 0.99 ? sb_v3_make(1, 0, 0) : sb_v3_make(0, 1, 0));
        jw_floats(j, "rotation", (double[4]){q.x, q.y, q.z, q.w}, 4);
    }
    sb_jw_key(j, "extensions");
    sb_jw_obj(j);
    sb_jw_key(j, "KHR_lights_punctual");
    sb_jw_obj(j);
    sb_jw_kint(j, "light", light);
    sb_jw_end_obj(j);
    sb_jw_end_obj(j);
    sb_jw_end_obj(j);
}

/* What the glTF export shares between its parts: the camera nodes, the lights and the keys' accessors. */
typedef struct gltf_parts {
    int cams, lamps;
    bool have_sun;
    sb_v3 sun;                  /* read only with have_sun */
    int acc[2][3];              /* per camera node: the accessors of its times, translations, rotations */
    double near, far, fov;      /* every frame's near and far, the first frame's field of view */
} gltf_parts;

/* The keys: each camera's translations and rotations at the frames' times, as accessors in g. glTF's times
 * increase strictly, so a frame at the time of the last key (a path of one key, whose every frame is at 0) is that
 * key's camera and is not keyed again. */
static void gltf_keys(const sb_cameras_req *r, gltf_parts *gp, gbuf *g) {
    const int n = r->opts->frames;
    float *times = sb_xmalloc(sizeof(float) * (size_t)n), *pos = sb_xmalloc(sizeof(float) * 3 * (size_t)n),
          *rot = sb_xmalloc(sizeof(float) * 4 * (size_t)n);
    gp->near = INFINITY, gp->far = 0, gp->fov = 0;
    for (int c = 0; c < gp->cams; c++) {
        int m = 0;
        for (int i = 0; i < n; i++) {
            double t;
            sb_camera cam = camera_of(r, i, c == 1, &t);
            gp->near = fmin(gp->near, cam.znear), gp->far = fmax(gp->far, cam.zfar);
            if (c == 0 && i == 0) gp->fov = cam.fov_deg;
            if (m > 0 && !((float)t > times[m - 1])) continue;
            times[m] = (float)t;
            pos[3 * m] = (float)cam.pos.x, pos[3 * m + 1] = (float)cam.pos.y, pos[3 * m + 2] = (float)cam.pos.z;
            rot[4 * m] = (float)cam.rot.x, rot[4 * m + 1] = (float)cam.rot.y, rot[4 * m + 2] = (float)cam.rot.z;
            rot[4 * m + 3] = (float)cam.rot.w;
            m++;
        }
        gp->acc[c][0] = gbuf_add(g, times, m, 1);
        gp->acc[c][1] = gbuf_add(g, pos, m, 3);
        gp->acc[c][2] = gbuf_add(g, rot, m, 4);
    }
    free(times);
    free(pos);
    free(rot);
}

/* asset (what made it and from what), the extension used, the one scene of every node. */
static void gltf_header(const sb_cameras_req *r, const gltf_parts *gp, sb_jw *j) {
    const sb_run_opts *o = r->opts;
    sb_jw_key(j, "asset");
    sb_jw_obj(j);
    sb_jw_kstr(j, "version", "2.0");
    sb_jw_kstr(j, "generator", "shadowbench cameras");
    sb_jw_key(j, "extras");
    sb_jw_obj(j);
    sb_jw_kstr(j, "scene", r->scene_name);
    sb_jw_kstr(j, "path", r->path_name);
    sb_jw_kint(j, "frames", o->frames);
    sb_jw_kint(j, "width", o->width);
    sb_jw_kint(j, "height", o->height);
    sb_jw_kstr(j, "conventions", "glTF's; the cameras' znear and zfar hold every frame's (the tool derives them per "
                                 "frame: the JSON export has each), yfov is the first frame's");
    sb_jw_end_obj(j);
    sb_jw_end_obj(j);
    sb_jw_key(j, "extensionsUsed");
    sb_jw_arr(j);
    sb_jw_str(j, "KHR_lights_punctual");
    sb_jw_end_arr(j);
    sb_jw_kint(j, "scene", 0);
    sb_jw_key(j, "scenes");
    sb_jw_arr(j);
    sb_jw_obj(j);
    sb_jw_key(j, "nodes");
    sb_jw_arr(j);
    for (int k = 0; k < gp->cams + gp->have_sun + gp->lamps; k++) sb_jw_num(j, k);
    sb_jw_end_arr(j);
    sb_jw_end_obj(j);
    sb_jw_end_arr(j);
}

/* nodes: the camera (and its twin) at the first frame, the sun, the lamps; then the one camera. */
static void gltf_nodes(const sb_cameras_req *r, const gltf_parts *gp, sb_jw *j) {
    sb_jw_key(j, "nodes");
    sb_jw_arr(j);
    for (int c = 0; c < gp->cams; c++) {
        double t;
        sb_camera cam = camera_of(r, 0, c == 1, &t);
        sb_jw_obj(j);
        sb_jw_kstr(j, "name", c ? "camera twin" : "camera");
        sb_jw_kint(j, "camera", 0);
        jw_floats(j, "translation", (double[3]){cam.pos.x, cam.pos.y, cam.pos.z}, 3);
        jw_floats(j, "rotation", (double[4]){cam.rot.x, cam.rot.y, cam.rot.z, cam.rot.w}, 4);
        sb_jw_end_obj(j);
    }
    if (gp->have_sun) {
        sb_v3 travel = sb_v3_scale(gp->sun, -1);
        light_node(j, "sun", 0, NULL, &travel);
    }
    for (int k = 0; k < gp->lamps; k++) {
        const sb_light *l = sb_scene_point_light(r->scene, k, NULL);
        char name[32];
        snprintf(name, sizeof name, "lamp %d", k);
        sb_v3 at = sb_v3_add(l->position, r->scene->origin);
        light_node(j, name, gp->have_sun + k, &at, l->type == SB_LIGHT_SPOT ? &l->direction : NULL);
    }
    sb_jw_end_arr(j);
    sb_jw_key(j, "cameras");
    sb_jw_arr(j);
    sb_jw_obj(j);
    sb_jw_kstr(j, "type", "perspective");
    sb_jw_key(j, "perspective");
    sb_jw_obj(j);
    sb_jw_key(j, "yfov"), sb_jw_num_exact(j, gp->fov * SB_PI / 180);
    sb_jw_key(j, "aspectRatio"), sb_jw_num_exact(j, (double)r->opts->width / r->opts->height);
    sb_jw_key(j, "znear"), sb_jw_num_exact(j, gp->near);
    sb_jw_key(j, "zfar"), sb_jw_num_exact(j, gp->far);
    sb_jw_end_obj(j);
    sb_jw_end_obj(j);
    sb_jw_end_arr(j);
}

/* the lights (KHR_lights_punctual): the sun, then each lamp with every value written explicitly. */
static void gltf_lights(const sb_cameras_req *r, const gltf_parts *gp, sb_jw *j) {
    sb_jw_key(j, "extensions");
    sb_jw_obj(j);
    sb_jw_key(j, "KHR_lights_punctual");
    sb_jw_obj(j);
    sb_jw_key(j, "lights");
    sb_jw_arr(j);
    if (gp->have_sun) {
        sb_jw_obj(j);
        sb_jw_kstr(j, "name", "sun");
        sb_jw_kstr(j, "type", "directional");
        sb_jw_end_obj(j);
    }
    for (int k = 0; k < gp->lamps; k++) {
        const sb_light *l = sb_scene_point_light(r->scene, k, NULL);
        sb_jw_obj(j);
        sb_jw_kstr(j, "type", l->type == SB_LIGHT_SPOT ? "spot" : "point");
        jw_floats(j, "color", (double[3]){l->color[0], l->color[1], l->color[2]}, 3);
        /* always written: an engine reads a missing intensity as 1, a lit lamp (-0 as 0) */
        sb_jw_key(j, "intensity"), sb_jw_num_exact(j, l->intensity == 0 ? 0.0 : l->intensity);
        if (l->range > 0) sb_jw_key(j, "range"), sb_jw_num_exact(j, l->range);
        if (l->type == SB_LIGHT_SPOT) {
            sb_jw_key(j, "spot");
            sb_jw_obj(j);
            sb_jw_key(j, "innerConeAngle"), sb_jw_num(j, 0);
            sb_jw_key(j, "outerConeAngle"), sb_jw_num_exact(j, l->cone);
            sb_jw_end_obj(j);
        }
        sb_jw_end_obj(j);
    }
    sb_jw_end_arr(j);
    sb_jw_end_obj(j);
    sb_jw_end_obj(j);
}

/* the path: each camera node's translation and rotation keyed at the frames' times (gltf_keys' accessors). */
static void gltf_path(const gltf_parts *gp, sb_jw *j) {
    sb_jw_key(j, "animations");
    sb_jw_arr(j);
    sb_jw_obj(j);
    sb_jw_kstr(j, "name", "path");
    sb_jw_key(j, "channels");
    sb_jw_arr(j);
    for (int c = 0; c < gp->cams; c++)
        for (int k = 0; k < 2; k++) {
            sb_jw_obj(j);
            sb_jw_kint(j, "sampler", 2 * c + k);
            sb_jw_key(j, "target");
            sb_jw_obj(j);
            sb_jw_kint(j, "node", c);
            sb_jw_kstr(j, "path", k ? "rotation" : "translation");
            sb_jw_end_obj(j);
            sb_jw_end_obj(j);
        }
    sb_jw_end_arr(j);
    sb_jw_key(j, "samplers");
    sb_jw_arr(j);
    for (int c = 0; c < gp->cams; c++)
        for (int k = 0; k < 2; k++) {
            sb_jw_obj(j);
            sb_jw_kint(j, "input", gp->acc[c][0]);
            sb_jw_kint(j, "output", gp->acc[c][1 + k]);
            sb_jw_kstr(j, "interpolation", "LINEAR");
            sb_jw_end_obj(j);
        }
    sb_jw_end_arr(j);
    sb_jw_end_obj(j);
    sb_jw_end_arr(j);
}

static void gltf_document(const sb_cameras_req *r, sb_jw *j) {
    gltf_parts gp = {.cams = has_twins(r) ? 2 : 1, .lamps = lamp_count(r->scene)};
    gp.have_sun = sun_of(r, &gp.sun);
    gbuf g = {0};
    gltf_keys(r, &gp, &g);
    sb_jw_obj(j);
    gltf_header(r, &gp, j);
    gltf_nodes(r, &gp, j);
    gltf_lights(r, &gp, j);
    gltf_path(&gp, j);
    gbuf_write(&g, j);
    sb_jw_end_obj(j);
    sb_wbuf_free(&g.bytes);
}

char *sb_cameras_document(const sb_cameras_req *r) {
    sb_jw j = {0};
    if (r->format == SB_CAMERAS_GLTF) gltf_document(r, &j);
    else json_document(r, &j);
    return j.buf;
}
