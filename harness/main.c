/* main.c - the shadowbench command line. */
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "run.h"

#define SB_VERSION "0.1.0"

static void usage(FILE *f) {
    fprintf(f,
            "shadowbench " SB_VERSION " - headless benchmark harness for real-time shadow techniques\n"
            "\n"
            "usage:\n"
            "  shadowbench run SCENE PATH SPEC...     render each technique spec along the path, write CSV\n"
            "  shadowbench techniques                 list techniques and their parameters\n"
            "  shadowbench info                       backends, GL renderer and features\n"
            "  shadowbench path PATH [SCENE] [--frames N]   print the sampled cameras as CSV\n"
            "\n"
            "SCENE: a .gltf/.glb file or a bundled scene (plane-box, desert, towers, overhangs)\n"
            "PATH:  a .path file, a bundled path (same names), auto, orbit, or FILE.glb#camera=K\n"
            "SPEC:  technique[:param=value[,value...]]...  e.g. sm:res=1024,2048:filter=pcf3 (lists make a grid)\n"
            "\n"
            "options:\n"
            "  --backend egl|osmesa   GL context (default egl)\n"
            "  --timing auto|queries|sync   stage timing (default auto: sync on software rasterizers)\n"
            "  --ring N               timer-query ring depth in frames (default 3)\n"
            "  --frames N             frames sampled along the path (default 60)\n"
            "  --warmup N             warm-up frames, excluded (default 3)\n"
            "  --size WxH             render size (default 1280x720)\n"
            "  --sun AZ,EL            sun azimuth and elevation in degrees (overrides the scene's)\n"
            "  --error-every K        shadow error against the exact ray-cast reference on every K-th frame\n"
            "                         (default 10; 0 off), in an untimed pass after the timed frames\n"
            "  --images K             images of every K-th frame: colour, visibility, reference, error, cascades\n"
            "  --repeat K             run the path K times (default 1)\n"
            "  --target-ci PCT        repeat the path until the 95%% CI of mean gpu_ms is within PCT%% of it\n"
            "  --max-repeat N         at most N repetitions for --target-ci (default 10)\n"
            "  --threads N            reference ray-casting threads (default: all cores)\n"
            "  --out DIR              results folder (default results); each run command writes DIR/<UTC time>/\n"
            "  --progress             progress line on stderr (default when stderr is a terminal)\n"
            "  --quiet                no notices on stderr\n");
}

typedef struct cli {
    sb_run_opts opts;
    const char *out;
    const char *pos[256];
    int npos;
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
    c->out = "results";
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        long n;
        if (strncmp(a, "--", 2) != 0) {
            if (c->npos == 256) return bad("too many arguments%s", "");
            c->pos[c->npos++] = a;
            continue;
        }
        if (!strcmp(a, "--progress")) { c->opts.progress = true; continue; }
        if (!strcmp(a, "--quiet")) { sb_set_quiet(true); c->opts.progress = false; continue; }
        if (!v) return bad("%s needs a value", a);
        i++;
        if (!strcmp(a, "--backend")) {
            if (!sb_backend_parse(v, &c->opts.backend)) return bad("--backend %s: expected egl or osmesa", v);
        } else if (!strcmp(a, "--timing")) {
            if (!sb_timing_parse(v, &c->opts.timing)) return bad("--timing %s: expected auto, queries or sync", v);
        } else if (!strcmp(a, "--ring")) {
            if (!sb_parse_int(v, &n) || n < 1 || n > 16) return bad("--ring %s: expected 1..16", v);
            c->opts.ring = (int)n;
        } else if (!strcmp(a, "--frames")) {
            if (!sb_parse_int(v, &n) || n < 1 || n > 1000000) return bad("--frames %s: expected 1..1000000", v);
            c->opts.frames = (int)n;
        } else if (!strcmp(a, "--warmup")) {
            if (!sb_parse_int(v, &n) || n < 0 || n > 10000) return bad("--warmup %s: expected 0..10000", v);
            c->opts.warmup = (int)n;
        } else if (!strcmp(a, "--size")) {
            int w, h;
            char extra;
            if (sscanf(v, "%dx%d%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384)
                return bad("--size %s: expected WxH, e.g. 1280x720", v);
            c->opts.width = w;
            c->opts.height = h;
        } else if (!strcmp(a, "--sun")) {
            char buf[64];
            snprintf(buf, sizeof buf, "%s", v);
            char *comma = strchr(buf, ',');
            if (comma) *comma = 0;
            if (!comma || !sb_parse_double(buf, &c->opts.sun_az) || !sb_parse_double(comma + 1, &c->opts.sun_el) ||
                c->opts.sun_el < -90 || c->opts.sun_el > 90)
                return bad("--sun %s: expected AZIMUTH,ELEVATION in degrees (elevation -90..90)", v);
            c->opts.sun_override = true;
        } else if (!strcmp(a, "--images")) {
            if (!sb_parse_int(v, &n) || n < 0 || n > 1000000) return bad("--images %s: expected a frame interval >= 0", v);
            c->opts.images = (int)n;
        } else if (!strcmp(a, "--error-every")) {
            if (!sb_parse_int(v, &n) || n < 0 || n > 1000000) return bad("--error-every %s: expected a frame interval >= 0", v);
            c->opts.error_every = (int)n;
        } else if (!strcmp(a, "--repeat")) {
            if (!sb_parse_int(v, &n) || n < 1 || n > 1000) return bad("--repeat %s: expected 1..1000", v);
            c->opts.repeat = (int)n;
        } else if (!strcmp(a, "--target-ci")) {
            if (!sb_parse_double(v, &c->opts.target_ci) || c->opts.target_ci <= 0 || c->opts.target_ci > 100)
                return bad("--target-ci %s: expected a percentage in (0, 100]", v);
        } else if (!strcmp(a, "--max-repeat")) {
            if (!sb_parse_int(v, &n) || n < 1 || n > 1000) return bad("--max-repeat %s: expected 1..1000", v);
            c->opts.max_repeat = (int)n;
        } else if (!strcmp(a, "--threads")) {
            if (!sb_parse_int(v, &n) || n < 1 || n > 16) return bad("--threads %s: expected 1..16", v);
            c->opts.threads = (int)n;
        } else if (!strcmp(a, "--out")) {
            c->out = v;
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
                snprintf(range, sizeof range, "%s %g..%g", p->kind == SB_PARAM_INT ? "int" : "float", p->min, p->max);
                printf("  %-8s %-28s default %-6s %s\n", p->name, range, p->def, p->help);
            }
        }
    }
    return 0;
}

static int cmd_info(const cli *c) {
    char avail[1024];
    sb_backends_available(avail, sizeof avail);
    printf("shadowbench %s\nbackends available: %s\n", SB_VERSION, avail[0] ? avail : "none");
    sb_context ctx;
    sb_err err;
    if (!sb_context_create(&ctx, c->opts.backend, &err)) {
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
        if (!sb_scene_load(&scene, c->pos[1], &err)) {
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

static bool make_out_dir(const char *base, char *out, size_t len, sb_err *err) {
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    char stamp[32];
    strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
    for (int k = 0; k < 100; k++) {
        if (k == 0) snprintf(out, len, "%s/%s", base, stamp);
        else snprintf(out, len, "%s/%s-%d", base, stamp, k + 1);
        if (access(out, F_OK) != 0) return sb_mkdir_p(out, err);
    }
    return sb_fail(err, "%s: cannot find a free results folder name", base);
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
    if (!sb_session_open(&s, &c->opts, c->pos[0], c->pos[1], &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        free(runs);
        sb_context_destroy(&s.ctx);
        return 1;
    }
    char dir[4096], sum_path[4200];
    if (!make_out_dir(c->out, dir, sizeof dir, &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        sb_session_close(&s);
        free(runs);
        return 1;
    }
    sb_log("%s: %u triangles, %u draws, loaded in %.0f ms; renderer %s (%s timing)", s.scene.file,
           (unsigned)sb_scene_triangles(&s.scene), s.scene.draw_count, s.scene.load_ms, s.ctx.renderer,
           sb_timing_name(s.timing));
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    sb_summary sum;
    sb_summary_open(&sum, sum_path);
    for (int i = 0; i < nruns; i++) {
        sb_run_one(&s, &runs[i], dir, &sum, i, nruns);
        if (!sb_summary_flush(&sum, &err)) fprintf(stderr, "shadowbench: %s\n", err.msg);
    }
    printf("%s\n", dir);
    sb_log("%d run(s): %d ok, %d failed, %d skipped; results in %s", sum.count, sum.count - sum.failed - sum.skipped,
           sum.failed, sum.skipped, dir);
    int rc = sum.failed ? 1 : 0;
    sb_summary_free(&sum);
    sb_session_close(&s);
    free(runs);
    return rc;
}

int main(int argc, char **argv) {
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
    if (rc) return rc;
    const char *cmd = argv[1];
    if (!strcmp(cmd, "run")) return cmd_run(&c);
    if (!strcmp(cmd, "techniques")) return cmd_techniques();
    if (!strcmp(cmd, "info")) return cmd_info(&c);
    if (!strcmp(cmd, "path")) return cmd_path(&c);
    if (!strcmp(cmd, "batch") || !strcmp(cmd, "compare") || !strcmp(cmd, "merge") || !strcmp(cmd, "stress"))
        return bad("'%s' is not built yet", cmd);
    return bad("unknown command '%s' (see shadowbench --help)", cmd);
}
