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
#include "bisect.h"
#include "history.h"
#include "site.h"
#include "columns.h"
#include "run.h"
#include "stress.h"
#include "table.h"
#include "tune.h"
#include "options.h"
#include "pathcheck.h"
#include "version.h"


/* The history's default folder when --history and $SB_HISTORY do not say (not a source folder). */
static const char *const default_out = "out";

typedef struct cli {
    sb_cli_opts o;              /* every option, parsed once (options.h) */
    sb_command cmd;
    const char **pos;           /* the words that are not options, in order */
    int npos;
    int argc;
    char **argv;
    char **tail;                /* bisect: the words after "--" */
    int ntail;
} cli;

/* Bad input: one line, exit 2. */
static int bad(const char *fmt, const char *a) {
    fprintf(stderr, "shadowbench: ");
    fprintf(stderr, fmt, a);
    fputc('\n', stderr);
    return SB_EXIT_BAD_INPUT;
}

/* A command's usage, as bad input: "usage: shadowbench run SCENE PATH SPEC... (see shadowbench run --help)". */
static int bad_usage(const cli *c) {
    const char *u = sb_commands[c->cmd].usage;
    fprintf(stderr, "shadowbench: usage: shadowbench %.*s (see shadowbench %s --help)\n", (int)strcspn(u, "\n"), u,
            sb_commands[c->cmd].name);
    return SB_EXIT_BAD_INPUT;
}

/* A file the command was given could not be used: one line, exit 2 (4 when
 * what failed was writing a result, which sb_result_writes_failed knows). */
static int bad_file(const sb_err *err) {
    fprintf(stderr, "shadowbench: %s\n", err->msg);
    return sb_result_writes_failed() ? SB_EXIT_WRITE : SB_EXIT_BAD_INPUT;
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
    if (c->npos > 1) return bad_usage(c);
    if (c->npos == 1) { /* what a scene file holds and how it is drawn; no GL needed */
        sb_err err;
        sb_scene scene;
        sb_scene_opts so = sb_run_scene_opts(&c->o.run);
        if (!sb_scene_load(&scene, c->pos[0], &so, &err)) return bad_file(&err);
        sb_scene_info(&scene, stdout);
        printf("memory: CPU %.1f MiB (the scene's arrays, the reference's BVH not counted), GPU %.1f MiB (its "
               "buffers; a run adds its render targets and shadow maps)\n",
               sb_scene_cpu_bytes(&scene) / 1048576.0, sb_gpu_scene_bytes(&scene) / 1048576.0);
        sb_scene_free(&scene);
        return 0;
    }
    char avail[1024];
    sb_context ctx;
    sb_err err;
    bool have = sb_context_create(&ctx, c->o.run.backend, &err);
    sb_backends_available(have ? &ctx : NULL, avail, sizeof avail);
    printf("shadowbench %s\nbackends available: %s\n", SB_VERSION, avail[0] ? avail : "none");
    if (!have) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        return SB_EXIT_FAILED;
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
    if (c->npos < 1 || c->npos > 2) return bad_usage(c);
    sb_err err;
    sb_scene scene;
    bool have_scene = false;
    if (c->npos == 2) {
        sb_scene_opts so = sb_run_scene_opts(&c->o.run);
        if (!sb_scene_load(&scene, c->pos[1], &so, &err)) return bad_file(&err);
        have_scene = true;
    }
    sb_path p;
    if (!sb_path_load(&p, c->pos[0], have_scene ? &scene : NULL, &err)) {
        if (have_scene) sb_scene_free(&scene);
        return bad_file(&err);
    }
    int n = c->o.run.frames;
    double aspect = (double)c->o.run.width / c->o.run.height;
    /* with a scene: each camera checked against it (pathcheck.h) */
    sb_path_frame *check = NULL;
    int flagged = 0;
    char text[2048] = "";   /* the flagged frames */
    if (have_scene) {
        sb_reference ref;
        if (!sb_reference_build(&ref, &scene, &err)) {
            fprintf(stderr, "shadowbench: %s\n", err.msg);
            sb_path_free(&p);
            sb_scene_free(&scene);
            return SB_EXIT_FAILED;
        }
        check = sb_xmalloc(sizeof *check * (size_t)n);
        double t0 = sb_now_ms();
        flagged = sb_path_check(&ref, &scene, &p, n, aspect, check, c->o.run.threads);
        sb_verbose("path check: %d frame(s) in %.1f ms (the reference built in %.0f ms)", n, sb_now_ms() - t0,
                   ref.build_ms);
        sb_reference_free(&ref);
        sb_path_check_text(check, n, text, sizeof text);
    }
    if (flagged && c->o.run.strict_path) {   /* refused: the one-line error, no table */
        fprintf(stderr, "shadowbench: %s: %s (--strict-path)\n", c->pos[0], text);
        free(check);
        sb_path_free(&p);
        sb_scene_free(&scene);
        return SB_EXIT_BAD_INPUT;
    }
    printf("frame,progress,t,px,py,pz,qx,qy,qz,qw,fov,near,far%s\n", check ? ",verdict,node" : "");
    for (int i = 0; i < n; i++) {
        sb_camera cam = sb_path_camera(&p, i, n, aspect, have_scene ? &scene : NULL);
        printf("%d,%.6g,%.6g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g", i, sb_path_progress(i, n),
               sb_path_progress(i, n) * sb_path_duration(&p), cam.pos.x, cam.pos.y, cam.pos.z, cam.rot.x, cam.rot.y,
               cam.rot.z, cam.rot.w, cam.fov_deg, cam.znear, cam.zfar);
        if (check) {
            printf(",%s,", sb_path_verdict_names[check[i].verdict]);
            if (check[i].node >= 0) printf("%lld", (long long)check[i].node);
        }
        printf("\n");
    }
    if (flagged) fprintf(stderr, "shadowbench: %s along %s: %s\n", c->pos[1], c->pos[0], text);   /* as a run says it */
    free(check);
    sb_path_free(&p);
    if (have_scene) sb_scene_free(&scene);
    return SB_EXIT_OK;
}

static void command_line(const cli *c, char *out, size_t len) {
    out[0] = 0;
    for (int i = 0; i < c->argc; i++) {
        size_t l = strlen(out);
        snprintf(out + l, len - l, "%s%s", i ? " " : "", c->argv[i]);
    }
}

static int cmd_run(const cli *c) {
    if (c->npos < 3) return bad_usage(c);
    sb_err err;
    sb_run_spec *runs = NULL;
    int nruns = 0;
    for (int i = 2; i < c->npos; i++)
        if (!sb_spec_expand(c->pos[i], NULL, &runs, &nruns, &err)) {
            free(runs);
            return bad_file(&err);
        }
    sb_session s;
    memset(&s, 0, sizeof s);
    sb_run_opts o = c->o.run;
    sb_run_opts_finish(&o);
    if (!sb_session_open(&s, &o, c->pos[0], c->pos[1], &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        free(runs);
        int rc = s.files_refused ? SB_EXIT_BAD_INPUT : SB_EXIT_FAILED;
        sb_session_close(&s);
        return rc;
    }
    char dir[4096], sum_path[4200];
    if (c->o.resume) { /* the folder of an earlier run of the same command: its complete runs are kept */
        snprintf(dir, sizeof dir, "%s", c->o.resume);
        if (access(dir, W_OK) != 0) {
            fprintf(stderr, "shadowbench: --resume %s: no such results folder\n", c->o.resume);
            sb_session_close(&s);
            free(runs);
            return SB_EXIT_BAD_INPUT;
        }
    }
    if ((!c->o.resume && !sb_make_stamped_dir(c->o.out, dir, sizeof dir, &err)) || !sb_columns_write(dir, &err)) {
        fprintf(stderr, "shadowbench: %s\n", err.msg);
        sb_session_close(&s);
        free(runs);
        return SB_EXIT_WRITE;   /* the results folder could not be made */
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
    if (c->o.resume) {
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

static int cmd_tune(const cli *c) {
    if (c->npos < 1) return bad_usage(c);
    sb_run_opts o = c->o.run;
    /* tune's own defaults: the full measurement is 33 frames (rungs of 3, 9 and 33 share their cameras), one
       warm-up frame a run, the error of every frame, and a fixed plan */
    if (!sb_cli_given(&c->o, "--frames")) o.frames = 33;
    if (!sb_cli_given(&c->o, "--warmup")) o.warmup = 1;
    if (!sb_cli_given(&c->o, "--error-every")) o.error_every = 1;
    if (!sb_cli_given(&c->o, "--flicker-dt") && c->o.max_flicker <= 0) o.flicker_dt = 0;   /* no flicker bound: no twins */
    if (!sb_cli_given(&c->o, "--seed")) o.seed = 1;
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
                       .techniques = c->o.techniques, .max_err = c->o.max_err, .max_flicker = c->o.max_flicker, .max_mb = c->o.max_mb, .budget_ms = c->o.budget_ms,
                       .time_limit_s = c->o.time_limit_s, .opts = &o, .out = c->o.out, .resume = c->o.resume};
    if (cmd.nspecs && cmd.techniques) return bad("tune: give SPECs or --techniques, not both%s", "");
    return sb_tune_main(&cmd);
}

/* ---- batch ---- */

static int cmd_batch(const cli *c) {
    if (c->npos != 1) return bad_usage(c);
    char cmdline[2048];
    command_line(c, cmdline, sizeof cmdline);
    sb_run_opts base;
    sb_run_opts_defaults(&base);
    base.progress = c->o.run.progress;
    base.allow_external_uris = c->o.run.allow_external_uris;
    sb_batch_cmd cmd = {.file = c->pos[0], .base = &base, .cli = &c->o,
                        .out = c->o.out, .resume = c->o.resume, .shard = c->o.shard, .dry_run = c->o.dry_run,
                        .command_line = cmdline, .version = SB_VERSION, .commit = SB_GIT_COMMIT};
    return sb_batch_main(&cmd);
}

static int cmd_columns(const cli *c) {
    if (c->npos) return bad_usage(c);
    if (c->o.format == SB_OUTPUT_MARKDOWN) {
        sb_columns_markdown(stdout);
        return 0;
    }
    sb_csv csv = {0};
    sb_columns_csv(&csv);
    fputs(csv.buf, stdout);
    sb_csv_free(&csv);
    return 0;
}

/* ---- stress ---- */

static int cmd_stress(const cli *c) {
    sb_run_opts o = c->o.run;
    if (!sb_cli_given(&c->o, "--frames")) o.frames = 3;
    if (!sb_cli_given(&c->o, "--size")) {
        o.width = 320;
        o.height = 180;
    }
    o.warmup = 0;
    sb_err err;
    const char *only = c->npos && strcmp(c->pos[0], "all") ? c->pos[0] : NULL;   /* "all": every case */
    int failures = sb_stress_run(&o, only, c->npos > 1 ? c->pos + 1 : NULL, c->npos > 1 ? c->npos - 1 : 0, stdout, &err);
    if (failures < 0) return bad_file(&err);
    if (sb_interrupted()) return SB_EXIT_SIGNAL + sb_interrupted();
    return failures ? SB_EXIT_FAILED : SB_EXIT_OK;
}

/* ---- compare and merge ---- */

/* --metric M,...: the names, pointing into buf. */
static int split_metrics(const char *list, char *buf, size_t len, const char **out, int max) {
    int n = 0;
    snprintf(buf, len, "%s", list);
    for (char *t = strtok(buf, ","); t && n < max; t = strtok(NULL, ",")) out[n++] = t;
    return n;
}

static int cmd_compare(const cli *c) {
    sb_compare_opts o;
    memset(&o, 0, sizeof o);
    o.threshold_pct = c->o.threshold;
    o.pair = c->o.pair;
    char metrics[1024];
    if (c->o.metrics) o.nmetrics = split_metrics(c->o.metrics, metrics, sizeof metrics, o.metrics, 32);
    o.format = c->o.format;
    sb_err err;
    if (c->o.pair) {
        if (c->npos != 1) return bad("usage: shadowbench compare RESULTS --pair KEY=A,B%s", "");
        return sb_compare_pairs(c->pos[0], &o, stdout, &err) < 0 ? bad_file(&err) : SB_EXIT_OK;
    }
    if (c->npos != 2) return bad_usage(c);
    int unstable = 0;
    int n = sb_compare(c->pos[0], c->pos[1], &o, stdout, &unstable, &err);
    if (n < 0) return bad_file(&err);
    return n > 0 ? SB_EXIT_FAILED : unstable > 0 ? SB_EXIT_UNSTABLE : SB_EXIT_OK;
}

static int cmd_merge(const cli *c) {
    if (c->npos < 1 || !sb_cli_given(&c->o, "--out")) return bad_usage(c);
    sb_err err;
    if (!sb_merge(c->pos, c->npos, c->o.out, &err)) return bad_file(&err);
    printf("%s\n", c->o.out);
    return 0;
}

/* ---- history and report ---- */

static const char *history_path(const cli *c, char *buf, size_t len) {
    return c->o.history ? c->o.history : sb_history_default_path(default_out, buf, len);
}

static int cmd_history(const cli *c) {
    if (c->npos < 1) return bad_usage(c);
    char pbuf[4096];
    const char *path = history_path(c, pbuf, sizeof pbuf);
    const char *sub = c->pos[0];
    sb_err err;
    if (!strcmp(sub, "add")) {
        if (c->npos < 2) return bad_usage(c);
        sb_history *h = sb_history_open(path, true, &err);
        if (!h) return bad_file(&err);
        int rc = SB_EXIT_OK;
        for (int i = 1; i < c->npos; i++) {
            sb_history_added a;
            double t0 = sb_now_ms();
            if (!sb_history_add(h, c->pos[i], &a, &err)) {
                fprintf(stderr, "shadowbench: %s\n", err.msg);
                rc = SB_EXIT_BAD_INPUT;   /* not a results set; the others are still added */
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
    if (!strcmp(sub, "annotate")) {
        if (c->npos != 3) return bad_usage(c);
        sb_history *h = sb_history_open(path, true, &err);
        if (!h) return bad_file(&err);
        const char *what = c->pos[1];
        long long night = sb_history_find_night(h, what, &err);
        if (night == 0) {
            /* a commit no night ran (one bisect named): the first night whose commit holds it */
            sb_history_night *n = NULL;
            int nn = sb_history_nights(h, &n, &err);
            for (int i = 0; i < nn && !night; i++)
                if (n[i].commit[0] && sb_git_is_ancestor(what, n[i].commit)) night = n[i].id;
            sb_history_nights_free(n, nn);
        }
        int rc = SB_EXIT_OK;
        if (night < 0) rc = bad_file(&err);
        else if (night == 0)
            rc = bad("history annotate: '%s' is no night of the history, and no night ran that commit or one after "
                     "it (`history list` names the nights and their commits)", what);
        else if (!sb_history_store_annotation(h, night, what, c->o.series ? c->o.series : "", c->pos[2], c->o.accept, &err))
            rc = bad_file(&err);
        else
            sb_log("night %lld annotated%s%s%s", night, c->o.series ? " for series " : "",
                   c->o.series ? c->o.series : "", c->o.accept ? ", accepted" : "");
        sb_history_close(h);
        return rc;
    }
    if (!strcmp(sub, "check")) {
        if (c->npos != 2) return bad_usage(c);
        sb_history *h = sb_history_open(path, false, &err);
        if (!h) return bad_file(&err);
        sb_history_query q = {.noise_floor_pct = c->o.noise_floor};
        char mbuf[1024];
        if (c->o.metrics) q.nmetrics = split_metrics(c->o.metrics, mbuf, sizeof mbuf, q.metrics, 32);
        int n = sb_history_check(h, c->pos[1], &q, c->o.nights, stdout, &err);
        sb_history_close(h);
        if (n < 0) return bad_file(&err);
        return n > 0 ? SB_EXIT_FAILED : SB_EXIT_OK;
    }
    if (c->npos != 1 || (strcmp(sub, "list") && strcmp(sub, "regressions"))) return bad_usage(c);
    sb_history *h = sb_history_open(path, false, &err);
    if (!h) return bad_file(&err);
    int rc = SB_EXIT_OK;
    if (!strcmp(sub, "list")) {
        if (!sb_history_list(h, stdout, &err)) rc = bad_file(&err);
    } else {
        sb_history_query q = {.since = c->o.since, .recent = c->o.recent, .noise_floor_pct = c->o.noise_floor};
        char mbuf[1024];
        if (c->o.metrics) q.nmetrics = split_metrics(c->o.metrics, mbuf, sizeof mbuf, q.metrics, 32);
        sb_history_change *ch = NULL;
        int n = sb_history_changes(h, &q, &ch, &err);
        if (n < 0) {
            rc = bad_file(&err);
        } else {
            int recent = 0, regressions = 0, accepted = 0;
            for (int i = 0; i < n; i++) {
                regressions += ch[i].regression;
                accepted += ch[i].regression && ch[i].accepted;
                recent += ch[i].regression && ch[i].recent && !ch[i].accepted;
            }
            sb_history_print_changes(ch, n, c->o.format, stdout);
            sb_log("%d change(s), %d regression(s) (%d accepted), %d not accepted starting in the newest %d night(s)",
                   n, regressions, accepted, recent, q.recent ? q.recent : 3);
            rc = recent > 0 ? SB_EXIT_FAILED : SB_EXIT_OK;
        }
        free(ch);
    }
    sb_history_close(h);
    return rc;
}

/* ---- bisect ---- */

static int cmd_bisect(const cli *c) {
    if (c->o.history ? c->npos != 0 : c->npos != 2) return bad_usage(c);
    sb_bisect_cmd b = {.good = c->o.history ? NULL : c->pos[0], .bad = c->o.history ? NULL : c->pos[1],
                       .run_argv = c->tail, .run_argc = c->ntail,
                       .metric = sb_cli_given(&c->o, "--metric") ? c->o.metrics : NULL, .repeat = c->o.pairs,
                       .threshold_pct = c->o.threshold, .workdir = c->o.workdir, .history = c->o.history,
                       .series = c->o.series};
    return sb_bisect_main(&b);
}

static int cmd_report(const cli *c) {
    if (c->npos > 1 || (c->npos == 1 && c->o.history)) return bad_usage(c);
    char pbuf[4096];
    const char *site = c->o.out;
    sb_site_opts so = {.dir = c->npos == 1 ? c->pos[0] : NULL, .out = site, .recent = c->o.recent};
    if (!so.dir) so.history = history_path(c, pbuf, sizeof pbuf);
    sb_err err;
    if (!sb_site_write(&so, &err)) return bad_file(&err);   /* a set or history it could not read, or a page not written */
    printf("%s/index.html\n", site);
    return 0;
}

static int dispatch(const cli *c) {
    switch (c->cmd) {
    case SB_CMD_RUN: return cmd_run(c);
    case SB_CMD_BATCH: return cmd_batch(c);
    case SB_CMD_COMPARE: return cmd_compare(c);
    case SB_CMD_MERGE: return cmd_merge(c);
    case SB_CMD_TUNE: return cmd_tune(c);
    case SB_CMD_STRESS: return cmd_stress(c);
    case SB_CMD_HISTORY: return cmd_history(c);
    case SB_CMD_BISECT: return cmd_bisect(c);
    case SB_CMD_REPORT: return cmd_report(c);
    case SB_CMD_TECHNIQUES: return c->npos ? bad_usage(c) : cmd_techniques();
    case SB_CMD_COLUMNS: return cmd_columns(c);
    case SB_CMD_INFO: return cmd_info(c);
    case SB_CMD_PATH: return cmd_path(c);
    case SB_CMD_COUNT: break;
    }
    return SB_EXIT_BAD_INPUT;
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
    sb_session_set_build(SB_BUILD_OPTIONS);
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        int cmd = argc > 2 ? sb_command_find(argv[2]) : -1;   /* help COMMAND */
        sb_cli_help(argc < 2 ? stderr : stdout, cmd);
        return argc < 2 ? SB_EXIT_BAD_INPUT : SB_EXIT_OK;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("shadowbench %s\n", SB_VERSION);
        return SB_EXIT_OK;
    }
    cli c;
    memset(&c, 0, sizeof c);
    int cmd = sb_command_find(argv[1]);
    if (cmd < 0) return bad("unknown command '%s' (see shadowbench --help)", argv[1]);
    for (int i = 2; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            sb_cli_help(stdout, cmd);
            return SB_EXIT_OK;
        }
    c.cmd = (sb_command)cmd;
    c.argc = argc;
    c.argv = argv;
    c.pos = sb_xcalloc((size_t)argc, sizeof *c.pos);   /* never more than the arguments */
    sb_cli_defaults(&c.o, cmd);
    c.o.run.progress = isatty(2);
    sb_err err;
    int parsed = argc;
    if (cmd == SB_CMD_BISECT)   /* what follows "--" is the run bisected, passed on as it is */
        for (int i = 2; i < argc; i++)
            if (!strcmp(argv[i], "--")) {
                parsed = i;
                c.tail = argv + i + 1;
                c.ntail = argc - i - 1;
                break;
            }
    if (!sb_cli_parse(&c.o, c.cmd, parsed, argv, 2, c.pos, &c.npos, &err)) {
        free(c.pos);
        return bad("%s", err.msg);
    }
    if (c.o.quiet) sb_set_quiet(true), c.o.run.progress = false;
    if (c.o.verbose) sb_set_verbose(true);
    if (cmd == SB_CMD_RUN || cmd == SB_CMD_BATCH || cmd == SB_CMD_TUNE || cmd == SB_CMD_STRESS) sb_interrupt_install();
    int rc = dispatch(&c);
    if (rc != SB_EXIT_BAD_INPUT && sb_result_writes_failed()) {   /* a cron job must not read a lost row as success */
        fprintf(stderr, "shadowbench: results could not all be written (the files are named above): exit status %d\n",
                SB_EXIT_WRITE);
        rc = SB_EXIT_WRITE;
    }
    free(c.pos);
    return rc;
}
