/* session.h - what runs share and what they render with.
 *
 * A session holds what runs share (context, scene, path, GPU buffers, the
 * reference); an instance is one technique with its parameters, rendering a
 * path frame or an explicit camera into the session's targets. The run loop
 * (run.h), the evaluation (eval.h), bias=auto (autobias.h) and the stress
 * battery all render through these, so none of them calls back into another. */
#pragma once
#include "calib.h"
#include "clocks.h"
#include "context.h"
#include "csv.h"
#include "render.h"
#include "run_opts.h"
#include "columns.h"
#include "spec.h"
#include "timing.h"

/* The light's size of the runs that follow (a batch line's): the options and
 * the reference (when built) take it. */
struct sb_session;
void sb_session_set_light_size(struct sb_session *s, double sun_size, double lamp_radius, int ref_samples);


typedef struct sb_session {
    sb_run_opts opts;
    sb_context ctx;
    sb_scene scene;
    sb_path path;
    sb_gpu gpu;
    sb_timing_mode timing;      /* resolved */
    char scene_name[256], path_name[256];
    char skip[SB_ERR_LEN + 64]; /* the last skip reason */
    sb_light_set lights;        /* --lights read against the scene (count 0: not given) */
    sb_light_set every_lamp;    /* every lamp of the scene, for a technique that shadows them all by default */
    uint32_t *scratch;          /* draw_count entries: a frame's culling results */
    uint32_t *cmds;             /* --submit indirect: a pass's pending commands (5 words a draw) */
    struct sb_reference *ref;   /* the scene's Embree reference, built on first use */
    double gpu_upload_ms;       /* the scene's buffers and targets made on the GPU (sb_gpu_init, finished) */
    struct sb_ref_cache *ref_cache; /* its answers per rasterized frame, shared by the runs of the scene */
    char ref_store[4096];       /* folder keeping those answers across processes ("": none; sb_session_keep_reference) */
    void **tech_data;           /* per technique (registry index): what its load step made for the scene */
    char path_note[1024];       /* the path check's flagged frames ("" all clear, or not checked: --error-every 0) */
    bool *tech_loaded;
    bool timed;                 /* true while a run's timed frames render (tests assert nothing is read back then) */
    sb_calib calib;             /* the calibration probe */
    sb_clocks *clocks;          /* the GPU's clock state (kept with the context) */
    char clocks_mode[64];       /* what the summary's clocks column says */
    bool files_refused;         /* sb_session_open failed on the scene or path file (bad input), not on the GL */
    int attempt;                /* the attempt the runs begun now are (0, 1: the first; --rerun-unstable) */
    /* a technique refused a frame's input files (sb_technique.check_frame: score's mask that does not line up): the
       first line; the command exits 2 (bad input) */
    char input_refused[SB_ERR_LEN];
} sb_session;

/* Above these shares a run's warnings say its error figures cannot be trusted
 * (see check_geometry in run.c and the README's "Error" section). */
/* The reference answers kept per scene (bytes: one per evaluated pixel; 1280x720 frames about 0.9 MB each). */
#define SB_REF_CACHE_BYTES ((size_t)512 << 20)
#define SB_GEOM_MISMATCH_WARN 1e-4
#define SB_ERR_FLOOR_WARN 1e-3

/* The most warm-up frames --warmup auto renders. */
#define SB_WARMUP_AUTO_CAP 1000

/* Opens the clock reader for the session's context and applies --clocks
 * (after the context exists; kept with it across scenes). */
bool sb_session_clocks(sb_session *s, const sb_run_opts *o, sb_err *err);
/* Loads scene and path, opens the context (if not already), uploads buffers.
 * On failure files_refused says whether a file was refused (exit 2) or the GL failed. */
bool sb_session_open(sb_session *s, const sb_run_opts *o, const char *scene, const char *path, sb_err *err);
/* The same with a scene and path already loaded: the session takes them over
 * (freed with it, also when this fails). */
bool sb_session_attach(sb_session *s, const sb_run_opts *o, sb_scene *scene, sb_path *path, sb_err *err);
/* Keeps the reference's answers beside a results set: in the hidden folder
 * `.reference` next to results_dir (OUT/.reference for run's OUT/<UTC>, the
 * batch's OUT/NAME/.reference: listings of results sets do not see it), read when a scene's reference is first used
 * and written when the scene closes, so reruns into the same OUT and
 * --resume cast no ray already cast. */
void sb_session_keep_reference(sb_session *s, const char *results_dir);
/* The shadow storage a run of rs holds on this session's scene: its parameters' (sb_spec_shadow_bytes), a map set a
 * lamp where it keeps one each (--lights). */
double sb_session_shadow_bytes(const sb_session *s, const sb_run_spec *rs);
/* The light column of the session's runs: the sun's and lamps' sizes and the reference's rays where given, and
 * --lights' set (each a series of its own); "" for a point sun and the scene's one light. */
void sb_session_light_label(const sb_session *s, char *out, size_t len);
/* A batch's runs of another --lights (NULL: none): read against the open scene; false with the reason. */
bool sb_session_set_lights(sb_session *s, const char *spec, sb_err *err);
/* The set's one name (sb_light_set_text), interned: "+1", "01" and "1" are one set, one run id. */
const char *sb_lights_name(const sb_scene *sc, const sb_light_set *set);
/* A spec's light=K against the scene and --lights (NULL: not given): a lamp the scene lacks, or light= given beside
 * --lights, is refused in one line (exit 2), never skipped or overruled in silence. */
bool sb_spec_lights_check(const sb_scene *sc, const sb_run_spec *rs, const char *lights, sb_err *err);
/* Frees the scene, path and what was made for them but keeps the context (next scene of a batch). */
void sb_session_close_scene(sb_session *s);
void sb_session_close(sb_session *s);
/* Writes DIR/meta ("key: value" lines): the command, shadowbench's version and
 * commit, the time (UTC), the host, the backend and GL strings, the CPU, the
 * kernel and the clocks, then `extra` (lines the caller adds). `shadowbench
 * history add` reads it. */
/* What the binary was built with (SB_BUILD_OPTIONS), written in every meta as `build:`. */
void sb_session_set_build(const char *options);
bool sb_session_write_meta(const sb_session *s, const char *dir, const char *command_line, const char *version,
                           const char *commit, const char *extra, sb_err *err);
/* The scene's Embree reference (built on the first call; refit to the pose the scene holds); NULL with err on
 * failure. */
const struct sb_reference *sb_session_reference(sb_session *s, sb_err *err);
/* Path seconds of frame i of n: the clock the scene's clips play on. */
double sb_session_frame_time(const sb_session *s, int i, int n);
/* Poses the scene at path time t (its clips at t x --anim-speed) and sends the moving vertices to the GPU; the
 * milliseconds it took (NaN for a scene where nothing moves). */
double sb_session_pose(sb_session *s, double t);

/* A live technique instance: its parameters as values and as the bound struct. */
typedef struct sb_instance {
    const sb_technique *tech;
    sb_run_spec *spec;          /* the spec it was made from (its own copy) */
    void *desc;                 /* the parameter struct: spec->desc, bound with the spec */
    void *state;
    sb_run_ctx rc;
    /* a moving scene: the draws' boxes as its previous frame saw them, and what moved since (sb_frame.moved) */
    sb_aabb *seen, *moved_from;
    uint32_t *moved;
    uint64_t seen_serial;
} sb_instance;

/* Creates the technique for `frames` frames (warm-up and repeats included);
 * false with the reason when it is not supported here or fails. */
bool sb_instance_create(sb_instance *in, sb_session *s, const sb_run_spec *spec, int frames, sb_err *err);
void sb_instance_destroy(sb_instance *in);
/* Earlier frames a frame of this instance depends on (sb_technique.history). */
int sb_instance_history(const sb_instance *in);
/* Renders frame i of n of the path as the run's seq-th frame, timed by timer. */
void sb_render_frame(sb_session *s, sb_instance *in, sb_frame *f, int i, int n, int seq, struct sb_timer *timer);
/* Renders an explicit camera (tests, stress cases); eval binds the evaluation targets. */
/* The same with the image shifted by (jx, jy) pixels (TAA's sub-pixel jitter, taa.h): the projection moves, the
 * shadow maps' fit follows the jittered frustum as an engine's does. */
void sb_render_camera_jittered(sb_session *s, sb_instance *in, sb_frame *f, const sb_camera *cam, int seq,
                               struct sb_timer *timer, bool eval, double jx, double jy);
void sb_render_camera(sb_session *s, sb_instance *in, sb_frame *f, const sb_camera *cam, int seq,
                      struct sb_timer *timer, bool eval);
/* Why a technique (with parameters p; NULL: its defaults) cannot run on this
 * scene and context, or NULL. The text lives in the session. */
const char *sb_skip_reason(sb_session *s, const sb_technique *t, const sb_run_spec *spec);
