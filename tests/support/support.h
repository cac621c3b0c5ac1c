/* support.h - shared helpers for shadowbench tests (real GL on llvmpipe). */
#pragma once
#include <stdbool.h>

#include "error.h"
#include "options.h"
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
/* Renders path frame i of n as the evaluation pass does (timed frames write
 * colour alone): the visibility target then holds this frame's. */
void render_frame_eval(sb_session *s, sb_instance *in, sb_frame *f, int i, int n, int seq, struct sb_timer *t);
bool pb_render(sb_session *s, const char *spec, pb_result *out, unsigned char *vis_out, sb_err *err);
/* Renders path frame i of n with the spec in evaluation mode and measures its
 * error against the reference; pos (w*h*4 floats) and ref (w*h) optional. */
bool eval_frame(sb_session *s, const char *spec, int i, int n, sb_error_metrics *m, float *pos, unsigned char *ref,
                sb_err *err);
/* The same for an instance the caller made (and may have changed). */
bool eval_instance(sb_session *s, sb_instance *in, int i, int n, sb_error_metrics *m, float *pos_out,
                   unsigned char *ref_out, sb_err *err);
/* Does a ray from p toward the sun hit the box [-1,1]x[0,2]x[-1,1]? */
bool pb_box_shadows(sb_v3 p, sb_v3 sun);
/* Does the segment p + t d, t in (0, tmax), cross that box? */
bool pb_box_blocks(sb_v3 p, sb_v3 d, double tmax);
/* Whether the segment p + t d, t in (0, tmax], meets the axis-aligned box [lo, hi]. */
bool box_blocks(sb_v3 p, sb_v3 d, double tmax, const double lo[3], const double hi[3]);
/* Path of a file in the source tree's tests/data. */
const char *test_data(const char *name);
/* Path of the built shadowbench binary. */
const char *test_binary(void);
/* Runs a shell command, captures stderr+stdout into out; returns the exit code. */
int run_capture(const char *cmd, char *out, size_t len);
/* run_capture of a printf-formatted command, logging the command, its exit code and
 * the start of its output. */
int run_logged(char *out, size_t len, const char *fmt, ...);

/* A one-triangle glTF document (.gltf, buffer in a data: URI unless `uri` is
 * given) whose fields can be replaced by exact JSON text, for bad-input tests.
 * The buffer holds three float VEC3 positions (36 bytes) and three unsigned
 * short indices (6 bytes, padded to 44). NULL keeps the default, shown after
 * each field. */
typedef struct gltf_tri {
    const char *uri;            /* data: URI of the 44 bytes */
    const char *buffer_len;     /* "44" */
    const char *view0;          /* positions' bufferView body: "\"buffer\":0,\"byteOffset\":0,\"byteLength\":36" */
    const char *view1;          /* indices' bufferView body: "\"buffer\":0,\"byteOffset\":36,\"byteLength\":6" */
    const char *acc0;           /* positions' accessor body: bufferView 0, byteOffset 0, float VEC3, count 3 */
    const char *acc1;           /* indices' accessor body: bufferView 1, byteOffset 0, ushort SCALAR, count 3 */
    const char *prim;           /* primitive body: "\"attributes\":{\"POSITION\":0},\"indices\":1" */
    const char *node0;          /* node 0 body: "\"mesh\":0" */
    const char *nodes_more;     /* more nodes after node 0, with a leading comma: "" */
    const char *scene;          /* "0" */
    const char *scene_nodes;    /* "[0]" */
    const char *root_more;      /* more root members, with a leading comma: "" */
} gltf_tri;

/* n bytes as base64 into out (4 * ((n + 2) / 3) + 1 bytes), for a data: URI. */
void test_base64(const unsigned char *in, size_t n, char *out);
/* Writes the document to path; false if it cannot. */
bool gltf_tri_write(const char *path, const gltf_tri *t);
/* Loads path as a scene expecting a refusal whose one-line message holds
 * needle; prints the message. */
void expect_scene_refused(const char *path, const char *needle);
/* Loads DIR/summary.csv (a results folder's runs) into t, asserting it loads. */
struct sb_table;
void summary_table(const char *dir, struct sb_table *t);
/* Renders `run SCENE PATH SPECS --frames N --size SIZE --error-every 1 --warmup 0 --quiet --out OUT` (logged),
 * every frame evaluated, asserting exit 0; the results folder into dir, its summary into sum. */
void run_evaluated(const char *scene, const char *path, const char *specs, int frames, const char *size,
                   const char *out, struct sb_table *sum, char *dir, size_t len);
/* Loads the per-frame CSV of the summary's row r (DIR/RUN_ID.csv) into t, asserting it loads. */
void frames_table(const char *dir, const struct sb_table *sum, int r, struct sb_table *t);
/* A cell of a loaded table as an integer (atol: 0 when empty). */
long table_int(const struct sb_table *t, int r, const char *col);

/* Runs the printf-formatted command (logged) expecting exit 2 (bad input) and
 * one line of output holding needle; returns that output. */
/* The last line of a command's output (a results folder, as run and batch print it last), its newline cut:
 * points into out, which it changes. */
const char *last_line_of(char *out);
const char *expect_cli_fail(const char *needle, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The same for another exit status (1: the GL or the machine failed, not the input). */
const char *expect_cli_exit(int status, const char *needle, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* Copies the bundled scene file `name` (from SB_DATA_DIR) to dst. */
void copy_bundled(const char *name, const char *dst);
/* A fresh folder /tmp/<prefix>XXXXXX into dir (len >= 64); 0 on success (a cmocka group setup's result). */
/* A generated part of a document in the source tree (docs/...): the text after the line holding `begin` (up to
 * the line holding `end`; NULL: the end of the file) must equal what `write` prints; a failure says where they
 * part and to run scripts/gen-docs. */
void assert_generated(const char *doc, const char *begin, const char *end, void (*write)(FILE *f));
int tmp_folder(char *dir, size_t len, const char *prefix);
/* Removes the folder and everything in it; 0 on success. */
int tmp_remove(const char *dir);
/* A test file's scratch folder g_tmp: made by its group's setup, removed with
 * everything in it by its teardown (cmocka_run_group_tests(..., setup, teardown)). */
#define SB_TEST_SCRATCH(prefix)                                                          \
    static char g_tmp[64];                                                               \
    static int setup(void **st) {                                                        \
        (void)st;                                                                        \
        return tmp_folder(g_tmp, sizeof g_tmp, prefix);                                  \
    }                                                                                    \
    static int teardown(void **st) {                                                     \
        (void)st;                                                                        \
        return tmp_remove(g_tmp);                                                        \
    }
