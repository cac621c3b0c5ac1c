/* support.h - shared helpers for shadowbench tests (real GL on llvmpipe). */
#pragma once
#include <stdbool.h>

#include "error.h"
#include "run.h"

/* Classification of a rendered plane-box frame against the analytic shadow. */
typedef struct pb_result {
    long pixels;            /* image pixels */
    long plane;             /* pixels showing the top of the slab */
    long shadow_tech;       /* plane pixels the technique shadows */
    long shadow_exact;      /* plane pixels the box shadows analytically */
    long mismatch;          /* plane pixels where they differ */
} pb_result;

/* Opens a scene and path (bundled names or files) at w x h, other options default. */
bool test_open(sb_session *s, const char *scene, const char *path, int w, int h, sb_err *err);
/* Opens plane-box with the fixed camera in tests/data/planebox-fixed.path. */
bool pb_open(sb_session *s, sb_backend backend, int w, int h, sb_err *err);
/* The same with another camera (a path in tests/data) and sun (NAN: the file's). */
bool pb_open_view(sb_session *s, sb_backend backend, int w, int h, const char *path, double sun_az, double sun_el,
                  sb_err *err);
/* Renders frame 0 with the spec and classifies it. */
bool pb_render(sb_session *s, const char *spec, pb_result *out, unsigned char *vis_out, sb_err *err);
/* Renders path frame i of n with the spec in evaluation mode and measures its
 * error against the reference; pos (w*h*4 floats) and ref (w*h) optional. */
bool eval_frame(sb_session *s, const char *spec, int i, int n, sb_error_metrics *m, float *pos, unsigned char *ref,
                sb_err *err);
/* Does a ray from p toward the sun hit the box [-1,1]x[0,2]x[-1,1]? */
bool pb_box_shadows(sb_v3 p, sb_v3 sun);
/* Does the segment p + t d, t in (0, tmax), cross that box? */
bool pb_box_blocks(sb_v3 p, sb_v3 d, double tmax);
/* Path of a file in the source tree's tests/data. */
const char *test_data(const char *name);
/* Path of the built shadowbench binary. */
const char *test_binary(void);
/* Runs a shell command, captures stderr+stdout into out; returns the exit code. */
int run_capture(const char *cmd, char *out, size_t len);
/* run_capture of a printf-formatted command, logging the command, its exit code and
 * the start of its output. */
int run_logged(char *out, size_t len, const char *fmt, ...);
