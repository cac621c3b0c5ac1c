/* options.c - the option table and the one parser, help writer and run
 * identity that read it (options.h). */
#include "cameras.h"
#include "options.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "compare.h"
#include "image.h"

/* --images needs the image writer, which a build may leave out. */
static bool images_built(const char *v, const sb_cli_opts *o, sb_err *err) {
    if (o->run.images > 0 && !sb_images_available())
        return sb_fail(err, "--images %s: %s", v, sb_images_unavailable_reason());
    return true;
}

/* --backend osmesa needs OSMesa's header at build time. */
static bool backend_built(const char *v, const sb_cli_opts *o, sb_err *err) {
    if (o->run.backend == SB_BACKEND_OSMESA && !SB_HAVE_OSMESA)
        return sb_fail(err, "--backend %s: this shadowbench was built without OSMesa (meson -Dosmesa=disabled); use "
                            "--backend egl", v);
    return true;
}

/* Who takes what: a row names the kinds of command that take it (SB_CMDF_*, the commands' own flags) and
 * any other command by name; a run option (RUN_OPT) is also taken by a batch file's defaults line. */
#define RUN_OPT .run_option = true
#define HISTORY_ALL (SB_IN(SB_CMD_HISTORY_ADD) | SB_IN(SB_CMD_HISTORY_LIST) | SB_IN(SB_CMD_HISTORY_REGRESSIONS) | \
                     SB_IN(SB_CMD_HISTORY_ANNOTATE) | SB_IN(SB_CMD_HISTORY_CHECK))

/* A command's own default of a row: OWN_DEFAULTS(OWN(SB_CMD_TUNE, "33"), ...). */
#define OWN(c, d) {.cmd = (c), .def = (d)}
#define OWN_DEFAULTS(...) (const sb_cmd_default[]){__VA_ARGS__, {.def = NULL}}

#define F(f) offsetof(sb_cli_opts, f)
#define RUN(f) offsetof(sb_cli_opts, run.f)

static const int overlap_values[] = {-1, 1, 0};
static const int compare_formats[] = {SB_OUTPUT_TEXT, SB_OUTPUT_CSV, SB_OUTPUT_MARKDOWN};
static const int history_formats[] = {SB_OUTPUT_TEXT, SB_OUTPUT_CSV};
static const int columns_formats[] = {SB_OUTPUT_CSV, SB_OUTPUT_MARKDOWN};
static const int doc_formats[] = {SB_DOC_TEXT, SB_DOC_MARKDOWN, SB_DOC_MAN};
static const int cameras_formats[] = {SB_CAMERAS_JSON, SB_CAMERAS_GLTF};

/* --anim: all, none, or clip names (which the file must have: said when it loads) without empty ones. */
static bool check_anim(const char *v, const sb_cli_opts *o, sb_err *err) {
    (void)o;
    size_t n = strlen(v);
    if (!n || v[0] == ',' || v[n - 1] == ',' || strstr(v, ",,") || n >= sizeof(((sb_scene_opts *)0)->anim_clips))
        return sb_fail(err, "--anim %s: expected all, none, or clip names separated by commas (at most 255 characters)", v);
    return true;
}

/* A path a command writes or reads: never empty (an empty --out wrote into the working folder's root, an empty
 * --history opened a database stored nowhere). */
static bool check_path(const char *v, const sb_cli_opts *o, sb_err *err) {
    (void)o;
    if (!*v) return sb_fail(err, "an empty path: name a file or folder");
    return true;
}

/* --since: a date as the nights' are written (YYYY-MM-DD, optionally THH:MM[:SS][Z]), and a real one: the nights
 * compare against it as text, so "yesterday" or 2026-13-45 would select every night or none in silence. */
static bool check_date(const char *v, const sb_cli_opts *o, sb_err *err) {
    (void)o;
    int y = 0, m = 0, d = 0, hh = 0, mm = 0, ss = 0, n = 0, len = (int)strlen(v);
    bool ok = sscanf(v, "%4d-%2d-%2d%n", &y, &m, &d, &n) == 3 && n == 10;
    if (ok && len > 10) {
        int k = 0, t = sscanf(v + 10, "T%2d:%2d%n:%2d%n", &hh, &mm, &k, &ss, &k);
        ok = t >= 2 && (v[10 + k] == 0 || (v[10 + k] == 'Z' && v[11 + k] == 0));
    }
    static const int days[] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    bool leap = y % 4 == 0 && (y % 100 != 0 || y % 400 == 0);
    ok = ok && y >= 1970 && m >= 1 && m <= 12 && d >= 1 && d <= days[m - 1] && (m != 2 || d <= 28 + leap) &&
         hh <= 23 && mm <= 59 && ss <= 60 && hh >= 0 && mm >= 0 && ss >= 0;
    for (int i = 0; ok && i < 10; i++) ok = (i == 4 || i == 7) ? v[i] == '-' : (v[i] >= '0' && v[i] <= '9');
    if (!ok) return sb_fail(err, "expected a date, YYYY-MM-DD or YYYY-MM-DDTHH:MM:SSZ (UTC, as `history list` shows)");
    return true;
}

const sb_option sb_options[] = {
    /* the context and timing */
    {.name = "--backend", .kind = SB_OPT_CHOICE, .arg = "egl|osmesa", .def = "egl", .with = SB_CMDF_CONTEXT,
     .of_set = true,
     .commands = SB_IN(SB_CMD_INFO), RUN_OPT, .identity = SB_ID_DIM, .id_slot = 3, .field = RUN(backend),
     .help = "GL context", .check = backend_built},
    {.name = "--timing", .kind = SB_OPT_CHOICE, .arg = "auto|queries|sync", .def = "auto", .with = SB_CMDF_CONTEXT,
     .of_set = true, RUN_OPT, .field = RUN(timing), .help = "stage timing (auto: sync on software rasterizers)"},
    {.name = "--submit", .kind = SB_OPT_CHOICE, .arg = "direct|indirect", .def = "direct", .with = SB_CMDF_MEASURE,
     .of_set = true, RUN_OPT, .identity = SB_ID_NAMED, .id_column = "submit", .field = RUN(submit),
     .help = "one GL call per draw, or one glMultiDrawElementsIndirect per pass and layer (draw_calls counts draws, "
             "api_calls the calls)"},
    {.name = "--ring", .kind = SB_OPT_INT, .arg = "N", .min = 1, .max = 16, .def = "3", .with = SB_CMDF_CONTEXT, RUN_OPT,
     .of_set = true, .field = RUN(ring), .help = "timer-query ring depth in frames"},
    {.name = "--clocks", .kind = SB_OPT_CHOICE, .arg = "auto|lock|free", .def = "auto", .with = SB_CMDF_CONTEXT, RUN_OPT,
     .of_set = true,
     .field = RUN(clocks), .help = "lock the GPU clock for the invocation (NVML; auto: when permitted)"},
    {.name = "--gpu-memory", .kind = SB_OPT_BYTES, .arg = "SIZE", .min = 1, .max = 1e15,
     .def_help = "what the GL reports free, or on a software rasterizer the system memory available",
     .with = SB_CMDF_CONTEXT, RUN_OPT, .field = RUN(gpu_memory), .help = "GPU memory a run may allocate, e.g. 8G or 512M"},
    /* what is rendered */
    {.name = "--frames", .kind = SB_OPT_INT, .arg = "N", .min = 1, .max = 1000000, .def = "60",
     .of_set = true, .cmd_defs = OWN_DEFAULTS(OWN(SB_CMD_TUNE, "33"), OWN(SB_CMD_STRESS, "3")),
     .with = SB_CMDF_CONTEXT, .commands = SB_IN(SB_CMD_PATH) | SB_IN(SB_CMD_CAMERAS), RUN_OPT, .identity = SB_ID_DIM,
     .id_slot = 0, .field = RUN(frames), .help = "frames sampled along the path"},
    {.name = "--warmup", .kind = SB_OPT_INT, .arg = "auto|N", .max = 10000, .can_auto = true, .def = "auto",
     .of_set = true, .def_help = "auto: until the GPU's times and clocks settle",
     .cmd_defs = OWN_DEFAULTS(OWN(SB_CMD_TUNE, "1"), OWN(SB_CMD_STRESS, "0")),
     .with = SB_CMDF_MEASURE, RUN_OPT, .field = RUN(warmup), .help = "warm-up frames, excluded"},
    {.name = "--size", .kind = SB_OPT_SIZE, .arg = "WxH", .min = 1, .max = 16384, .def = "1280x720",
     .of_set = true, .cmd_defs = OWN_DEFAULTS(OWN(SB_CMD_STRESS, "320x180")), .with = SB_CMDF_CONTEXT,
     .commands = SB_IN(SB_CMD_PATH) | SB_IN(SB_CMD_CAMERAS), RUN_OPT, .identity = SB_ID_DIM, .id_slot = 1,
     .field = RUN(width),
     .field2 = RUN(height), .help = "render size"},
    {.name = "--sun", .kind = SB_OPT_ANGLES, .arg = "AZ,EL", .min = -90, .max = 90,
     .of_set = true, .def_help = "the scene's first directional light, else 135,40", .with = SB_CMDF_MEASURE,
     .commands = SB_IN(SB_CMD_CAMERAS) | SB_IN(SB_CMD_SCORE), RUN_OPT,
     .identity = SB_ID_GIVEN, .field = RUN(sun_az), .field2 = RUN(sun_el), .given_field = RUN(sun_override),
     .help = "sun azimuth and elevation in degrees"},
    {.name = "--error-every", .kind = SB_OPT_INT, .arg = "K", .max = 1000000, .def = "10",
     .of_set = true, .cmd_defs = OWN_DEFAULTS(OWN(SB_CMD_TUNE, "1"), OWN(SB_CMD_SCORE, "1")), .with = SB_CMDF_MEASURE,
     .commands = SB_IN(SB_CMD_SCORE), RUN_OPT, .field = RUN(error_every),
     .help = "shadow error against the exact ray-cast reference on every K-th frame (0 off), untimed"},
    {.name = "--sun-size", .kind = SB_OPT_NUM, .arg = "DEG", .max = 10, .def = "0", .def_help = "0, a sun of no size",
     .of_set = true,
     .with = SB_CMDF_MEASURE, .commands = SB_IN(SB_CMD_SCORE), RUN_OPT, .line_option = true, .identity = SB_ID_LIGHT,
     .field = RUN(sun_size),
     .help = "the sun's angular diameter: the reference casts rays over its disc (soft shadows; the real sun: 0.53)"},
    {.name = "--lamp-radius", .kind = SB_OPT_NUM, .arg = "M", .max = INFINITY, .def = "0", .def_help = "0, no size",
     .of_set = true,
     .with = SB_CMDF_MEASURE, .commands = SB_IN(SB_CMD_SCORE), RUN_OPT, .line_option = true, .identity = SB_ID_LIGHT,
     .field = RUN(lamp_radius),
     .help = "point and spot lights' radius in scene units: the reference casts rays over it"},
    {.name = "--lights", .kind = SB_OPT_TEXT, .arg = "sun|lamps|all|LIST", .def = NULL,
     .of_set = true,
     .def_help = "the light the technique shadows alone: the sun; light= of cube and dpsm", .with = SB_CMDF_MEASURE,
     RUN_OPT, .line_option = true, .identity = SB_ID_TEXT, .id_column = "light", .field = RUN(lights),
     .help = "the lights a run shadows and scores, each with its own shadows: every point and spot light (lamps), "
             "the sun and every lamp (all), or a list such as sun,0,3 (lamps by number in file order)"},
    {.name = "--ref-samples", .kind = SB_OPT_INT, .arg = "N", .min = 1, .max = 4096, .def = "64",
     .of_set = true,
     .with = SB_CMDF_MEASURE, .commands = SB_IN(SB_CMD_SCORE), RUN_OPT, .line_option = true, .identity = SB_ID_LIGHT,
     .field = RUN(ref_samples),
     .help = "rays over a sized light at a penumbra point (centre and rim decide the rest)"},
    {.name = "--flicker-dt", .kind = SB_OPT_NUM, .arg = "S", .max = 10, .def = "0.0166667",
     .of_set = true, .def_help = "1/60 s, one display frame at 60 Hz",
     .cmd_defs = OWN_DEFAULTS({.cmd = SB_CMD_TUNE, .def = "0", .help = "0; 1/60 s when --max-flicker bounds the flicker"}),
     .with = SB_CMDF_MEASURE, .commands = SB_IN(SB_CMD_CAMERAS), RUN_OPT, .field = RUN(flicker_dt),
     .help = "path time from an evaluated frame to its twin, whose shadow maps look the frame's points up again "
             "(flicker_rate; 0 off)"},
    {.name = "--images", .kind = SB_OPT_INT, .arg = "K", .max = 1000000, .def = "0", .with = SB_CMDF_MEASURE,
     .commands = SB_IN(SB_CMD_SCORE), RUN_OPT,
     .of_set = true,
     .field = RUN(images), .help = "images of every K-th frame: colour, visibility, reference, error, cascades (0 none)",
     .check = images_built},
    {.name = "--flip", .kind = SB_OPT_FLAG, .with = SB_CMDF_MEASURE, .commands = SB_IN(SB_CMD_SCORE), RUN_OPT,
     .of_set = true, .field = RUN(flip),
     .help = "score each evaluated frame's shaded colour against the reference's with LDR-FLIP (flip_mean, flip_p95; "
             "with --images, the shaded frames and the FLIP map)"},
    {.name = "--taa", .kind = SB_OPT_CHOICE, .arg = "off|on", .def = "off", .with = SB_CMDF_MEASURE, RUN_OPT,
     .of_set = true, .identity = SB_ID_NAMED, .field = RUN(taa),
     .help = "resolve each evaluated frame through temporal anti-aliasing too (8 jittered display frames before it, "
             "reprojected, clamped, blended): taa_flip_mean and taa_flicker_rate, the error and flicker a player "
             "sees"},
    {.name = "--repeat", .kind = SB_OPT_INT, .arg = "K", .min = 1, .max = 1000, .def = "1", .with = SB_CMDF_MEASURE,
     .of_set = true, RUN_OPT, .field = RUN(repeat), .help = "run the path K times"},
    {.name = "--target-ci", .kind = SB_OPT_NUM, .arg = "PCT", .max = 100, .open_min = true, .def_help = "off",
     .of_set = true, .with = SB_CMDF_MEASURE, RUN_OPT, .field = RUN(target_ci),
     .help = "repeat the path until the 95% CI of mean gpu_ms is within PCT% of it"},
    {.name = "--max-repeat", .kind = SB_OPT_INT, .arg = "N", .min = 1, .max = 1000, .def = "10",
     .of_set = true,
     .with = SB_CMDF_MEASURE, RUN_OPT, .field = RUN(max_repeat), .help = "at most N repetitions for --target-ci"},
    {.name = "--order", .kind = SB_OPT_CHOICE, .arg = "matrix|interleave|shuffle", .def = "matrix",
     .cmd_defs = OWN_DEFAULTS(OWN(SB_CMD_TUNE, "shuffle")), .with = SB_CMDF_MATRIX, RUN_OPT,
     .field = RUN(order), .help = "order of a scene's runs and repetitions (interleave: A1 B1 A2 B2 ...)"},
    {.name = "--rerun-unstable", .kind = SB_OPT_INT, .arg = "N", .max = 10, .def = "0", .with = SB_CMDF_MATRIX, RUN_OPT,
     .field = RUN(rerun_unstable),
     .help = "run again, at the end, each run flagged unstable (its timings disturbed), up to N times, within a "
             "quarter of the night's time (a disturbed night waits for a calm probe first): the figures of a stable "
             "attempt are the run's, every attempt's frames kept"},
    {.name = "--seed", .kind = SB_OPT_SEED, .arg = "N", .min = 1, .max = 1.8e19,
     .def_help = "chosen, in the summary's seed column", .cmd_defs = OWN_DEFAULTS(OWN(SB_CMD_TUNE, "1")),
     .with = SB_CMDF_MEASURE, RUN_OPT, .field = RUN(seed), .help = "shuffle's seed"},
    {.name = "--threads", .kind = SB_OPT_INT, .arg = "N", .min = 1, .max = 1024, .def_help = "all cores",
     .with = SB_CMDF_CONTEXT, RUN_OPT, .field = RUN(threads), .help = "reference ray-casting threads"},
    {.name = "--overlap", .kind = SB_OPT_CHOICE, .arg = "auto|on|off", .values = overlap_values, .def = "auto",
     .def_help = "auto: on on a GPU, off on a CPU rasterizer", .with = SB_CMDF_MEASURE, RUN_OPT, .field = RUN(overlap),
     .help = "cast the reference of evaluated frames in the background while timed frames render"},
    {.name = "--run-timeout", .kind = SB_OPT_NUM, .arg = "S", .max = INFINITY, .def = "0", .def_help = "none",
     .with = SB_CMDF_MEASURE, RUN_OPT, .field = RUN(run_timeout_s), .help = "a run taking longer is recorded as failed"},
    /* how scene files are read */
    {.name = "--allow-external-uris", .kind = SB_OPT_FLAG, .with = SB_CMDF_SCENES, RUN_OPT,
     .field = RUN(allow_external_uris), .help = "let glTF buffers and images be read from outside the scene's folder"},
    {.name = "--blend-casters", .kind = SB_OPT_CHOICE, .arg = "mask|opaque|none", .def = "mask", .with = SB_CMDF_SCENES,
     .of_set = true,
     RUN_OPT, .field = RUN(blend), .help = "glTF BLEND materials: alpha-tested at 0.5, opaque, or left out"},
    {.name = "--pose", .kind = SB_OPT_NUM, .arg = "T", .min = -INFINITY, .max = INFINITY, .def_help = "the rest pose",
     .of_set = true,
     .with = SB_CMDF_SCENES, RUN_OPT, .field = RUN(pose_time), .given_field = RUN(pose), .excludes = "--anim",
     .help = "nodes and skins at time T (seconds) of the file's first animation, frozen (no clip plays)"},
    {.name = "--anim", .kind = SB_OPT_TEXT, .arg = "all|none|NAME[,NAME]", .def = "all", .with = SB_CMDF_SCENES, RUN_OPT,
     .cmd_defs = OWN_DEFAULTS(OWN(SB_CMD_SCORE, "none")),
     .of_set = true, .field = RUN(anim), .check = check_anim,
     .help = "which of a file's animation clips play on the path's clock (each loops; with all, a node follows the "
             "first clip that animates it; none: the scene as today, frozen; score: none, as another renderer's "
             "exported scene is drawn)"},
    {.name = "--anim-speed", .kind = SB_OPT_NUM, .arg = "X", .min = 0, .open_min = true, .max = 1e6, .def = "1",
     .of_set = true,
     .with = SB_CMDF_SCENES, RUN_OPT, .field = RUN(anim_speed), .help = "clip seconds a second of the path's clock"},
    /* where results go, and what is said */
    {.name = "--out", .kind = SB_OPT_TEXT, .arg = "DIR", .def = "out",
     .commands = SB_IN(SB_CMD_RUN) | SB_IN(SB_CMD_BATCH) | SB_IN(SB_CMD_TUNE) | SB_IN(SB_CMD_SCORE), .field = F(out),
     .help = "results folder; run, tune and score write DIR/<UTC time>/, batch DIR/<batch name>/<UTC time>/", .check = check_path},
    {.name = "--out", .kind = SB_OPT_TEXT, .arg = "DIR", .def_help = "required", .commands = SB_IN(SB_CMD_MERGE),
     .field = F(out), .help = "the merged results set: a new or empty folder (written beside it, renamed to it whole)", .check = check_path},
    {.name = "--out", .kind = SB_OPT_TEXT, .arg = "SITE", .def = "out/report", .commands = SB_IN(SB_CMD_REPORT),
     .field = F(out), .help = "the site's folder", .check = check_path},
    {.name = "--resume", .kind = SB_OPT_TEXT, .arg = "DIR",
     .commands = SB_IN(SB_CMD_RUN) | SB_IN(SB_CMD_BATCH) | SB_IN(SB_CMD_TUNE), .field = F(resume),
     .help = "keep DIR's complete runs and render the rest into it", .check = check_path},
    {.name = "--shard", .kind = SB_OPT_TEXT, .arg = "I/N", .commands = SB_IN(SB_CMD_BATCH), .field = F(shard),
     .of_set = true, .help = "render share I of N of the matrix (cost-balanced)"},
    {.name = "--strict-path", .kind = SB_OPT_FLAG, .with = SB_CMDF_MEASURE, .commands = SB_IN(SB_CMD_PATH), RUN_OPT,
     .field = RUN(strict_path),
     .help = "refuse a path whose cameras stand inside closed geometry, under a surface facing up or nearer a "
             "surface than the near plane (checked whenever the error is; exit 2)"},
    {.name = "--format", .kind = SB_OPT_CHOICE, .arg = "json|gltf", .values = cameras_formats, .def = "json",
     .commands = SB_IN(SB_CMD_CAMERAS), .field = F(format),
     .help = "JSON (every camera's matrices, for a script) or glTF 2.0 (an animated camera and the lights, for an engine)"},
    {.name = "--twins", .kind = SB_OPT_FLAG, .commands = SB_IN(SB_CMD_CAMERAS), .field = F(twins),
     .help = "each frame's flicker twin too: its camera --flicker-dt of path time later"},
    {.name = "--all-pairs", .kind = SB_OPT_FLAG, .commands = SB_IN(SB_CMD_TECHNIQUES), .field = F(all_pairs),
     .help = "print, for each SPEC, specs in which every pair of values of two of its enumerated parameters appears "
             "(the parameters SPEC gives held); pairs the technique refuses on stderr with the reason"},
    {.name = "--dry-run", .kind = SB_OPT_FLAG, .commands = SB_IN(SB_CMD_BATCH), .field = F(dry_run),
     .help = "print the matrix (and the shard's share), render nothing"},
    {.name = "--yes", .kind = SB_OPT_FLAG, .with = SB_CMDF_MATRIX, .field = F(yes),
     .help = "start a matrix of more runs than SB_GRID_CONFIRM without asking for this (it prints their count and "
             "estimated time, then exits 2)"},
    {.name = "--progress", .kind = SB_OPT_FLAG, .def_help = "when stderr is a terminal", .with = SB_CMDF_CONTEXT,
     .field = RUN(progress), .help = "progress line on stderr"},
    {.name = "--quiet", .kind = SB_OPT_FLAG, .with = SB_CMDF_ANY, .field = F(quiet), .help = "no notices on stderr"},
    {.name = "--verbose", .kind = SB_OPT_FLAG, .with = SB_CMDF_ANY, .field = F(verbose), .excludes = "--quiet",
     .help = "also the notes a user cannot act on (e.g. a software rasterizer has no clock)"},
    /* compare */
    {.name = "--metric", .kind = SB_OPT_TEXT, .arg = "M,...",
     .def_help = "the metrics marked for it (shadowbench columns)",
     .commands = SB_IN(SB_CMD_COMPARE) | SB_IN(SB_CMD_HISTORY_REGRESSIONS) | SB_IN(SB_CMD_HISTORY_CHECK),
     .field = F(metrics), .help = "the metrics compared"},
    {.name = "--threshold", .kind = SB_OPT_NUM, .arg = "PCT", .max = INFINITY, .def = "5",
     .commands = SB_IN(SB_CMD_COMPARE) | SB_IN(SB_CMD_BISECT), .field = F(threshold),
     .help = "a change smaller than PCT% is no regression (bisect: a timing change smaller than it is none)"},
    {.name = "--metric", .kind = SB_OPT_TEXT, .arg = "M", .def_help = "the frame time (gpu_ms)",
     .commands = SB_IN(SB_CMD_BISECT), .field = F(metrics),
     .help = "the metric bisected: a timing (ms) by paired runs, any other exactly"},
    {.name = "--repeat", .kind = SB_OPT_INT, .arg = "K", .min = 2, .max = 100, .def = "5",
     .commands = SB_IN(SB_CMD_BISECT), .field = F(pairs),
     .help = "timings: interleaved runs of the candidate and of GOOD a step (as many again when it cannot tell)"},
    {.name = "--series", .kind = SB_OPT_TEXT, .arg = "TEXT", .commands = SB_IN(SB_CMD_BISECT), .field = F(series),
     .help = "with --history: bisect the newest regression of the series whose name holds TEXT"},
    {.name = "--series", .kind = SB_OPT_TEXT, .arg = "PATTERN", .def_help = "every series",
     .commands = SB_IN(SB_CMD_HISTORY_ANNOTATE), .field = F(series),
     .help = "the series the note is about (a glob, or text in the series' name)"},
    {.name = "--accept", .kind = SB_OPT_FLAG, .commands = SB_IN(SB_CMD_HISTORY_ANNOTATE), .field = F(accept),
     .help = "the change starting on that night was meant (listed as accepted; no exit 1)"},
    {.name = "--restart", .kind = SB_OPT_FLAG, .commands = SB_IN(SB_CMD_HISTORY_ANNOTATE), .field = F(restart),
     .help = "by COMMIT: noted only where the history restarts, a night before having run without it (a change older "
             "than the history's first night is none of its nights' doing: nothing noted, exit 0)"},
    {.name = "--ppd", .kind = SB_OPT_NUM, .arg = "N", .min = 1, .max = 1000, .def = "67.0206",
     .commands = SB_IN(SB_CMD_FLIP), .field = F(ppd),
     .help = "pixels per degree of the viewing condition (the paper's: a 0.7 m wide 3840-pixel display from 0.7 m)"},
    {.name = "--pattern", .kind = SB_OPT_TEXT, .arg = "FILE", .def = "vis_%04d.png", .commands = SB_IN(SB_CMD_SCORE),
     .field = F(pattern),
     .help = "a frame's visibility in DIR, its number as %d or %0Nd (PNG 8 or 16 bits, or EXR: white lit, black "
             "shadowed, grey a share of the light)", .check = check_path},
    {.name = "--mask", .kind = SB_OPT_TEXT, .arg = "FILE", .def_help = "required", .commands = SB_IN(SB_CMD_SCORE),
     .field = F(mask),
     .help = "a frame's mask in DIR, numbered as --pattern: white where the renderer drew geometry, black where it "
             "drew none (what checks that its camera is the exported one)", .check = check_path},
    {.name = "--renderer", .kind = SB_OPT_TEXT, .arg = "NAME", .def_help = "DIR's name",
     .commands = SB_IN(SB_CMD_SCORE), .field = F(renderer),
     .help = "the renderer's name: the results' technique column"},
    {.name = "--params", .kind = SB_OPT_TEXT, .arg = "TEXT", .def_help = "none", .commands = SB_IN(SB_CMD_SCORE),
     .field = F(renderer_params),
     .help = "the renderer's settings as you name them (e.g. cascades=4:bias=0.001): the results' params column"},
    {.name = "--map", .kind = SB_OPT_TEXT, .arg = "FILE.png", .commands = SB_IN(SB_CMD_FLIP), .field = F(map),
     .help = "write the per-pixel error there (grey: black 0, white 1)", .check = check_path},
    {.name = "--nights", .kind = SB_OPT_INT, .arg = "N", .min = 3, .max = 1000, .def = "10",
     .commands = SB_IN(SB_CMD_HISTORY_CHECK), .field = F(nights),
     .help = "how many of each series' newest nights make its band"},
    {.name = "--build-type", .kind = SB_OPT_CHOICE, .arg = "release|debugoptimized|debug|plain", .def = "release",
     .commands = SB_IN(SB_CMD_BISECT), .field = F(build_type),
     .help = "meson's build type of the scratch builds: debug and plain build in half the time, and their harness "
             "is slower (a GPU-time metric's change is the same; a CPU-side one's, cpu_ms, is not the release build's)"},
    {.name = "--workdir", .kind = SB_OPT_TEXT, .arg = "DIR", .def_help = "shadowbench-bisect in the git directory",
     .commands = SB_IN(SB_CMD_BISECT), .field = F(workdir),
     .help = "the scratch worktree, its build and every binary built (kept for the next bisect)", .check = check_path},
    {.name = "--format", .kind = SB_OPT_CHOICE, .arg = "text|csv|markdown", .values = compare_formats, .def = "text",
     .commands = SB_IN(SB_CMD_COMPARE), .field = F(format), .help = "how the table is written"},
    {.name = "--format", .kind = SB_OPT_CHOICE, .arg = "text|csv", .values = history_formats, .def = "text",
     .commands = SB_IN(SB_CMD_HISTORY_REGRESSIONS), .field = F(format), .help = "how the changes are written"},
    {.name = "--format", .kind = SB_OPT_CHOICE, .arg = "csv|markdown", .values = columns_formats, .def = "csv",
     .commands = SB_IN(SB_CMD_COLUMNS), .field = F(format), .help = "how the columns are written"},
    {.name = "--format", .kind = SB_OPT_CHOICE, .arg = "text|markdown", .values = doc_formats, .def = "text",
     .commands = SB_IN(SB_CMD_TECHNIQUES), .field = F(format),
     .help = "how they are written (markdown: docs/techniques.md's parameter tables)"},
    {.name = "--format", .kind = SB_OPT_CHOICE, .arg = "text|markdown|man", .values = doc_formats, .def = "text",
     .commands = SB_IN(SB_CMD_HELP), .field = F(format),
     .help = "--help's text, or the reference of docs/cli.md (markdown) or of the man page (man)"},
    {.name = "--pair", .kind = SB_OPT_TEXT, .arg = "KEY=A,B", .commands = SB_IN(SB_CMD_COMPARE), .field = F(pair),
     .help = "the runs of one set that differ only in KEY (technique=pssm,sdsm, layered=off,gs)"},
    /* history and report */
    {.name = "--history", .kind = SB_OPT_TEXT, .arg = "FILE", .def_help = "$SB_HISTORY, else out/history.sqlite",
     .commands = HISTORY_ALL | SB_IN(SB_CMD_REPORT) | SB_IN(SB_CMD_BISECT), .field = F(history),
     .help = "the results history", .check = check_path},
    {.name = "--since", .kind = SB_OPT_TEXT, .arg = "DATE", .commands = SB_IN(SB_CMD_HISTORY_REGRESSIONS),
     .field = F(since), .help = "only the nights from DATE on", .check = check_date},
    {.name = "--recent", .kind = SB_OPT_INT, .arg = "N", .min = 1, .max = 10000, .def = "3",
     .commands = SB_IN(SB_CMD_HISTORY_REGRESSIONS) | SB_IN(SB_CMD_REPORT), .field = F(recent),
     .help = "a regression starting in the newest N nights is recent (exit 1, the report's index)"},
    {.name = "--noise-floor", .kind = SB_OPT_NUM, .arg = "PCT", .max = 100, .open_min = true,
     .def_help = "1, 5 on a software rasterizer",
     .commands = SB_IN(SB_CMD_HISTORY_REGRESSIONS) | SB_IN(SB_CMD_HISTORY_CHECK), .field = F(noise_floor),
     .help = "the least night-to-night timing noise assumed"},
    /* tune */
    {.name = "--max-err", .kind = SB_OPT_NUM, .arg = "E", .max = 1, .open_min = true, .commands = SB_IN(SB_CMD_TUNE),
     .of_set = true, .field = F(max_err), .help = "the cheapest settings whose err_rate stays within E"},
    {.name = "--max-flicker", .kind = SB_OPT_NUM, .arg = "F", .max = 1, .open_min = true, .def_help = "none",
     .of_set = true, .commands = SB_IN(SB_CMD_TUNE), .field = F(max_flicker),
     .help = "and whose flicker_rate (twins --flicker-dt later) stays within F"},
    {.name = "--max-flip", .kind = SB_OPT_NUM, .arg = "F", .max = 1, .open_min = true, .def_help = "none",
     .of_set = true, .commands = SB_IN(SB_CMD_TUNE), .field = F(max_flip),
     .help = "and whose flip_mean (the shaded frame's LDR-FLIP against the reference's: --flip) stays within F"},
    {.name = "--max-mb", .kind = SB_OPT_NUM, .arg = "M", .max = INFINITY, .open_min = true, .def_help = "none",
     .of_set = true, .commands = SB_IN(SB_CMD_TUNE), .field = F(max_mb),
     .help = "and whose shadow storage (shadow_mb) stays within M MiB: settings over it are not rendered"},
    {.name = "--budget-ms", .kind = SB_OPT_NUM, .arg = "B", .max = INFINITY, .open_min = true,
     .of_set = true, .commands = SB_IN(SB_CMD_TUNE), .field = F(budget_ms),
     .help = "the most accurate settings whose frame time stays within B ms"},
    {.name = "--techniques", .kind = SB_OPT_TEXT, .arg = "LIST", .def_help = "every technique with a shadow map",
     .of_set = true,
     .commands = SB_IN(SB_CMD_TUNE), .field = F(techniques), .help = "the techniques searched (comma list)"},
    {.name = "--time-limit", .kind = SB_OPT_DURATION, .arg = "D", .max = INFINITY, .open_min = true, .def_help = "none",
     .commands = SB_IN(SB_CMD_TUNE), .field = F(time_limit_s), .help = "stop the search after D (600, 90s, 10m, 1.5h)"},
};
const int sb_option_count = (int)SB_COUNT(sb_options);

_Static_assert(SB_COUNT(sb_options) <= SB_OPTION_MAX, "raise SB_OPTION_MAX");

bool sb_option_taken(const sb_option *opt, const sb_command_def *cmd) {
    return (opt->commands & SB_IN(cmd->id)) || (opt->with & cmd->flags);
}

const sb_option *sb_option_find(const char *name, const sb_command_def *cmd) {
    for (int i = 0; i < sb_option_count; i++)
        if (!strcmp(sb_options[i].name, name) && (!cmd || sb_option_taken(&sb_options[i], cmd))) return &sb_options[i];
    return NULL;
}

/* The run option of `name` (a batch file's defaults line), or NULL. */
static const sb_option *run_option(const char *name) {
    for (int i = 0; i < sb_option_count; i++)
        if (sb_options[i].run_option && !strcmp(sb_options[i].name, name)) return &sb_options[i];
    return NULL;
}

static void *at(sb_cli_opts *o, size_t field) { return (char *)o + field; }

/* "[1, 16]", "(0, 100]", ">= 0", "> 0" */
static void range_text(const sb_option *opt, char *out, size_t len) {
    if (isinf(opt->min))
        snprintf(out, len, "a finite number");
    else if (isinf(opt->max))
        snprintf(out, len, "a number %s %.15g", opt->open_min ? ">" : ">=", opt->min);
    else
        snprintf(out, len, "%s in %c%.15g, %.15g]",
                 opt->kind == SB_OPT_INT || opt->kind == SB_OPT_SEED ? "an integer" : "a number",
                 opt->open_min ? '(' : '[', opt->min, opt->max);
}

static bool in_range(const sb_option *opt, double v) {
    return isfinite(v) ? (opt->open_min ? v > opt->min : v >= opt->min) && v <= opt->max : false;
}

/* "expected matrix, interleave or shuffle" */
static void choices_text(const char *choices, char *out, size_t len) {
    out[0] = 0;
    int n = 1;
    for (const char *c = choices; *c; c++)
        n += *c == '|';
    const char *c = choices;
    for (int k = 0; k < n; k++) {
        size_t w = strcspn(c, "|");
        size_t l = strlen(out);
        snprintf(out + l, len - l, "%s%.*s", k == 0 ? "" : k == n - 1 ? " or " : ", ", (int)w, c);
        c += w + (c[w] == '|');
    }
}

static bool bad_value(const sb_option *opt, const char *v, sb_err *err) {
    char what[160];
    switch (opt->kind) {
    case SB_OPT_CHOICE: choices_text(opt->arg, what, sizeof what); break;
    case SB_OPT_SIZE:
        snprintf(what, sizeof what, "WxH, width and height integers in [%g, %g], e.g. 1280x720", opt->min, opt->max);
        break;
    case SB_OPT_ANGLES:
        snprintf(what, sizeof what, "AZIMUTH,ELEVATION in degrees, the elevation in [%g, %g]", opt->min, opt->max);
        break;
    case SB_OPT_BYTES:
        snprintf(what, sizeof what, "a size with M or G, e.g. 8G or 512M (up to %g bytes)", opt->max);
        break;
    case SB_OPT_DURATION: snprintf(what, sizeof what, "a duration > 0 such as 600, 90s, 10m or 1.5h"); break;
    default:
        range_text(opt, what, sizeof what);
        if (opt->can_auto) {
            size_t l = strlen(what);
            snprintf(what + l, sizeof what - l, " or auto");
        }
    }
    return sb_fail(err, "%s %s: expected %s", opt->name, v, what);
}

static bool parse_duration(const char *text, double *seconds) {
    char *end;
    double v = strtod(text, &end);
    if (end == text || !isfinite(v)) return false;
    double unit = !strcmp(end, "") || !strcmp(end, "s")      ? 1
                  : !strcmp(end, "m") || !strcmp(end, "min") ? 60
                  : !strcmp(end, "h")                        ? 3600
                                                             : 0;
    *seconds = v * unit;
    return unit > 0;
}

/* Parses v for opt into o; false with the range when it does not fit. */
static bool set_value(sb_cli_opts *o, const sb_option *opt, const char *v, sb_err *err) {
    double d;
    long n;
    char extra;
    switch (opt->kind) {
    case SB_OPT_FLAG: *(bool *)at(o, opt->field) = true; break;
    case SB_OPT_INT:
        if (opt->can_auto && !strcmp(v, "auto"))
            n = -1;
        else if (!sb_parse_int(v, &n) || !in_range(opt, (double)n))
            return bad_value(opt, v, err);
        *(int *)at(o, opt->field) = (int)n;
        break;
    case SB_OPT_SEED: {
        unsigned long long u;
        if (sscanf(v, "%llu%c", &u, &extra) != 1 || v[0] == '-' || !in_range(opt, (double)u))
            return bad_value(opt, v, err);
        *(uint64_t *)at(o, opt->field) = u;
        break;
    }
    case SB_OPT_NUM:
        if (!sb_parse_double(v, &d) || !in_range(opt, d)) return bad_value(opt, v, err);
        *(double *)at(o, opt->field) = d;
        break;
    case SB_OPT_DURATION:
        if (!parse_duration(v, &d) || !in_range(opt, d)) return bad_value(opt, v, err);
        *(double *)at(o, opt->field) = d;
        break;
    case SB_OPT_BYTES: {
        char unit = 0;
        int k = sscanf(v, "%lf%c%c", &d, &unit, &extra);
        double scale = unit == 'G' || unit == 'g' ? 1073741824.0 : unit == 'M' || unit == 'm' ? 1048576.0 : 0;
        if (k != 2 || !scale || !in_range(opt, d * scale)) return bad_value(opt, v, err);
        *(double *)at(o, opt->field) = d * scale;
        break;
    }
    case SB_OPT_CHOICE: {
        const char *c = opt->arg;
        for (int k = 0; *c; k++) {
            size_t w = strcspn(c, "|");
            if (strlen(v) == w && !strncmp(v, c, w)) {
                *(int *)at(o, opt->field) = opt->values ? opt->values[k] : k;
                return true;
            }
            c += w + (c[w] == '|');
        }
        return bad_value(opt, v, err);
    }
    case SB_OPT_TEXT: *(const char **)at(o, opt->field) = sb_intern(v); break;   /* outlives a batch file's line */
    case SB_OPT_SIZE: {
        int w, h;
        if (sscanf(v, "%dx%d%c", &w, &h, &extra) != 2 || !in_range(opt, w) || !in_range(opt, h))
            return bad_value(opt, v, err);
        *(int *)at(o, opt->field) = w;
        *(int *)at(o, opt->field2) = h;
        break;
    }
    case SB_OPT_ANGLES: {
        char buf[64];
        double az, el;
        snprintf(buf, sizeof buf, "%s", v);
        char *comma = strchr(buf, ',');
        if (comma) *comma = 0;
        if (!comma || !sb_parse_double(buf, &az) || !sb_parse_double(comma + 1, &el) || !in_range(opt, el))
            return bad_value(opt, v, err);
        *(double *)at(o, opt->field) = az;
        *(double *)at(o, opt->field2) = el;
        break;
    }
    }
    if (opt->given_field) *(bool *)at(o, opt->given_field) = true;
    return true;
}

const char *sb_option_default(const sb_option *opt, const sb_command_def *cmd) {
    for (const sb_cmd_default *d = opt->cmd_defs; cmd && d && d->def; d++)
        if (d->cmd == cmd->id) return d->def;
    return opt->def;
}

void sb_cli_defaults(sb_cli_opts *o, const sb_command_def *cmd) {
    memset(o, 0, sizeof *o);
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        const char *def = sb_option_default(opt, cmd);
        if (!def || !(opt->run_option || (cmd && sb_option_taken(opt, cmd)))) continue;
        sb_err e;
        bool was = opt->given_field && *(bool *)at(o, opt->given_field);
        if (!set_value(o, opt, def, &e))
            abort(); /* a row whose default is out of its own range: the unit test
                        says which */
        if (opt->given_field) *(bool *)at(o, opt->given_field) = was;
    }
    long cpus = sysconf(_SC_NPROCESSORS_ONLN); /* --threads: all cores */
    o->run.threads = cpus > 1024 ? 1024 : cpus > 0 ? (int)cpus : 1;
}

void sb_run_opts_defaults(sb_run_opts *o) {
    sb_cli_opts c;
    sb_cli_defaults(&c, NULL);
    *o = c.run;
}

/* One option at argv-like position: value from `v`; *used: whether v was taken.
 */
static bool take(sb_cli_opts *o, const sb_option *opt, const char *v, bool *used, sb_err *err) {
    *used = false;
    if (opt->kind != SB_OPT_FLAG) {
        if (!v) return sb_fail(err, "%s needs a value (%s)", opt->name, opt->arg);
        *used = true;
    }
    if (!set_value(o, opt, v, err)) return false;
    if (opt->check && !opt->check(v, o, err)) {   /* the option and its value named, where the check did not */
        if (strncmp(err->msg, opt->name, strlen(opt->name))) {
            char why[SB_ERR_LEN];
            snprintf(why, sizeof why, "%s", err->msg);
            sb_fail(err, "%s '%.200s': %s", opt->name, v, why);
        }
        return false;
    }
    o->given[opt - sb_options] = true;
    return true;
}

/* Options that cannot be given together (a row's `excludes`). */
static bool check_exclusions(const sb_cli_opts *o, sb_err *err) {
    for (int i = 0; i < sb_option_count; i++)
        if (o->given[i] && sb_options[i].excludes && sb_cli_given(o, sb_options[i].excludes))
            return sb_fail(err, "%s and %s: give one of them", sb_options[i].excludes, sb_options[i].name);
    return true;
}

bool sb_cli_parse(sb_cli_opts *o, const sb_command_def *cmd, int argc, char **argv, int first, const char **pos,
                  int *npos, sb_err *err) {
    *npos = 0;
    for (int i = first; i < argc; i++) {
        const char *a = argv[i];
        if (strncmp(a, "--", 2) != 0 || !a[2]) {
            pos[(*npos)++] = a;
            continue;
        }
        char name[64];   /* --name=value: the value after '=' */
        const char *eq = strchr(a, '=');
        snprintf(name, sizeof name, "%.*s", (int)(eq && eq - a < (long)sizeof name ? eq - a : (long)strlen(a)), a);
        const sb_option *opt = sb_option_find(name, cmd);
        if (!opt) {
            if (sb_option_find(name, NULL))
                return sb_fail(err, "%s: %s is not an option of %s (see shadowbench %s --help)", cmd->name, name,
                               cmd->name, cmd->name);
            return sb_fail(err, "%s: unknown option %s (see shadowbench %s --help)", cmd->name, name, cmd->name);
        }
        if (eq && opt->kind == SB_OPT_FLAG) return sb_fail(err, "%s takes no value (%s)", name, a);
        bool used;
        if (!take(o, opt, eq ? eq + 1 : i + 1 < argc ? argv[i + 1] : NULL, &used, err)) return false;
        i += used && !eq;
    }
    return check_exclusions(o, err);
}

bool sb_cli_parse_tokens(sb_cli_opts *o, char **tok, int n, const char *where, sb_err *err) {
    for (int i = 0; i < n; i++) {
        char name[64];
        const char *eq = strchr(tok[i], '=');
        snprintf(name, sizeof name, "%.*s", (int)(eq && eq - tok[i] < 64 ? eq - tok[i] : (long)strlen(tok[i])), tok[i]);
        const sb_option *opt = run_option(name);
        if (!opt) return sb_fail(err, "%s: '%s' is not a run option", where, name);
        bool used;
        sb_err e;
        if (!take(o, opt, eq ? eq + 1 : i + 1 < n ? tok[i + 1] : NULL, &used, &e))
            return sb_fail(err, "%s: %s", where, e.msg);
        i += used && !eq;
    }
    return true;
}

bool sb_cli_given(const sb_cli_opts *o, const char *name) {
    for (int i = 0; i < sb_option_count; i++)
        if (o->given[i] && !strcmp(sb_options[i].name, name)) return true;
    return false;
}

static size_t kind_size(sb_opt_kind k) {
    switch (k) {
    case SB_OPT_FLAG: return sizeof(bool);
    case SB_OPT_INT:
    case SB_OPT_CHOICE:
    case SB_OPT_SIZE: return sizeof(int);
    case SB_OPT_SEED: return sizeof(uint64_t);
    case SB_OPT_TEXT: return sizeof(const char *);
    default: return sizeof(double);
    }
}

static void copy_given(sb_run_opts *to, const sb_cli_opts *from, bool lines_only) {
    sb_cli_opts dst;
    dst.run = *to;
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        if (!from->given[i] || !opt->run_option || (lines_only && !opt->line_option)) continue; /* the run options */
        size_t fields[] = {opt->field, opt->field2, opt->given_field};
        for (int k = 0; k < 3; k++)
            if (fields[k])
                memcpy(at(&dst, fields[k]), (const char *)from + fields[k],
                       k == 2 ? sizeof(bool) : kind_size(opt->kind));
    }
    *to = dst.run;
}

void sb_cli_copy_given(sb_run_opts *to, const sb_cli_opts *from) { copy_given(to, from, false); }
void sb_cli_copy_line_options(sb_run_opts *to, const sb_cli_opts *from) { copy_given(to, from, true); }

void sb_line_options_text(char *out, size_t len) {
    out[0] = 0;
    int n = 0, k = 0;
    for (int i = 0; i < sb_option_count; i++) n += sb_options[i].line_option;
    for (int i = 0; i < sb_option_count; i++) {
        if (!sb_options[i].line_option) continue;
        size_t l = strlen(out);
        snprintf(out + l, len - l, "%s%s", k == 0 ? "" : k == n - 1 ? " and " : ", ", sb_options[i].name);
        k++;
    }
}

void sb_option_synopsis(const sb_option *opt, char *out, size_t len) {
    snprintf(out, len, "%s%s%s", opt->name, opt->arg ? " " : "", opt->arg ? opt->arg : "");
}

/* "  --frames N   frames sampled along the path (default 60)", the text wrapped at 100 columns. */
/* "  LABEL        text ...": the text from column 30, wrapped at 100. */
static void labelled(FILE *f, const char *label, const char *text) {
    enum { COL = 30, WIDTH = 100 };
    int at_col = fprintf(f, "  %s", label);
    const char *t = text;
    while (*t) {
        if (at_col >= COL - 1) fputc('\n', f), at_col = 0;
        fprintf(f, "%*s", COL - at_col, "");
        size_t n = strlen(t);
        if (n > WIDTH - COL) { /* break at the last space that fits */
            n = WIDTH - COL;
            while (n > 0 && t[n] != ' ') n--;
            if (n == 0) n = strcspn(t, " ");
        }
        fprintf(f, "%.*s\n", (int)n, t);
        t += n;
        while (*t == ' ') t++;
        at_col = 0;
    }
}

void sb_option_default_text(const sb_option *opt, const sb_command_def *table, const sb_command_def *cmd, char *out,
                            size_t len) {
    const char *own = NULL;
    for (const sb_cmd_default *d = opt->cmd_defs; cmd && d && d->def; d++)
        if (d->cmd == cmd->id) own = d->help ? d->help : d->def;
    snprintf(out, len, "%s", own ? own : opt->def_help ? opt->def_help : opt->def ? opt->def : "");
    if (cmd || !table) return;
    for (const sb_cmd_default *d = opt->cmd_defs; d && d->def; d++) {   /* the general help: each command's own */
        if (!sb_option_taken(opt, &table[d->cmd])) continue;
        size_t l = strlen(out);
        snprintf(out + l, len - l, "; %s %s", table[d->cmd].name, d->help ? d->help : d->def);
    }
}

/* "  --frames N   frames sampled along the path (default 60)" */
static void option_line(FILE *f, const sb_option *opt, const sb_command_def *table, const sb_command_def *cmd,
                        const char *extra) {
    char syn[64], text[640], def[256];
    sb_option_synopsis(opt, syn, sizeof syn);
    sb_option_default_text(opt, table, cmd, def, sizeof def);
    snprintf(text, sizeof text, "%s%s%s%s%s", opt->help, def[0] ? " (default " : "", def, def[0] ? ")" : "",
             extra ? extra : "");
    labelled(f, syn, text);
}

static void usage_lines(FILE *f, const sb_command_def *c) {
    for (const char *u = c->usage; *u;) {
        size_t w = strcspn(u, "\n");
        fprintf(f, "  shadowbench %.*s\n", (int)w, u);
        u += w + (u[w] == '\n');
    }
}

static const char *const operands = "SCENE: a .gltf/.glb file or a bundled scene (plane-box, desert, towers, "
                                    "overhangs, plane-box-lamp,\n"
                                    "       towers-night, street-lamps, movers, conf-*)\n"
                                    "PATH:  a .path file, a bundled path (same names), auto, orbit, or "
                                    "FILE.glb#camera=K\n"
                                    "SPEC:  technique[:param=value[,value...]]...  e.g. "
                                    "sm:res=1024,2048:filter=pcf3 (lists make a grid)\n";

/* ", run, batch, tune": the commands of the table that take a row ("" when every command does). */
static void takers(const sb_option *opt, const sb_command_def *table, char *out, size_t len) {
    out[0] = 0;
    if (opt->with & SB_CMDF_ANY) return;
    for (int c = 0; c < SB_CMD_COUNT; c++)
        if (sb_option_taken(opt, &table[c])) {
            size_t l = strlen(out);
            snprintf(out + l, len - l, "%s%s", l ? ", " : "; ", table[c].name);
        }
}

static void exit_statuses(FILE *f) {
    fprintf(f, "\nexit status (every command):\n");
    for (int i = 0; i < sb_exit_status_count; i++) {
        char label[32];
        snprintf(label, sizeof label, "%-4d %s", sb_exit_statuses[i].code, sb_exit_statuses[i].name);
        labelled(f, label, sb_exit_statuses[i].meaning);
    }
}

void sb_cli_help(FILE *f, const sb_command_def *table, const sb_command_def *cmd) {
    if (cmd) {
        fprintf(f, "usage:\n");
        usage_lines(f, cmd);
        fprintf(f, "\n%s\n\noptions:\n", cmd->summary);
        for (int i = 0; i < sb_option_count; i++)
            if (sb_option_taken(&sb_options[i], cmd)) option_line(f, &sb_options[i], table, cmd, NULL);
        return;
    }
    fprintf(f, "usage:\n");
    for (int c = 0; c < SB_CMD_COUNT; c++) usage_lines(f, &table[c]);
    fprintf(f, "\n%s\noptions (shadowbench COMMAND --help: the options of one command):\n", operands);
    for (int i = 0; i < sb_option_count; i++) {
        char cmds[300];
        takers(&sb_options[i], table, cmds, sizeof cmds);
        option_line(f, &sb_options[i], table, NULL, cmds);
    }
    fprintf(f, "\nenvironment:\n"
               "  SB_HISTORY=FILE        the history file (default out/history.sqlite)\n"
               "  SB_SCENE_CACHE=DIR|off where scenes read before are kept, flattened (default\n"
               "                         $XDG_CACHE_HOME or ~/.cache, shadowbench/scenes)\n");
    exit_statuses(f);
}

/* ---- a run's identity ---- */

/* A run option's value in a run's options (its row's field is an offset in sb_cli_opts). */
static const void *run_field(const sb_run_opts *o, size_t field) {
    return (const char *)o + (field - offsetof(sb_cli_opts, run));
}

static double as_double(const sb_option *opt, const sb_run_opts *o, size_t field) {
    const void *p = run_field(o, field);
    switch (opt->kind) {
    case SB_OPT_INT:
    case SB_OPT_CHOICE:
    case SB_OPT_SIZE: return *(const int *)p;
    case SB_OPT_SEED: return (double)*(const uint64_t *)p;
    case SB_OPT_FLAG: return *(const bool *)p;
    default: return *(const double *)p;
    }
}

/* A CHOICE row's name for the value it holds ("indirect"). */
static void choice_name(const sb_option *opt, int value, char *out, size_t len) {
    out[0] = 0;
    const char *c = opt->arg;
    for (int k = 0; *c; k++) {
        size_t w = strcspn(c, "|");
        if ((opt->values ? opt->values[k] : k) == value) snprintf(out, len, "%.*s", (int)w, c);
        c += w + (c[w] == '|');
    }
}

/* The hash's blocks, in order: the dimensions, what was given, what is not its default, the light, the texts given. Each block as
 * the ids of before each row joined it hashed it, so that every earlier run id holds. */
static uint64_t identity_blocks(uint64_t h, const sb_run_opts *o) {
    int dims[8] = {0}, ndims = 0;
    double light[8];
    int nlight = 0;
    bool light_on = false;
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        if (opt->identity == SB_ID_DIM) {
            dims[opt->id_slot] = *(const int *)run_field(o, opt->field);
            if (opt->field2) dims[opt->id_slot + 1] = *(const int *)run_field(o, opt->field2);
            ndims = ndims > opt->id_slot + 1 + (opt->field2 != 0) ? ndims : opt->id_slot + 1 + (opt->field2 != 0);
        } else if (opt->identity == SB_ID_LIGHT && nlight < 8) {
            light[nlight] = as_double(opt, o, opt->field);
            light_on |= opt->def && !strcmp(opt->def, "0") && light[nlight] != 0;
            nlight++;
        }
    }
    h = sb_fnv1a(h, dims, sizeof *dims * (size_t)ndims);
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        if (opt->identity == SB_ID_GIVEN && *(const bool *)run_field(o, opt->given_field)) {
            double v[2] = {as_double(opt, o, opt->field), opt->field2 ? as_double(opt, o, opt->field2) : 0};
            h = sb_fnv1a(h, v, sizeof *v * (opt->field2 ? 2 : 1));
        }
    }
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        char name[64], def[64];
        if (opt->identity != SB_ID_NAMED) continue;
        choice_name(opt, *(const int *)run_field(o, opt->field), name, sizeof name);
        snprintf(def, sizeof def, "%s", opt->def ? opt->def : "");
        if (strcmp(name, def)) h = sb_fnv1a(h, name, strlen(name) + 1);
    }
    if (light_on) h = sb_fnv1a(h, light, sizeof *light * (size_t)nlight);
    for (int i = 0; i < sb_option_count; i++) {   /* last: the ids of before hold */
        const sb_option *opt = &sb_options[i];
        const char *text = opt->identity == SB_ID_TEXT ? *(const char *const *)run_field(o, opt->field) : NULL;
        if (text) h = sb_fnv1a(sb_fnv1a(h, opt->name, strlen(opt->name) + 1), text, strlen(text) + 1);
    }
    return h;
}

void sb_run_id(uint64_t scene_hash, uint64_t path_hash, const sb_run_opts *o, const sb_run_spec *spec, char out[17]) {
    char params[SB_PARAMS_TEXT_LEN];
    sb_params_canonical(&spec->params, params, sizeof params);
    uint64_t h = SB_FNV_SEED;
    h = sb_fnv1a(h, &scene_hash, sizeof scene_hash);
    h = sb_fnv1a(h, &path_hash, sizeof path_hash);
    h = sb_fnv1a(h, spec->tech->name, strlen(spec->tech->name) + 1);
    h = sb_fnv1a(h, params, strlen(params) + 1);
    h = identity_blocks(h, o);
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

/* ---- a results set's identity ---- */

/* A row's value as text ("1280x720", "lamps", "auto"; "" for a text not given or a value given none), its fields
 * where at() finds them in o (an sb_cli_opts, or a run's sb_run_opts). */
static void value_at(const sb_option *opt, const void *o, const void *(*at)(const void *o, size_t field), char *out,
                     size_t len) {
    const void *p = at(o, opt->field);
    out[0] = 0;
    if (opt->given_field && !*(const bool *)at(o, opt->given_field)) return;   /* not given: none */
    switch (opt->kind) {
    case SB_OPT_FLAG: snprintf(out, len, "%s", *(const bool *)p ? "on" : "off"); break;
    case SB_OPT_INT:
        if (opt->can_auto && *(const int *)p < 0) snprintf(out, len, "auto");
        else snprintf(out, len, "%d", *(const int *)p);
        break;
    case SB_OPT_SEED: snprintf(out, len, "%llu", (unsigned long long)*(const uint64_t *)p); break;
    case SB_OPT_CHOICE: choice_name(opt, *(const int *)p, out, len); break;
    case SB_OPT_TEXT: snprintf(out, len, "%s", *(const char *const *)p ? *(const char *const *)p : ""); break;
    case SB_OPT_SIZE: snprintf(out, len, "%dx%d", *(const int *)p, *(const int *)at(o, opt->field2)); break;
    case SB_OPT_ANGLES: snprintf(out, len, "%.15g,%.15g", *(const double *)p, *(const double *)at(o, opt->field2)); break;
    default: snprintf(out, len, "%.15g", *(const double *)p);
    }
}

static const void *cli_at(const void *o, size_t field) { return (const char *)o + field; }
static const void *run_at(const void *o, size_t field) { return run_field(o, field); }
static void value_text(const sb_option *opt, const sb_cli_opts *o, char *out, size_t len) {
    value_at(opt, o, cli_at, out, len);
}

void sb_run_options_text(const sb_run_opts *o, char *out, size_t len) {
    out[0] = 0;
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        if (opt->id_column || (opt->identity != SB_ID_GIVEN && opt->identity != SB_ID_NAMED &&
                               opt->identity != SB_ID_TEXT))
            continue;
        char v[600];
        value_at(opt, o, run_at, v, sizeof v);
        if (!v[0] || (opt->identity == SB_ID_NAMED && opt->def && !strcmp(v, opt->def))) continue;   /* default */
        size_t n = strlen(out);
        snprintf(out + n, len - n, "%s%s %s", n ? " " : "", opt->name, v);
    }
}

void sb_cli_set_identity(const sb_cli_opts *o, const sb_command_def *cmd, const char *const *words, int nwords,
                         char *out, size_t len) {
    out[0] = 0;
    size_t used = 0;
    for (int i = 0; i < nwords && used < len; i++)
        used += (size_t)snprintf(out + used, len - used, "set: word %d %s\n", i + 1, words[i]);
    for (int i = 0; i < sb_option_count && used < len; i++) {
        const sb_option *opt = &sb_options[i];
        if (!opt->of_set || !sb_option_taken(opt, cmd)) continue;
        char v[512];
        value_text(opt, o, v, sizeof v);
        used += (size_t)snprintf(out + used, len - used, "set: %s %s\n", opt->name, v);
    }
}

/* The next line of a text after p (NULL at its end). */
static const char *next_line(const char *p) {
    const char *nl = strchr(p, '\n');
    return nl && nl[1] ? nl + 1 : NULL;
}

/* The "set: " line of `lines` whose key is key[0..keylen), its value into out; false if none. */
static bool set_line(const char *lines, const char *key, size_t keylen, char *out, size_t len) {
    for (const char *p = lines; p && *p; p = next_line(p)) {
        const char *k = p + 5;
        if (strncmp(p, "set: ", 5) || strncmp(k, key, keylen) || (k[keylen] != ' ' && k[keylen] != '\n' && k[keylen]))
            continue;
        const char *v = k[keylen] == ' ' ? k + keylen + 1 : k + keylen;
        snprintf(out, len, "%.*s", (int)strcspn(v, "\n"), v);
        return true;
    }
    return false;
}

bool sb_set_identity_differs(const char *was, const char *now, char *what, size_t len) {
    if (!strstr(was, "\nset: ")) return false;   /* a set from before its meta said what made it: its runs decide */
    /* every key of either side: a word the set had and this command lacks is a difference too */
    for (int side = 0; side < 2; side++)
        for (const char *p = side ? was : now; p && *p; p = next_line(p)) {
            if (strncmp(p, "set: ", 5)) continue;
            const char *k = p + 5;
            size_t keylen = !strncmp(k, "word ", 5) ? 5 + strcspn(k + 5, " \n") : strcspn(k, " \n");
            char a[1024] = "", b[1024] = "";
            bool had = set_line(was, k, keylen, a, sizeof a), has = set_line(now, k, keylen, b, sizeof b);
            if ((!had || !has) && !strncmp(k, "--", 2)) continue;   /* an option one side's shadowbench did not have */
            if (had && has && !strcmp(a, b)) continue;
            char key[64];
            snprintf(key, sizeof key, "%.*s", (int)keylen, k);
            bool word = !strncmp(key, "word ", 5);
            snprintf(what, len, "%s%s: the set was made with %s, this command gives %s", word ? "the command's " : "",
                     key, had && *a ? a : "none", has && *b ? b : "none");
            return true;
        }
    return false;
}

/* ---- the reference documents: docs/cli.md's and the man page's generated parts ---- */

/* Text as a markdown table cell ('|' escaped) or as roff ('-' as \-, '\' as \e, a leading '.' or '\'' guarded). */
static void doc_text(FILE *f, const char *text, sb_doc_format fmt) {
    if (fmt == SB_DOC_MAN && (text[0] == '.' || text[0] == '\'')) fputs("\\&", f);
    for (const char *p = text; *p; p++) {
        if (fmt == SB_DOC_MARKDOWN && *p == '|') fputs("\\|", f);
        else if (fmt == SB_DOC_MAN && *p == '-') fputs("\\-", f);
        else if (fmt == SB_DOC_MAN && *p == '\\') fputs("\\e", f);
        else fputc(*p, f);
    }
}

static void doc_synopsis(FILE *f, const sb_command_def *table, sb_doc_format fmt) {
    fputs(fmt == SB_DOC_MAN ? ".SH SYNOPSIS\n.nf\n" : "### Commands\n\n```\n", f);
    for (int c = 0; c < SB_CMD_COUNT; c++)
        for (const char *u = table[c].usage; *u;) {
            size_t w = strcspn(u, "\n");
            char line[512];
            snprintf(line, sizeof line, "shadowbench %.*s", (int)w, u);
            if (fmt == SB_DOC_MAN) doc_text(f, line, fmt);
            else fputs(line, f);
            fputc('\n', f);
            u += w + (u[w] == '\n');
        }
    fputs(fmt == SB_DOC_MAN ? ".fi\n" : "```\n\n| command | what it does |\n|---|---|\n", f);
    for (int c = 0; c < SB_CMD_COUNT && fmt == SB_DOC_MARKDOWN; c++) {
        fprintf(f, "| `%s` | ", table[c].name);
        doc_text(f, table[c].summary, fmt);
        fputs(" |\n", f);
    }
}

static void doc_options(FILE *f, const sb_command_def *table, sb_doc_format fmt) {
    fputs(fmt == SB_DOC_MAN ? ".SH OPTIONS\n" : "\n### Options\n\n| option | commands | default | meaning |\n|---|---|---|---|\n", f);
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        char syn[64], cmds[300], def[256];
        sb_option_synopsis(opt, syn, sizeof syn);
        takers(opt, table, cmds, sizeof cmds);
        sb_option_default_text(opt, table, NULL, def, sizeof def);
        const char *who = cmds[0] ? cmds + 2 : "every command";   /* takers() starts with "; " */
        if (fmt == SB_DOC_MARKDOWN) {
            fprintf(f, "| `");
            doc_text(f, syn, fmt);
            fprintf(f, "` | %s | ", who);
            doc_text(f, def, fmt);
            fputs(" | ", f);
            doc_text(f, opt->help, fmt);
            fputs(" |\n", f);
            continue;
        }
        fputs(".TP\n\\fB", f);
        doc_text(f, opt->name, fmt);
        fputs("\\fR", f);
        if (opt->arg) fputs(" \\fI", f), doc_text(f, opt->arg, fmt), fputs("\\fR", f);
        fputc('\n', f);
        doc_text(f, opt->help, fmt);
        fputs(def[0] ? " (default " : "", f);
        doc_text(f, def, fmt);
        fprintf(f, "%s; %s.\n", def[0] ? ")" : "", who);
    }
}

static void doc_exit(FILE *f, sb_doc_format fmt) {
    fputs(fmt == SB_DOC_MAN ? ".SH EXIT STATUS\nThe same for every command:\n"
                            : "\n### Exit status\n\nThe same for every command:\n\n| status | name | meaning |\n|---|---|---|\n",
          f);
    for (int i = 0; i < sb_exit_status_count; i++) {
        const sb_exit_status *e = &sb_exit_statuses[i];
        if (fmt == SB_DOC_MAN) fprintf(f, ".TP\n.B %d\n%s: ", e->code, e->name);
        else fprintf(f, "| %d | %s | ", e->code, e->name);
        doc_text(f, e->meaning, fmt);
        fputs(fmt == SB_DOC_MAN ? "\n" : " |\n", f);
    }
}

void sb_cli_doc(FILE *f, const sb_command_def *table, sb_doc_format fmt) {
    doc_synopsis(f, table, fmt);
    doc_options(f, table, fmt);
    doc_exit(f, fmt);
}
