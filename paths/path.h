/* path.h - camera fly-throughs: keyframes, interpolation, sampling.
 *
 * Text format (one keyframe or directive a line, '#' starts a comment):
 *   fov  DEG                       default vertical field of view (degrees)
 *   near D / far D                 fixed clip planes (otherwise derived from the scene)
 *   key  T  PX PY PZ  QX QY QZ QW  [FOV]   position and orientation (unit quaternion,
 *                                          camera looks along its -Z, glTF convention)
 *   look T  PX PY PZ  TX TY TZ     [FOV]   position and a point to look at (+Y up)
 * Times strictly increase. Positions are interpolated with centripetal
 * Catmull-Rom, orientations with slerp. A path is sampled at a fixed frame
 * count: frame i of N is at t = i/(N-1) * duration, never wall-clock time.
 *
 * Built-in paths stand where a file goes: "auto" (a fly-over derived from the
 * scene bounds, from low and close to high and far) and "orbit". A glTF camera
 * is "scene.glb#camera=K" (its node's animation, sampled at its key times). */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "sbmath.h"
#include "util.h"

/* Largest magnitude of a time or coordinate in a path file. */
#define SB_PATH_MAX_COORD 1e12

typedef struct sb_path_key {
    double t;
    sb_v3 pos;              /* world space */
    sb_quat rot;
    double fov_deg;         /* 0: the path's default */
} sb_path_key;

typedef struct sb_path {
    char *file;             /* as given ("auto", "x.path", "a.glb#camera=0") */
    sb_path_key *keys;
    int key_count;
    double fov_deg;         /* default 60 */
    double znear, zfar;     /* 0: derived from the scene per frame */
    uint64_t content_hash;
} sb_path;

typedef struct sb_camera {
    sb_v3 pos;              /* world space */
    sb_quat rot;
    sb_v3 right, up, forward;
    double fov_deg, znear, zfar, aspect;
} sb_camera;

struct sb_scene;

/* Parses path text; `name` is used in messages (file:line: ...). */
bool sb_path_parse(sb_path *p, const char *name, const char *text, sb_err *err);
/* Loads a path file, a bundled path name, a glTF camera, or a built-in
 * (auto/orbit, which need the scene). */
bool sb_path_load(sb_path *p, const char *spec, const struct sb_scene *scene, sb_err *err);
void sb_path_free(sb_path *p);
double sb_path_duration(const sb_path *p);
/* Position, orientation and fov at time t (clamped to the path). */
void sb_path_eval(const sb_path *p, double t, sb_v3 *pos, sb_quat *rot, double *fov_deg);
/* Frame i of n: the camera, with near/far from the path or derived from the scene. */
sb_camera sb_path_camera(const sb_path *p, int i, int n, double aspect, const struct sb_scene *scene);
/* The same at path time t (clamped to the path). */
sb_camera sb_path_camera_at(const sb_path *p, double t, double aspect, const struct sb_scene *scene);
/* A camera at pos looking along dir (y up). */
sb_camera sb_camera_look(sb_v3 pos, sb_v3 dir, double fov_deg, double aspect, double znear, double zfar);
/* progress of frame i of n in [0,1] */
double sb_path_progress(int i, int n);
/* Centripetal Catmull-Rom between p1 and p2 (u in [0,1]), p0/p3 the neighbours. */
sb_v3 sb_catmull_rom(sb_v3 p0, sb_v3 p1, sb_v3 p2, sb_v3 p3, double u);
