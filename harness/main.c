/* main.c - the shadowbench command line. */
#include <math.h>
#include <stdlib.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <string.h>
#include <unistd.h>


#include "scene_load.h"
#include "batch.h"
#include "compare.h"
#include "history.h"
#include "site.h"
#include "report.h"
#include "run.h"
#include "stress.h"
#include "table.h"
#include "tune.h"
#include "version.h"


/* Results go here unless --out says otherwise: not a source folder. */
static const char *const default_out = "out";

static void usage(FILE *f) {
    fprintf(f,
            "shadowbench " SB_VERSION " - headless benchmark harness for real-time shadow techniques\n"
            "\n"
            "usage:\n"
            "  shadowbench run SCENE PATH SPEC... [--resume DIR]   render each technique spec along the path,\n"
            "                                         write CSV (--resume: keep DIR's complete runs, render the rest)\n"
            "  shadowbench batch FILE [--shard I/N] [--resume DIR] [--dry-run]   run a matrix from a batch file\n"
            "  shadowbench compare BASE NEW [--metric M,...] [--threshold PCT] [--format text|csv|markdown]\n"
            "                                         exit 1 when a metric regresses, 3 when none does but a\n"
            "                                         compared timing is UNSTABLE (a run marked stable=no)\n"
            "  shadowbench compare RESULTS --pair KEY=A,B   runs differing only in KEY\n"
            "  shadowbench merge DIR... --out DIR     merge shard outputs into one results set\n"
            "  shadowbench stress [CASE|all [SPEC...]]  numerical-stability battery (--frames N, --size WxH);\n"
            "                                         SPECs replace the battery's techniques\n"
            "  shadowbench tune SCENE [PATH] [SPEC...] --max-err E | --budget-ms B [--techniques LIST]\n"
            "                   [--time-limit D] [--seed N] [--resume DIR]\n"
            "                                         the cheapest settings within an error bound (or the most\n"
            "                                         accurate within a frame-time budget), by successive halving\n"
            "  shadowbench history add DIR...         keep results sets in the history (--history FILE, default\n"
            "                                         $SB_HISTORY or out/history.sqlite)\n"
            "  shadowbench history list               the nights in the history\n"
            "  shadowbench history regressions [--metric M,...] [--since DATE] [--recent N] [--noise-floor PCT]\n"
            "                                         changes across the nights per series; exit 1 when a\n"
            "                                         regression starts in the newest N nights (default 3)\n"
            "  shadowbench report [DIR | --history FILE] [--out SITE]   a static site to open in a browser\n"
            "                                         (default out/report)\n"
            "  shadowbench techniques                 list techniques and their parameters\n"
            "  shadowbench columns [--format csv|markdown]   the CSV columns (per frame and per run)\n"
            "  shadowbench info [SCENE]               backends, GL renderer and features; or what a scene holds\n"
            "  shadowbench path PATH [SCENE] [--frames N]   print the sampled cameras as CSV\n"
            "\n"
            "SCENE: a .gltf/.glb file or a bundled scene (plane-box, desert, towers, overhangs, plane-box-lamp,\n"
            "       towers-night)\n"
            "PATH:  a .path file, a bundled path (same names), auto, orbit, or FILE.glb#camera=K\n"
            "SPEC:  technique[:param=value[,value...]]...  e.g. sm:res=1024,2048:filter=pcf3 (lists make a grid)\n"
            "\n"
            "options:\n"
            "  --backend egl|osmesa   GL context (default egl)\n"
            "  --timing auto|queries|sync   stage timing (default auto: sync on software rasterizers)\n"
            "  --ring N               timer-query ring depth in frames (default 3)\n"
            "  --frames N             frames sampled along the path (default 60)\n"
            "  --warmup auto|N        warm-up frames, excluded (default auto: until the GPU's times and clocks settle)\n"
            "  --clocks auto|lock|free   lock the GPU clock for the invocation (NVML; auto: when permitted)\n"
            "  --size WxH             render size (default 1280x720)\n"
            "  --sun AZ,EL            sun azimuth and elevation in degrees (overrides the scene's)\n"
            "  --error-every K        shadow error against the exact ray-cast reference on every K-th frame\n"
            "                         (default 10; 0 off), in an untimed pass after the timed frames\n"
            "  --images K             images of every K-th frame: colour, visibility, reference, error, cascades\n"
            "  --repeat K             run the path K times (default 1)\n"
            "  --target-ci PCT        repeat the path until the 95%% CI of mean gpu_ms is within PCT%% of it\n"
            "  --max-repeat N         at most N repetitions for --target-ci (default 10)\n"
            "  --order matrix|interleave|shuffle   order of a scene's runs and repetitions (default matrix;\n"
            "                         interleave: A1 B1 A2 B2 ..., so slow drift hits every run alike)\n"
            "  --seed N               shuffle's seed (default: chosen, in the summary's seed column)\n"
            "  --threads N            reference ray-casting threads (default: all cores)\n"
            "  --overlap auto|on|off  cast the reference of evaluated frames in the background, at idle CPU\n"
            "                         priority, while timed frames render (auto: on a GPU, not on a CPU rasterizer)\n"
            "  --run-timeout S        a run taking longer is recorded as failed\n"
            "  --gpu-memory SIZE      GPU memory a run may allocate, e.g. 8G (default: what the GL reports\n"
            "                         free, or on a software rasterizer the system memory available)\n"
            "  --out DIR              results folder (default out); each run command writes DIR/<UTC time>/\n"
            "  --progress             progress line on stderr (default when stderr is a terminal)\n"
            "  --quiet                no notices on stderr\n"
            "  --verbose              also the notes a user cannot act on (e.g. a software rasterizer has no clock)\n"
            "  --allow-external-uris  let glTF buffers and images be read from outside the scene's folder\n"
            "  --blend-casters mask|opaque|none   glTF BLEND materials: alpha-tested at 0.5 (default), opaque, or left out\n"
            "  --pose T               nodes and skins at time T (seconds) of the file's first animation\n"
            "\nenvironment:\n"
            "  SB_HISTORY=FILE        the history file (default out/history.sqlite)\n"
            "  SB_SCENE_CACHE=DIR|off where scenes read before are kept, flattened (default\n"
            "                         $XDG_CACHE_HOME or ~/.cache, shadowbench/scenes)\n");
}

typedef struct cli {
    sb_run_opts opts;
    const char *out;
    const char **pos;
    int npos;
    const char **run_opts;      /* the run options as given, NAME VALUE pairs (batch: they beat defaults) */
    int nrun_opts;
    const char *resume, *shard, *metrics, *format, *pair, *techniques;
    const char *history, *since;    /* history and report: --history FILE, --since DATE */
    int recent;                     /* history regressions --recent N */
    double noise_floor;             /* history regressions --noise-floor PCT */
    double threshold, max_err, budget_ms, time_limit_s;
    bool dry_run;
    int argc;
    char **argv;
} cli;

static int bad(const char *fmt, const char *a) {
    fprintf(stderr, "shadowbench: ");
    fprintf(stderr, fmt, a);
    fputc('\n', stderr);
    return 2;
}

static int parse_cli(cli *c, int argc, char **argv) {
    sb_run_opts_defaults(&c->opts);
    c->opts.progress = isatty(2);
    c->out = default_out;
    c->threshold = 5;
    c->argc = argc;
    c->argv = argv;
    c->pos = sb_xcalloc((size_t)argc, sizeof *c->pos);           /* never more than the arguments */
    c->run_opts = sb_xcalloc((size_t)argc, sizeof *c->run_opts);
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strncmp(a, "--", 2) != 0) {
            c->pos[c->npos++] = a;
            continue;
        }
        if (!strcmp(a, "--progress")) { c->opts.progress = true; continue; }
        if (!strcmp(a, "--quiet")) { sb_set_quiet(true); c->opts.progress = false; continue; }
        if (!strcmp(a, "--verbose")) { sb_set_verbose(true); continue; }
        if (!strcmp(a, "--dry-run")) { c->dry_run = true; continue; }
        if (!strcmp(a, "--allow-external-uris")) { c->opts.allow_external_uris = true; continue; }
        if (!v) return bad("%s needs a value", a);
        i++;
        sb_err err;
        int rc = sb_run_opts_set(&c->opts, a, v, &err);
        if (rc < 0) return bad("%s", err.msg);
        if (rc > 0) {
            c->run_opts[c->nrun_opts++] = a;
            c->run_opts[c->nrun_opts++] = v;
            continue;
        }
        if (!strcmp(a, "--out")) {
            c->out = v;
        } else if (!strcmp(a, "--resume")) {
            c->resume = v;
        } else if (!strcmp(a, "--shard")) {
            c->shard = v;
        } else if (!strcmp(a, "--metric")) {
            c->metrics = v;
        } else if (!strcmp(a, "--format")) {
            c->format = v;
        } else if (!strcmp(a, "--pair")) {
            c->pair = v;
        } else if (!strcmp(a, "--history")) {
            c->history = v;
        } else if (!strcmp(a, "--since")) {
            c->since = v;
        } else if (!strcmp(a, "--recent")) {
            long n;
            if (!sb_parse_int(v, &n) || n < 1 || n > 10000) return bad("--recent %s: expected nights, 1..10000", v);
            c->recent = (int)n;
        } else if (!strcmp(a, "--noise-floor")) {
            if (!sb_parse_double(v, &c->noise_floor) || !(c->noise_floor > 0) || c->noise_floor > 100)
                return bad("--noise-floor %s: expected a percentage in (0, 100]", v);
        } else if (!strcmp(a, "--techniques")) {
            c->techniques = v;
        } else if (!strcmp(a, "--max-err")) {
            if (!sb_parse_double(v, &c->max_err) || !(c->max_err > 0) || c->max_err > 1)
                return bad("--max-err %s: expected an err_rate in (0, 1]", v);
        } else if (!strcmp(a, "--budget-ms")) {
            if (!sb_parse_double(v, &c->budget_ms) || !(c->budget_ms > 0) || isinf(c->budget_ms))
                return bad("--budget-ms %s: expected milliseconds > 0", v);
        } else if (!strcmp(a, "--time-limit")) {
            if (!sb_parse_duration(v, &c->time_limit_s) || c->time_limit_s <= 0)
                return bad("--time-limit %s: expected a duration such as 600, 90s, 10m or 1.5h", v);
        } else if (!strcmp(a, "--threshold")) {
            if (!sb_parse_double(v, &c->threshold) || c->threshold < 0)
                return bad("--threshold %s: expected a percentage >= 0", v);
        } else {
            return bad("unknown option %s (see shadowbench --help)", a);
        }
    }
    return 0;
}

static int cmd_techniques(void) {
    for (int i = 0; i < sb_technique_count(); i++) {
        const sb_technique *t = sb_technique_at(i);
        printf("%s - %s\n  stages:", t->name, t->summary);
        for (int s = 0; s < SB_STAGE_COUNT; s++)
            if (t->stages & SB_STAGE_BIT(s)) printf(" %s", sb_stage_names[s]);
        printf("\n");
        for (int k = 0; k < t->param_count; k++) {
            const sb_param_def *p = &t->params[k];
            if (p->kind == SB_PARAM_ENUM)
                printf("  %-8s %-28s default %-6s %s\n", p->name, p->choices, p->def, p->help);
            else {
                char range[64];
                snprintf(range, sizeof range, "%s %g..%g%s", p->kind == SB_PARAM_INT ? "int" : "float", p->min, p->max,
                         p->can_auto ? " or auto" : "");
                printf("  %-8s %-28s default %-6s %s\n", p->name, range, p->def, p->help);
            }
        }
    }
    return 0;
}

static int cmd_info(const cli *c) {
    if (c->npos > 1) return bad("usage: shadowbench info [SCENE]%s", "");
    if (c->npos == 1) { /* what a scene file holds and how it is drawn; no GL needed */
        sb_err err;
        sb_scene scene;
        sb_scene_opts so = sb_run_scene_opts(&c->opts);
        if (!sb_scene_load(&scene, c->pos[0], &so, &err)) {
            fprintf(stderr, "shadowbench: %s\n", err.msg);
            return 1;
        }
        sb_scene_info(&scene, stdout);
        sb_scene_free(&scene);
        return 0;
    }
    char avail[1024];
    sb_context ctx;
    sb_err err;
    bool have = sb_context_create(&ctx, c->opts.backend, &err);
    sb_backends_available(have ? &ctx : NULL, avail, sizeof avail);
    printf("shadowbench %s\nbackends available: %s\n", SB_VERSION, avail[0] ? avail : "none");
    if (!have) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        return 1;
    }
    printf("backend: %s (%s)\nGL vendor: %s\nGL renderer: %s\nGL version: %s\nsoftware rasterizer: %s\n",
           sb_backend_name(ctx.backend), ctx.device, ctx.vendor, ctx.renderer, ctx.version,
           ctx.software ? "yes" : "no");
    printf("timer queries: %s\ncompute shaders: %s\ngeometry shaders: %s\nlayered rendering from the vertex shader: %s\n",
           ctx.has_timer_query ? "yes" : "no", ctx.has_compute ? "yes" : "no", ctx.has_geometry ? "yes" : "no",
           ctx.has_vs_layer ? "yes" : "no");
    printf("default timing: %s\n", ctx.software ? "sync" : "queries");
    sb_context_destroy(&ctx);
    return 0;
}

static int cmd_path(const cli *c) {
    if (c->npos < 1 || c->npos > 2) return bad("usage: shadowbench path PATH [SCENE] [--frames N]%s", "");
    sb_err err;
    sb_scene scene;
    bool have_scene = false;
    if (c->npos == 2) {
        sb_scene_opts so = sb_run_scene_opts(&c->opts);
        if (!sb_scene_load(&scene, c->pos[1], &so, &err)) {
            fprintf(stderr, "shadowbench: %s\n", err.msg);
            return 1;
        }
        have_scene = true;
    }
    sb_path p;
    if (!sb_path_load(&p, c->pos[0], have_scene ? &scene : NULL, &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        if (have_scene) sb_scene_free(&scene);
        return 1;
    }
    printf("frame,progress,t,px,py,pz,qx,qy,qz,qw,fov,near,far\n");
    int n = c->opts.frames;
    double aspect = (double)c->opts.width / c->opts.height;
    for (int i = 0; i < n; i++) {
        sb_camera cam = sb_path_camera(&p, i, n, aspect, have_scene ? &scene : NULL);
        printf("%d,%.6g,%.6g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g\n", i, sb_path_progress(i, n),
               sb_path_progress(i, n) * sb_path_duration(&p), cam.pos.x, cam.pos.y, cam.pos.z, cam.rot.x, cam.rot.y,
               cam.rot.z, cam.rot.w, cam.fov_deg, cam.znear, cam.zfar);
    }
    sb_path_free(&p);
    if (have_scene) sb_scene_free(&scene);
    return 0;
}

static void command_line(const cli *c, char *out, size_t len) {
    out[0] = 0;
    for (int i = 0; i < c->argc; i++) {
        size_t l = strlen(out);
        snprintf(out + l, len - l, "%s%s", i ? " " : "", c->argv[i]);
    }
}

static int cmd_run(const cli *c) {
    if (c->npos < 3) return bad("usage: shadowbench run SCENE PATH SPEC... (see --help)%s", "");
    sb_err err;
    sb_run_spec *runs = NULL;
    int nruns = 0;
    for (int i = 2; i < c->npos; i++)
        if (!sb_spec_expand(c->pos[i], NULL, &runs, &nruns, &err)) {
            fprintf(stderr, "shadowbench: %s\n", err.msg);
            free(runs);
            return 2;
        }
    sb_session s;
    memset(&s, 0, sizeof s);
    sb_run_opts o = c->opts;
    sb_run_opts_finish(&o);
    if (!sb_session_open(&s, &o, c->pos[0], c->pos[1], &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        free(runs);
        sb_session_close(&s);
        return 1;
    }
    char dir[4096], sum_path[4200];
    if (c->resume) { /* the folder of an earlier run of the same command: its complete runs are kept */
        snprintf(dir, sizeof dir, "%s", c->resume);
        if (access(dir, W_OK) != 0) {
            fprintf(stderr, "shadowbench: --resume %s: no such results folder\n", c->resume);
            sb_session_close(&s);
            free(runs);
            return 2;
        }
    }
    if ((!c->resume && !sb_make_stamped_dir(c->out, dir, sizeof dir, &err)) || !sb_report_write_columns(dir, &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        sb_session_close(&s);
        free(runs);
        return 1;
    }
    char cmdline[2048];
    command_line(c, cmdline, sizeof cmdline);
    if (!sb_session_write_meta(&s, dir, cmdline, SB_VERSION, SB_GIT_COMMIT, NULL, &err))
        fprintf(stderr, "shadowbench: %s\n", err.msg);
    sb_session_keep_reference(&s, dir);
    char parts[256];
    sb_scene_load_parts(&s.scene, parts, sizeof parts);
    sb_log("%s: %u triangles, %u draws, loaded in %.0f ms (%s), GPU upload %.0f ms; renderer %s (%s timing)",
           s.scene.file, (unsigned)sb_scene_triangles(&s.scene), s.scene.draw_count, s.scene.load_ms, parts,
           s.gpu_upload_ms, s.ctx.renderer, sb_timing_name(s.timing));
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    sb_summary sum;
    sb_summary_open(&sum, sum_path);
    const sb_run_spec **specs = sb_xmalloc(sizeof *specs * (size_t)nruns);
    int *index = sb_xmalloc(sizeof *index * (size_t)nruns), todo = 0;
    bool *done = sb_xcalloc((size_t)nruns, 1);
    if (c->resume) {
        char (*idbuf)[17] = sb_xmalloc(sizeof *idbuf * (size_t)nruns);
        const char **ids = sb_xmalloc(sizeof *ids * (size_t)nruns);
        for (int i = 0; i < nruns; i++) sb_session_run_id(&s, &runs[i], idbuf[i]), ids[i] = idbuf[i];
        int kept = sb_summary_keep_complete(&sum, dir, ids, nruns, done);
        sb_log("resuming %s: %d run(s) complete, %d to do", dir, kept, nruns - kept);
        free(ids);
        free(idbuf);
    }
    for (int i = 0; i < nruns; i++)
        if (!done[i]) specs[todo] = &runs[i], index[todo++] = i;
    sb_run_group(&s, specs, index, todo, dir, &sum, 0, todo);
    if (!sb_summary_flush(&sum, &err)) fprintf(stderr, "shadowbench: %s\n", err.msg);
    free(specs);
    free(index);
    free(done);
    printf("%s\n", dir);
    int rc = sb_summary_conclude(&sum, dir, "the same command with");
    sb_summary_free(&sum);
    sb_session_close(&s);
    free(runs);
    return rc;
}

/* ---- tune ---- */

static bool given(const cli *c, const char *name) {
    for (int i = 0; i < c->nrun_opts; i += 2)
        if (!strcmp(c->run_opts[i], name)) return true;
    return false;
}

static int cmd_tune(const cli *c) {
    if (c->npos < 1)
        return bad("usage: shadowbench tune SCENE [PATH] [SPEC...] --max-err E | --budget-ms B%s", "");
    sb_run_opts o = c->opts;
    /* tune's own defaults: the full measurement is 33 frames (rungs of 3, 9 and 33 share their cameras), one
       warm-up frame a run, the error of every frame, and a fixed plan */
    if (!given(c, "--frames")) o.frames = 33;
    if (!given(c, "--warmup")) o.warmup = 1;
    if (!given(c, "--error-every")) o.error_every = 1;
    if (!given(c, "--seed")) o.seed = 1;
    o.order = SB_ORDER_SHUFFLE;   /* the summary's seed column records the plan's seed */
    sb_run_opts_finish(&o);
    /* the second word is the path unless it names a technique */
    int first_spec = 1;
    const char *path = NULL;
    if (c->npos > 1) {
        char name[64];
        snprintf(name, sizeof name, "%.*s", (int)strcspn(c->pos[1], ":"), c->pos[1]);
        if (!sb_technique_find(name)) path = c->pos[1], first_spec = 2;
    }
    sb_tune_cmd cmd = {.scene = c->pos[0], .path = path, .specs = c->pos + first_spec, .nspecs = c->npos - first_spec,
                       .techniques = c->techniques, .max_err = c->max_err, .budget_ms = c->budget_ms,
                       .time_limit_s = c->time_limit_s, .opts = &o, .out = c->out, .resume = c->resume};
    if (cmd.nspecs && cmd.techniques) return bad("tune: give SPECs or --techniques, not both%s", "");
    return sb_tune_main(&cmd);
}

/* ---- batch ---- */

static int cmd_batch(const cli *c) {
    if (c->npos != 1) return bad("usage: shadowbench batch FILE [--shard I/N] [--resume DIR] [--dry-run]%s", "");
    char cmdline[2048];
    command_line(c, cmdline, sizeof cmdline);
    sb_run_opts base;
    sb_run_opts_defaults(&base);
    base.progress = c->opts.progress;
    base.allow_external_uris = c->opts.allow_external_uris;
    sb_batch_cmd cmd = {.file = c->pos[0], .base = &base, .cli_opts = c->run_opts, .ncli = c->nrun_opts,
                        .out = c->out, .resume = c->resume, .shard = c->shard, .dry_run = c->dry_run,
                        .command_line = cmdline, .version = SB_VERSION, .commit = SB_GIT_COMMIT};
    return sb_batch_main(&cmd);
}

static int cmd_columns(const cli *c) {
    if (c->format && !strcmp(c->format, "markdown")) {
        sb_report_columns_markdown(stdout);
        return 0;
    }
    if (c->format && strcmp(c->format, "csv")) return bad("columns: --format %s: expected csv or markdown", c->format);
    sb_csv csv = {0};
    sb_report_columns(&csv);
    fputs(csv.buf, stdout);
    sb_csv_free(&csv);
    return 0;
}

/* ---- stress ---- */

static int cmd_stress(const cli *c) {
    sb_run_opts o = c->opts;
    bool frames_given = false, size_given = false;
    for (int i = 0; i < c->nrun_opts; i += 2) {
        frames_given |= !strcmp(c->run_opts[i], "--frames");
        size_given |= !strcmp(c->run_opts[i], "--size");
    }
    if (!frames_given) o.frames = 3;
    if (!size_given) {
        o.width = 320;
        o.height = 180;
    }
    o.warmup = 0;
    sb_err err;
    const char *only = c->npos && strcmp(c->pos[0], "all") ? c->pos[0] : NULL;   /* "all": every case */
    int failures = sb_stress_run(&o, only, c->npos > 1 ? c->pos + 1 : NULL, c->npos > 1 ? c->npos - 1 : 0, stdout, &err);
    if (failures < 0) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        return 2;
    }
    if (sb_interrupted()) return 128 + sb_interrupted();
    return failures ? 1 : 0;
}

/* ---- compare and merge ---- */

static int cmd_compare(const cli *c) {
    sb_compare_opts o;
    memset(&o, 0, sizeof o);
    o.threshold_pct = c->threshold;
    o.pair = c->pair;
    char metrics[1024];
    if (c->metrics) {
        snprintf(metrics, sizeof metrics, "%s", c->metrics);
        for (char *t = strtok(metrics, ","); t && o.nmetrics < 32; t = strtok(NULL, ",")) o.metrics[o.nmetrics++] = t;
    }
    if (c->format) {
        if (!strcmp(c->format, "text")) o.format = SB_FORMAT_TEXT;
        else if (!strcmp(c->format, "csv")) o.format = SB_FORMAT_CSV;
        else if (!strcmp(c->format, "markdown")) o.format = SB_FORMAT_MARKDOWN;
        else return bad("--format %s: expected text, csv or markdown", c->format);
    }
    sb_err err;
    if (c->pair) {
        if (c->npos != 1) return bad("usage: shadowbench compare RESULTS --pair KEY=A,B%s", "");
        int n = sb_compare_pairs(c->pos[0], &o, stdout, &err);
        if (n < 0) {
            fprintf(stderr, "shadowbench: %s\n", err.msg);
            return 2;
        }
        return 0;
    }
    if (c->npos != 2) return bad("usage: shadowbench compare BASE NEW [--metric M,...] [--threshold PCT]%s", "");
    int unstable = 0;
    int n = sb_compare(c->pos[0], c->pos[1], &o, stdout, &unstable, &err);
    if (n < 0) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        return 2;
    }
    return n > 0 ? 1 : unstable > 0 ? 3 : 0; /* 3: nothing regressed, but some timings cannot be trusted */
}

static int cmd_merge(const cli *c) {
    if (c->npos < 1 || c->out == default_out)
        return bad("usage: shadowbench merge DIR... --out MERGED_DIR%s", "");
    sb_err err;
    if (!sb_merge(c->pos, c->npos, c->out, &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        return 1;
    }
    printf("%s\n", c->out);
    return 0;
}

/* ---- history and report ---- */

static const char *history_path(const cli *c, char *buf, size_t len) {
    return c->history ? c->history : sb_history_default_path(default_out, buf, len);
}

static int split_metrics(const char *list, char *buf, size_t len, const char **out, int max) {
    int n = 0;
    snprintf(buf, len, "%s", list);
    for (char *t = strtok(buf, ","); t && n < max; t = strtok(NULL, ",")) out[n++] = t;
    return n;
}

static int cmd_history(const cli *c) {
    static const char *const usage_text =
        "usage: shadowbench history add DIR... | list | regressions [--metric M,...] [--since DATE] [--recent N]\n"
        "       [--noise-floor PCT] [--format text|csv]   (the file: --history FILE, $SB_HISTORY or out/history.sqlite)";
    if (c->npos < 1) return bad("%s", usage_text);
    char pbuf[4096];
    const char *path = history_path(c, pbuf, sizeof pbuf);
    const char *sub = c->pos[0];
    sb_err err;
    if (!strcmp(sub, "add")) {
        if (c->npos < 2) return bad("%s", usage_text);
        sb_history *h = sb_history_open(path, true, &err);
        if (!h) {
            fprintf(stderr, "shadowbench: %s\n", err.msg);
            return 1;
        }
        int rc = 0;
        for (int i = 1; i < c->npos; i++) {
            sb_history_added a;
            double t0 = sb_now_ms();
            if (!sb_history_add(h, c->pos[i], &a, &err)) {
                fprintf(stderr, "shadowbench: %s\n", err.msg);
                rc = 1;
                continue;
            }
            if (a.existed) sb_log("%s: already in %s as night %lld; nothing changed", c->pos[i], path, a.night);
            else
                sb_log("%s: night %lld in %s (%d runs, %d per-frame files, %.0f ms)", c->pos[i], a.night, path, a.runs,
                       a.frames_files, sb_now_ms() - t0);
        }
        sb_history_close(h);
        return rc;
    }
    if (c->npos != 1) return bad("%s", usage_text);
    sb_history *h = sb_history_open(path, false, &err);
    if (!h) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        return 2;
    }
    int rc = 0;
    if (!strcmp(sub, "list")) {
        if (!sb_history_list(h, stdout, &err)) fprintf(stderr, "shadowbench: %s\n", err.msg), rc = 2;
    } else if (!strcmp(sub, "regressions")) {
        int format = SB_FORMAT_TEXT;
        if (c->format && !strcmp(c->format, "csv")) format = SB_FORMAT_CSV;
        else if (c->format && strcmp(c->format, "text")) rc = bad("history regressions: --format %s: expected text or csv", c->format);
        sb_history_query q = {.since = c->since, .recent = c->recent, .noise_floor_pct = c->noise_floor};
        char mbuf[1024];
        if (c->metrics) q.nmetrics = split_metrics(c->metrics, mbuf, sizeof mbuf, q.metrics, 32);
        sb_history_change *ch = NULL;
        int n = rc ? 0 : sb_history_changes(h, &q, &ch, &err);
        if (n < 0) {
            fprintf(stderr, "shadowbench: %s\n", err.msg);
            rc = 2;
        } else if (!rc) {
            int recent = 0, regressions = 0;
            for (int i = 0; i < n; i++) regressions += ch[i].regression, recent += ch[i].regression && ch[i].recent;
            sb_history_print_changes(ch, n, format, stdout);
            sb_log("%d change(s), %d regression(s), %d starting in the newest %d night(s)", n, regressions, recent,
                   q.recent ? q.recent : 3);
            rc = recent > 0 ? 1 : 0;
        }
        free(ch);
    } else {
        rc = bad("%s", usage_text);
    }
    sb_history_close(h);
    return rc;
}

static int cmd_report(const cli *c) {
    if (c->npos > 1 || (c->npos == 1 && c->history))
        return bad("usage: shadowbench report [DIR | --history FILE] [--out SITE]%s", "");
    char pbuf[4096], obuf[4200];
    const char *site = c->out;
    if (site == default_out) snprintf(obuf, sizeof obuf, "%s/report", default_out), site = obuf;
    sb_site_opts so = {.dir = c->npos == 1 ? c->pos[0] : NULL, .out = site, .recent = c->recent};
    if (!so.dir) so.history = history_path(c, pbuf, sizeof pbuf);
    sb_err err;
    if (!sb_site_write(&so, &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        return 1;
    }
    printf("%s/index.html\n", site);
    return 0;
}

static int dispatch(const cli *c, const char *cmd) {
    if (!strcmp(cmd, "run")) return cmd_run(c);
    if (!strcmp(cmd, "techniques")) return cmd_techniques();
    if (!strcmp(cmd, "columns")) return cmd_columns(c);
    if (!strcmp(cmd, "info")) return cmd_info(c);
    if (!strcmp(cmd, "path")) return cmd_path(c);
    if (!strcmp(cmd, "batch")) return cmd_batch(c);
    if (!strcmp(cmd, "compare")) return cmd_compare(c);
    if (!strcmp(cmd, "merge")) return cmd_merge(c);
    if (!strcmp(cmd, "stress")) return cmd_stress(c);
    if (!strcmp(cmd, "tune")) return cmd_tune(c);
    if (!strcmp(cmd, "history")) return cmd_history(c);
    if (!strcmp(cmd, "report")) return cmd_report(c);
    return bad("unknown command '%s' (see shadowbench --help)", cmd);
}

/* glibc gives the top of the heap back to the system whenever more than
 * M_TRIM_THRESHOLD is free there (128 KiB until the first large block mmap'd
 * is freed, which raises it). A software rasterizer mallocs and frees its
 * per-frame buffers, so until that first free (in practice, until the first
 * run of the process ends) every frame gave pages back and faulted them in
 * again inside the timed work: the first run of a process measured 1.3-1.4x
 * the identical runs after it (llvmpipe, towers, 640x360). Keeping the heap's
 * top removes that. Setting it also stops glibc raising the mmap threshold
 * as large blocks are freed, so every block of 128 KiB or more (the
 * evaluation's per-frame arrays: 26 MB of reference points at 1280x720) was
 * a fresh mmap whose pages faulted in on first touch, each frame again: with
 * blocks under 256 MiB taken from the heap and reused, an evaluated frame
 * whose reference is reused costs 22 ms instead of 100 (towers, 1280x720). */
static void keep_heap_top(void) {
#ifdef __GLIBC__
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
#endif
}

int main(int argc, char **argv) {
    keep_heap_top();
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("shadowbench %s\n", SB_VERSION);
        return 0;
    }
    cli c;
    memset(&c, 0, sizeof c);
    int rc = parse_cli(&c, argc, argv);
    if (!rc && (!strcmp(argv[1], "run") || !strcmp(argv[1], "batch") || !strcmp(argv[1], "tune") ||
                !strcmp(argv[1], "stress")))
        sb_interrupt_install();
    if (!rc) rc = dispatch(&c, argv[1]);
    if (rc != 2 && sb_result_writes_failed()) {   /* a cron job must not read a lost row as success */
        fprintf(stderr, "shadowbench: results could not all be written (the files are named above): exit status %d\n",
                SB_EXIT_WRITE);
        rc = SB_EXIT_WRITE;
    }
    free(c.pos);
    free(c.run_opts);
    return rc;
}
