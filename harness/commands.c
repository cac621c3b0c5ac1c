/* commands.c - every command's handler and the commands' table (commands.h). */
#include "commands.h"

#include "motion.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "batch.h"
#include "bisect.h"
#include "cameras.h"
#include "score.h"
#include "columns.h"
#include "compare.h"
#include "flip.h"
#include "history.h"
#include "image.h"
#include "pathcheck.h"
#include "resultset.h"
#include "run.h"
#include "scene_load.h"
#include "site.h"
#include "stress.h"
#include "sweep.h"
#include "table.h"
#include "tune.h"

/* The history's default folder when --history and $SB_HISTORY do not say (not a source folder). */
static const char *const default_out = "out";

/* Bad input: one line, exit 2. */
static int bad(const char *fmt, const char *a) {
    char line[SB_ERR_LEN + 512];
    snprintf(line, sizeof line, fmt, a);
    sb_say_line(stderr, line);
    return SB_EXIT_BAD_INPUT;
}

/* A command's usage, as bad input: "usage: shadowbench run SCENE PATH SPEC... (see shadowbench run --help)". */
static int bad_usage(const sb_cli *c) {
    const char *u = c->cmd->usage;
    fprintf(stderr, "shadowbench: usage: shadowbench %.*s (see shadowbench %s --help)\n", (int)strcspn(u, "\n"), u,
            c->cmd->name);
    return SB_EXIT_BAD_INPUT;
}

/* A file the command was given could not be used: one line, exit 2 (4 when
 * what failed was writing a result, which sb_result_writes_failed knows). */
static int bad_file(const sb_err *err) {
    sb_say_line(stderr, err->msg);
    return sb_result_writes_failed() ? SB_EXIT_WRITE : SB_EXIT_BAD_INPUT;
}

/* ---- where results go: checked before anything runs ---- */

/* A folder a command will write into (nothing is made yet): bad input when a file stands there or on the way,
 * or when it (or, missing, the nearest folder above it that exists) cannot be written. */
static bool writable_dir(const char *what, const char *dir, bool may_make, sb_err *err) {
    char at[4096];
    snprintf(at, sizeof at, "%s", dir);
    struct stat st;
    while (stat(at, &st) != 0) {
        if (!may_make) return sb_fail(err, "%s %s: no such results folder", what, dir);
        char *slash = strrchr(at, '/');
        while (slash && slash > at && slash[1] == 0) *slash = 0, slash = strrchr(at, '/');   /* a trailing '/' */
        if (!slash) snprintf(at, sizeof at, ".");
        else if (slash == at) at[1] = 0;
        else *slash = 0;
    }
    if (!S_ISDIR(st.st_mode))
        return sb_fail(err, "%s %s: %s is a file, not a folder", what, dir, strcmp(at, dir) ? at : "it");
    if (access(at, W_OK | X_OK) != 0)
        return sb_fail(err, "%s %s: %s cannot be written (%s)", what, dir, strcmp(at, dir) ? at : "the folder",
                       strerror(errno));
    return true;
}

/* --out and --resume of a command that writes a results set. */
static bool check_out(const sb_cli *c, sb_err *err) {
    if (!(c->cmd->flags & SB_CMDF_RESULTS)) return true;
    if (c->o.resume) return writable_dir("--resume", c->o.resume, false, err);
    return writable_dir("--out", c->o.out, true, err);
}

static void command_line(const sb_cli *c, char *out, size_t len) {
    out[0] = 0;
    for (int i = 0; i < c->argc; i++) {
        size_t l = strlen(out);
        snprintf(out + l, len - l, "%s%s", i ? " " : "", c->argv[i]);
    }
}

/* --metric M,...: the names, pointing into buf. */
static int split_metrics(const char *list, char *buf, size_t len, const char **out, int max) {
    int n = 0;
    snprintf(buf, len, "%s", list);
    for (char *t = strtok(buf, ","); t && n < max; t = strtok(NULL, ",")) out[n++] = t;
    return n;
}

/* ---- what the tool holds ---- */

/* --all-pairs SPEC...: each spec's covering set, a spec a line; the refused pairs on stderr. */
static int techniques_pairwise(const sb_cli *c) {
    if (!c->npos) return bad_usage(c);
    for (int k = 0; k < c->npos; k++) {
        sb_sweep sw;
        sb_err err;
        if (!sb_sweep_pairwise(c->pos[k], &sw, &err)) return bad("%s", err.msg);
        for (int i = 0; i < sw.count; i++) printf("%s\n", sw.specs[i]);
        fflush(stdout);   /* whole lines before the refusals, where both go to one pipe */
        for (int i = 0; i < sw.refused_count; i++) fprintf(stderr, "%s: refused: %s\n", c->pos[k], sw.refused[i]);
        sb_sweep_free(&sw);
    }
    return fflush(stdout) == 0 && !ferror(stdout) ? SB_EXIT_OK : SB_EXIT_WRITE;
}

static int cmd_techniques(const sb_cli *c) {
    if (c->o.all_pairs) return techniques_pairwise(c);
    if (c->npos) return bad_usage(c);
    if (c->o.format == SB_DOC_MARKDOWN) {
        sb_techniques_markdown(stdout);
        return SB_EXIT_OK;
    }
    for (int i = 0; i < sb_technique_count(); i++) {
        const sb_technique *t = sb_technique_at(i);
        printf("%s - %s\n  stages:", t->name, t->summary);
        for (int s = 0; s < sb_stage_count(); s++)
            if (sb_technique_stage_mask(t) & SB_STAGE_BIT(s)) printf(" %s", sb_stage_at(s)->name);
        printf("%s\n", t->stage_count ? "" : " none (nothing of it is timed)");
        for (int k = 0; k < t->param_count; k++) {
            const sb_param_def *p = &t->params[k];
            if (p->kind == SB_PARAM_ENUM || p->kind == SB_PARAM_TEXT)
                printf("  %-8s %-28s default %-6s %s\n", p->name, p->kind == SB_PARAM_TEXT ? "text" : p->choices,
                       p->kind == SB_PARAM_TEXT && !*p->def ? "(none)" : p->def, p->help);
            else {
                char range[64];
                snprintf(range, sizeof range, "%s %g..%g%s", p->kind == SB_PARAM_INT ? "int" : "float", p->min, p->max,
                         p->can_auto ? " or auto" : "");
                printf("  %-8s %-28s default %-6s %s\n", p->name, range, p->def, p->help);
            }
        }
    }
    return SB_EXIT_OK;
}

static int cmd_columns(const sb_cli *c) {
    if (c->npos) return bad_usage(c);
    if (c->o.format == SB_OUTPUT_MARKDOWN) {
        sb_columns_markdown(stdout);
        return SB_EXIT_OK;
    }
    sb_csv csv = {0};
    sb_columns_csv(&csv);
    fputs(csv.buf, stdout);
    sb_csv_free(&csv);
    return SB_EXIT_OK;
}

/* What a scene file holds and how it is drawn; no GL needed. */
static int scene_info(const sb_cli *c) {
    sb_err err;
    sb_scene scene;
    sb_scene_opts so = sb_run_scene_opts(&c->o.run);
    if (!sb_scene_load(&scene, c->pos[0], &so, &err)) return bad_file(&err);
    sb_scene_info(&scene, stdout);
    sb_motion_info(&scene, stdout);
    printf("memory: CPU %.1f MiB (the scene's arrays, the reference's BVH not counted), GPU %.1f MiB (its "
           "buffers; a run adds its render targets and shadow maps)\n",
           sb_scene_cpu_bytes(&scene) / 1048576.0, sb_gpu_scene_bytes(&scene) / 1048576.0);
    sb_scene_free(&scene);
    return SB_EXIT_OK;
}

static int cmd_info(const sb_cli *c) {
    if (c->npos > 1) return bad_usage(c);
    if (c->npos == 1) return scene_info(c);
    char avail[1024];
    sb_context ctx;
    sb_err err;
    bool have = sb_context_create(&ctx, c->o.run.backend, &err);
    sb_backends_available(have ? &ctx : NULL, avail, sizeof avail);
    printf("shadowbench %s\nbackends available: %s\n", c->version, avail[0] ? avail : "none");
    if (!have) {
        sb_say_line(stderr, err.msg);
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
    return SB_EXIT_OK;
}

/* ---- path ---- */

/* Each camera of the path checked against the scene (pathcheck.h): the verdicts, or NULL when the reference
 * cannot be built (err). */
static sb_path_frame *check_cameras(const sb_cli *c, const sb_scene *scene, const sb_path *p, int *flagged,
                                    char *text, size_t tlen, sb_err *err) {
    sb_reference ref;
    if (!sb_reference_build(&ref, scene, err)) return NULL;
    int n = c->o.run.frames;
    sb_path_frame *check = sb_xmalloc(sizeof *check * (size_t)n);
    double t0 = sb_now_ms();
    *flagged = sb_path_check(&ref, scene, p, n, (double)c->o.run.width / c->o.run.height, check, c->o.run.threads);
    sb_verbose("path check: %d frame(s) in %.1f ms (the reference built in %.0f ms)", n, sb_now_ms() - t0,
               ref.build_ms);
    sb_reference_free(&ref);
    sb_path_check_text(check, n, text, tlen);
    return check;
}

static void print_cameras(const sb_cli *c, const sb_path *p, const sb_scene *scene, const sb_path_frame *check) {
    int n = c->o.run.frames;
    double aspect = (double)c->o.run.width / c->o.run.height;
    printf("frame,progress,t,px,py,pz,qx,qy,qz,qw,fov,near,far%s\n", check ? ",verdict,node" : "");
    for (int i = 0; i < n; i++) {
        sb_camera cam = sb_path_camera(p, i, n, aspect, scene);
        printf("%d,%.6g,%.6g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g", i, sb_path_progress(i, n),
               sb_path_progress(i, n) * sb_path_duration(p), cam.pos.x, cam.pos.y, cam.pos.z, cam.rot.x, cam.rot.y,
               cam.rot.z, cam.rot.w, cam.fov_deg, cam.znear, cam.zfar);
        if (check) {
            printf(",%s,", sb_path_verdict_names[check[i].verdict]);
            if (check[i].node >= 0) printf("%lld", (long long)check[i].node);
        }
        printf("\n");
    }
}

static int cmd_path(const sb_cli *c) {
    if (c->npos < 1 || c->npos > 2) return bad_usage(c);
    sb_err err;
    sb_scene scene;
    bool have_scene = c->npos == 2;
    sb_scene_opts so = sb_run_scene_opts(&c->o.run);
    if (have_scene && !sb_scene_load(&scene, c->pos[1], &so, &err)) return bad_file(&err);
    sb_path p;
    if (!sb_path_load(&p, c->pos[0], have_scene ? &scene : NULL, &err)) {
        if (have_scene) sb_scene_free(&scene);
        return bad_file(&err);
    }
    sb_path_frame *check = NULL;
    int flagged = 0, rc = SB_EXIT_OK;
    char text[2048] = "";   /* the flagged frames */
    if (have_scene && !(check = check_cameras(c, &scene, &p, &flagged, text, sizeof text, &err))) {
        sb_say_line(stderr, err.msg);
        rc = SB_EXIT_FAILED;
    } else if (flagged && c->o.run.strict_path) {   /* refused: the one-line error, no table */
        fprintf(stderr, "shadowbench: %s: %s (--strict-path)\n", c->pos[0], text);
        rc = SB_EXIT_BAD_INPUT;
    } else {
        print_cameras(c, &p, have_scene ? &scene : NULL, check);
        if (flagged) fprintf(stderr, "shadowbench: %s along %s: %s\n", c->pos[1], c->pos[0], text);   /* as a run says it */
    }
    free(check);
    sb_path_free(&p);
    if (have_scene) sb_scene_free(&scene);
    return rc;
}

/* ---- cameras ---- */

static int cmd_cameras(const sb_cli *c) {
    if (c->npos != 2) return bad_usage(c);
    sb_err err;
    sb_scene scene;
    sb_scene_opts so = sb_run_scene_opts(&c->o.run);
    if (!sb_scene_load(&scene, c->pos[0], &so, &err)) return bad_file(&err);
    sb_path p;
    if (!sb_path_load(&p, c->pos[1], &scene, &err)) {
        sb_scene_free(&scene);
        return bad_file(&err);
    }
    if (c->o.twins && c->o.run.flicker_dt <= 0) {   /* it would drop the twins without a word */
        sb_path_free(&p);
        sb_scene_free(&scene);
        return bad("cameras: --twins needs --flicker-dt above 0 (a twin is a frame --flicker-dt of path time later)%s",
                   "");
    }
    sb_cameras_req req = {.scene_name = c->pos[0], .path_name = c->pos[1], .scene = &scene, .path = &p,
                          .opts = &c->o.run, .twins = c->o.twins, .format = (sb_cameras_format)c->o.format};
    char *doc = sb_cameras_document(&req);
    fputs(doc, stdout);
    fputc('\n', stdout);
    free(doc);
    sb_path_free(&p);
    sb_scene_free(&scene);
    if (fflush(stdout) != 0 || ferror(stdout)) {   /* a full disk, /dev/full: the document is not whole */
        fprintf(stderr, "shadowbench: cameras: the document could not be written: %s\n", strerror(errno));
        return SB_EXIT_WRITE;
    }
    return SB_EXIT_OK;
}

/* ---- run ---- */

/* The specs of the command line expanded into runs; false with err on a bad one. */
static bool expand_specs(const char *const *specs, int n, sb_run_spec **runs, int *nruns, sb_err *err) {
    for (int i = 0; i < n; i++)
        if (!sb_spec_expand(specs[i], NULL, runs, nruns, err)) return false;
    return true;
}

/* The runs not yet complete (a resumed folder keeps the complete ones). */
static int runs_to_do(const sb_cli *c, sb_session *s, sb_summary *sum, const char *dir, const sb_run_spec *runs,
                      int nruns, const sb_run_spec **specs, int *index) {
    bool *done = sb_xcalloc((size_t)(nruns ? nruns : 1), 1);
    if (c->o.resume) {
        char (*idbuf)[17] = sb_xmalloc(sizeof *idbuf * (size_t)(nruns ? nruns : 1));
        const char **ids = sb_xmalloc(sizeof *ids * (size_t)(nruns ? nruns : 1));
        for (int i = 0; i < nruns; i++) sb_session_run_id(s, &runs[i], idbuf[i]), ids[i] = idbuf[i];
        int kept = sb_summary_keep_complete(sum, dir, ids, nruns, done);
        sb_log("resuming %s: %d run(s) complete, %d to do", dir, kept, nruns - kept);
        free(ids);
        free(idbuf);
    }
    int todo = 0;
    for (int i = 0; i < nruns; i++)
        if (!done[i]) specs[todo] = &runs[i], index[todo++] = i;
    free(done);
    return todo;
}

/* The results folder: the resumed one (unsealed: it changes now), or a new stamped one under --out. */
static bool results_folder(const sb_cli *c, char *dir, size_t len, sb_err *err) {
    if (c->o.resume) {
        snprintf(dir, len, "%s", c->o.resume);
        sb_resultset_unseal(dir);
        return sb_columns_write(dir, err);
    }
    return sb_make_stamped_dir(c->o.out, dir, len, err) && sb_columns_write(dir, err);
}

static void log_session(const sb_session *s) {
    char parts[256];
    sb_scene_load_parts(&s->scene, parts, sizeof parts);
    sb_log("%s: %u triangles, %u draws, loaded in %.0f ms (%s), GPU upload %.0f ms; renderer %s (%s timing)",
           s->scene.file, (unsigned)sb_scene_triangles(&s->scene), s->scene.draw_count, s->scene.load_ms, parts,
           s->gpu_upload_ms, s->ctx.renderer, sb_timing_name(s->timing));
}

/* The runs into the folder, the summary concluded and the set sealed: the command's exit status. */
static int run_into(const sb_cli *c, sb_session *s, const char *dir, const sb_run_spec *runs, int nruns) {
    char sum_path[4200];
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    sb_summary sum;
    sb_summary_open(&sum, sum_path);
    const sb_run_spec **specs = sb_xmalloc(sizeof *specs * (size_t)(nruns ? nruns : 1));
    int *index = sb_xmalloc(sizeof *index * (size_t)(nruns ? nruns : 1));
    int todo = runs_to_do(c, s, &sum, dir, runs, nruns, specs, index);
    const double t0 = sb_now_ms();
    sb_run_group(s, specs, index, todo, dir, &sum, 0, todo);
    /* the runs flagged unstable, run again while the session is open: planned as a batch's are (a share of the
       command's time, a disturbed machine waited for or said) */
    const double night_s = (sb_now_ms() - t0) / 1e3;
    const int nprobe = sum.ncalib;
    double spent_s = 0;
    for (int attempt = 2; attempt <= 1 + s->opts.rerun_unstable && !sb_interrupted(); attempt++) {
        sb_rerun_round round;
        int m = 0;
        if (sb_rerun_round_plan(s, &sum, nprobe, night_s, spent_s, attempt, &round))
            for (int i = 0; i < nruns; i++) {
                char id[17];
                sb_session_run_id(s, &runs[i], id);
                for (int u = 0; u < round.n; u++)
                    if (round.pick[u] && !strcmp(round.ids[u], id)) specs[m] = &runs[i], index[m++] = i;
            }
        sb_rerun_round_free(&round);
        if (!m) break;
        const double a0 = sb_now_ms();
        sb_run_again(s, specs, index, m, dir, &sum, attempt);
        spent_s += (sb_now_ms() - a0) / 1e3;
    }
    sb_err err;
    if (!sb_summary_flush(&sum, &err) || !sb_resultset_seal(dir, &err)) sb_say_line(stderr, err.msg);
    free(specs);
    free(index);
    printf("%s\n", dir);
    int rc = sb_summary_conclude(&sum, dir, "the same command with");
    sb_summary_free(&sum);
    if (s->input_refused[0]) {   /* bad input: said even with --quiet (the run's reason holds it too) */
        fprintf(stderr, "shadowbench: %s: %s\n", c->cmd->name, s->input_refused);
        rc = SB_EXIT_BAD_INPUT;
    }
    return rc;
}

/* The runs against the open scene, before anything is written: a spec's light=K (a lamp the scene has, not beside
 * --lights), a run given twice (dropped with a note: a run_id names one row), and --resume of another command
 * (refused). */
static bool check_runs(const sb_cli *c, sb_session *s, sb_run_spec *runs, int *nruns, const char *identity,
                       sb_err *err) {
    for (int i = 0; i < *nruns; i++)
        if (!sb_spec_lights_check(&s->scene, &runs[i], s->opts.lights, err)) return false;
    char (*idbuf)[17] = sb_xmalloc(sizeof *idbuf * (size_t)(*nruns ? *nruns : 1));
    const char **ids = sb_xmalloc(sizeof *ids * (size_t)(*nruns ? *nruns : 1));
    int n = 0;
    for (int i = 0; i < *nruns; i++) {
        sb_session_run_id(s, &runs[i], idbuf[n]);
        int twin = -1;
        for (int k = 0; k < n && twin < 0; k++)
            if (!strcmp(idbuf[k], idbuf[n])) twin = k;
        if (twin >= 0) {
            char params[SB_PARAMS_TEXT_LEN];
            sb_params_canonical(&runs[i].params, params, sizeof params);
            sb_log("note: %s:%s is given twice (run_id %s): run once", runs[i].tech->name, params, idbuf[n]);
            continue;
        }
        runs[n] = runs[i];
        ids[n] = idbuf[n];
        n++;
    }
    *nruns = n;
    bool ok = !c->o.resume || sb_resume_check(c->o.resume, identity, ids, n, err);
    free(ids);
    free(idbuf);
    return ok;
}

static int cmd_run(const sb_cli *c) {
    if (c->npos < 3) return bad_usage(c);
    sb_err err;
    sb_run_spec *runs = NULL;
    int nruns = 0;
    if (!expand_specs(c->pos + 2, c->npos - 2, &runs, &nruns, &err) || !sb_grid_confirm(nruns, &c->o, &err)) {
        free(runs);
        return bad_file(&err);
    }
    sb_session s;
    memset(&s, 0, sizeof s);
    sb_run_opts o = c->o.run;
    sb_run_opts_finish(&o);
    if (!sb_session_open(&s, &o, c->pos[0], c->pos[1], &err)) {
        sb_say_line(stderr, err.msg);
        free(runs);
        int rc = s.files_refused ? SB_EXIT_BAD_INPUT : SB_EXIT_FAILED;
        sb_session_close(&s);
        return rc;
    }
    char dir[4096], cmdline[2048], identity[8192];
    sb_cli_opts as_read = c->o;   /* --lights by the set's one name, read against the scene ("2,0" is "0,2") */
    as_read.run.lights = s.opts.lights;
    sb_cli_set_identity(&as_read, c->cmd, c->pos, c->npos, identity, sizeof identity);
    int rc;
    if (!check_runs(c, &s, runs, &nruns, identity, &err)) {
        sb_say_line(stderr, err.msg);
        rc = SB_EXIT_BAD_INPUT;   /* nothing written */
    } else if (!results_folder(c, dir, sizeof dir, &err)) {
        sb_say_line(stderr, err.msg);
        rc = SB_EXIT_WRITE;   /* checked writable before: a write that failed since */
    } else {
        command_line(c, cmdline, sizeof cmdline);
        if (!sb_session_write_meta(&s, dir, cmdline, c->version, c->commit, identity, &err))
            sb_say_line(stderr, err.msg);
        sb_session_keep_reference(&s, dir);
        log_session(&s);
        rc = run_into(c, &s, dir, runs, nruns);
    }
    sb_session_close(&s);
    free(runs);
    return rc;
}

/* ---- score: another renderer's frames ---- */

/* The score technique's spec of the command's words (score.h): its parameters set one by one, so a folder, a
 * pattern or the renderer's settings may hold what a spec's text divides on (':', ','). */
static bool score_spec(const sb_cli *c, sb_run_spec *spec, sb_err *err) {
    const sb_technique *t = sb_technique_find("score");
    const char *values[][2] = {{"dir", c->pos[2]}, {"vis", c->o.pattern}, {"mask", c->o.mask},
                               {"renderer", c->o.renderer}, {"settings", c->o.renderer_params}};
    sb_spec_defaults(spec, t);
    for (size_t k = 0; k < SB_COUNT(values); k++)
        for (int i = 0; values[k][1] && i < t->param_count; i++)
            if (!strcmp(t->params[i].name, values[k][0]) &&
                !sb_param_set(&spec->params, i, &t->params[i], values[k][1], t->name, err))
                return false;
    sb_spec_bind(spec);
    return t->check(spec->desc, err);
}

static int cmd_score(const sb_cli *c) {
    if (c->npos != 3) return bad_usage(c);
    sb_err err;
    if (!c->o.mask)
        return bad("score: --mask FILE is needed: the renderer's mask of the pixels it drew is how score checks that "
                   "its cameras are the exported ones%s", "");
    if (c->o.run.error_every <= 0) return bad("score: --error-every 0 scores nothing%s", "");
    /* a renderer's name and its parameters are data every writer prints (CSV, the report, compare's table) */
    const char *names[2][2] = {{"--renderer", c->o.renderer}, {"--params", c->o.renderer_params}};
    for (int k = 0; k < 2; k++) {
        const char *v = names[k][1];
        if (!v) continue;
        if (!*v) return bad("score: %s is empty (leave it out for the default)", names[k][0]);
        char what[32];
        snprintf(what, sizeof what, "score: %s", names[k][0]);
        if (!sb_name_check(what, v, &err)) return bad("%s", err.msg);
    }
    sb_run_spec spec;
    if (!score_spec(c, &spec, &err)) return bad("score: %s", err.msg);
    sb_run_opts o = c->o.run;
    o.warmup = 0;
    sb_run_opts_finish(&o);
    if (!sb_score_files_present(c->pos[2], c->o.pattern, c->o.mask, o.frames, o.error_every, o.width, o.height, &err))
        return bad_file(&err);
    sb_session s;
    memset(&s, 0, sizeof s);
    if (!sb_session_open(&s, &o, c->pos[0], c->pos[1], &err)) {
        sb_say_line(stderr, err.msg);
        int rc = s.files_refused ? SB_EXIT_BAD_INPUT : SB_EXIT_FAILED;
        sb_session_close(&s);
        return rc;
    }
    char out[4096], cmdline[2048], identity[8192];
    sb_cli_set_identity(&c->o, c->cmd, c->pos, c->npos, identity, sizeof identity);
    int rc;
    if (!results_folder(c, out, sizeof out, &err)) {
        sb_say_line(stderr, err.msg);
        rc = SB_EXIT_WRITE;
    } else {
        command_line(c, cmdline, sizeof cmdline);
        if (!sb_session_write_meta(&s, out, cmdline, c->version, c->commit, identity, &err))
            sb_say_line(stderr, err.msg);
        sb_session_keep_reference(&s, out);
        log_session(&s);
        rc = run_into(c, &s, out, &spec, 1);
    }
    sb_session_close(&s);
    return rc;
}

/* ---- tune, batch, stress ---- */

static int cmd_tune(const sb_cli *c) {
    if (c->npos < 1) return bad_usage(c);
    sb_run_opts o = c->o.run;   /* tune's own defaults are its rows' (options.c) */
    if (c->o.max_flicker > 0 && !sb_cli_given(&c->o, "--flicker-dt")) {   /* a flicker bound measures twins */
        sb_run_opts general;
        sb_run_opts_defaults(&general);
        o.flicker_dt = general.flicker_dt;
    }
    if (c->o.max_flip > 0) o.flip = true;   /* a FLIP bound scores the shaded frames */
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
                       .techniques = c->o.techniques, .max_err = c->o.max_err,
                       .max_side = {c->o.max_flicker, c->o.max_flip},
                       .max_mb = c->o.max_mb, .budget_ms = c->o.budget_ms, .time_limit_s = c->o.time_limit_s,
                       .opts = &o, .out = c->o.out, .resume = c->o.resume};
    if (cmd.nspecs && cmd.techniques) return bad("tune: give SPECs or --techniques, not both%s", "");
    char identity[8192];
    sb_cli_set_identity(&c->o, c->cmd, c->pos, c->npos, identity, sizeof identity);
    cmd.identity = identity;
    return sb_tune_main(&cmd);
}

static int cmd_batch(const sb_cli *c) {
    if (c->npos != 1) return bad_usage(c);
    char cmdline[2048];
    command_line(c, cmdline, sizeof cmdline);
    sb_run_opts base;
    sb_run_opts_defaults(&base);
    base.progress = c->o.run.progress;
    base.allow_external_uris = c->o.run.allow_external_uris;
    char identity[8192];
    sb_cli_set_identity(&c->o, c->cmd, NULL, 0, identity, sizeof identity);
    sb_batch_cmd cmd = {.file = c->pos[0], .base = &base, .cli = &c->o, .identity = identity,
                        .out = c->o.out, .resume = c->o.resume, .shard = c->o.shard, .dry_run = c->o.dry_run,
                        .command_line = cmdline, .version = c->version, .commit = c->commit};
    return sb_batch_main(&cmd);
}

static int cmd_stress(const sb_cli *c) {
    sb_run_opts o = c->o.run;   /* stress's own defaults are its rows' (options.c) */
    sb_err err;
    const char *only = c->npos && strcmp(c->pos[0], "all") ? c->pos[0] : NULL;   /* "all": every case */
    int failures = sb_stress_run(&o, only, c->npos > 1 ? c->pos + 1 : NULL, c->npos > 1 ? c->npos - 1 : 0, stdout, &err);
    if (failures < 0) return bad_file(&err);
    if (sb_interrupted()) return SB_EXIT_SIGNAL + sb_interrupted();
    return failures ? SB_EXIT_FAILED : SB_EXIT_OK;
}

/* ---- compare and merge ---- */

static int cmd_compare(const sb_cli *c) {
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

static int cmd_merge(const sb_cli *c) {
    if (c->npos < 1 || !sb_cli_given(&c->o, "--out")) return bad_usage(c);
    sb_err err;
    if (!sb_merge(c->pos, c->npos, c->o.out, &err)) return bad_file(&err);
    printf("%s\n", c->o.out);
    return SB_EXIT_OK;
}

/* ---- history and report ---- */

static const char *history_path(const sb_cli *c, char *buf, size_t len) {
    return c->o.history ? c->o.history : sb_history_default_path(default_out, buf, len);
}

/* The history the subcommand reads (write: add and annotate, which make it when missing); NULL: said, exit 2. */
static sb_history *open_history(const sb_cli *c, bool write) {
    char pbuf[4096];
    sb_err err;
    sb_history *h = sb_history_open(history_path(c, pbuf, sizeof pbuf), write, &err);
    if (!h) bad_file(&err);
    return h;
}

static int cmd_history_add(const sb_cli *c) {
    if (c->npos < 1) return bad_usage(c);
    sb_history *h = open_history(c, true);
    if (!h) return SB_EXIT_BAD_INPUT;
    int rc = SB_EXIT_OK;
    for (int i = 0; i < c->npos; i++) {
        sb_history_added a;
        sb_err err;
        double t0 = sb_now_ms();
        if (!sb_history_add(h, c->pos[i], &a, &err)) {
            sb_say_line(stderr, err.msg);
            rc = SB_EXIT_BAD_INPUT;   /* not a results set, or a damaged one; the others are still added */
            continue;
        }
        if (a.existed) sb_log("%s: already in %s as night %lld; nothing changed", c->pos[i], sb_history_path(h), a.night);
        else
            sb_log("%s: night %lld in %s (%d runs, %d per-frame files, %.0f ms)", c->pos[i], a.night, sb_history_path(h),
                   a.runs, a.frames_files, sb_now_ms() - t0);
    }
    sb_history_discard_if_new(h);   /* nothing added to a history made just now: no file left behind */
    sb_history_close(h);
    return rc;
}

/* A night by its id or commit; a commit no night ran (one bisect named): the first night whose commit holds it.
 * *first: that night is the history's first and was named by a commit (no night before it ran without it). */
/* The night NIGHT|COMMIT names (0: none, -1: *err), whether it is the history's first by a commit, and the commit
 * a note on it is filed under: the one typed, or the night's own where a night's number was typed. */
static long long night_of(sb_history *h, const char *what, bool *first, char *commit, size_t len, sb_err *err) {
    *first = false;
    snprintf(commit, len, "%s", what);
    long long night = sb_history_find_night(h, what, err);
    if (night < 0) return night;
    char *end;
    bool by_id = night > 0 && strtoll(what, &end, 10) == night && !*end;
    sb_history_night *n = NULL;
    int nn = sb_history_nights(h, &n, err);
    for (int i = 0; i < nn && !night; i++)
        if (n[i].commit[0] && sb_git_is_ancestor(what, n[i].commit)) night = n[i].id;
    for (int i = 0; i < nn && by_id; i++)
        if (n[i].id == night) snprintf(commit, len, "%s", n[i].commit);
    *first = !by_id && nn > 0 && night == n[0].id;
    sb_history_nights_free(n, nn);
    return night;
}

static int cmd_history_annotate(const sb_cli *c) {
    if (c->npos != 2) return bad_usage(c);
    sb_history *h = open_history(c, true);
    if (!h) return SB_EXIT_BAD_INPUT;
    const char *what = c->pos[0];
    sb_err err;
    bool first;
    char commit[128];
    long long night = night_of(h, what, &first, commit, sizeof commit, &err);
    int rc = SB_EXIT_OK, added = 0;
    if (night < 0) rc = bad_file(&err);
    else if (night > 0 && first && c->o.restart)   /* a change older than the history restarts none of its series */
        sb_log("%s: the history's first night (%lld) already ran it: no series of this history restarts there, "
               "nothing noted (--restart)", what, night);
    else if (night == 0)
        rc = bad("history annotate: '%s' is no night of the history, and no night ran that commit or one after "
                 "it (`history list` names the nights and their commits)", what);
    else if ((added = sb_history_store_annotation(h, night, commit, c->o.series ? c->o.series : "", c->pos[1],
                                                  c->o.accept, &err)) < 0)
        rc = bad_file(&err);
    else
        sb_log("night %lld %s%s%s%s", night, added ? "annotated" : "already had this note",
               c->o.series ? " for series " : "", c->o.series ? c->o.series : "", c->o.accept ? ", accepted" : "");
    sb_history_discard_if_new(h);   /* a history made by this open has no night to note: no file left behind */
    sb_history_close(h);
    return rc;
}

static int cmd_history_check(const sb_cli *c) {
    if (c->npos != 1) return bad_usage(c);
    sb_history *h = open_history(c, false);
    if (!h) return SB_EXIT_BAD_INPUT;
    sb_history_query q = {.noise_floor_pct = c->o.noise_floor};
    char mbuf[1024];
    sb_err err;
    if (c->o.metrics) q.nmetrics = split_metrics(c->o.metrics, mbuf, sizeof mbuf, q.metrics, 32);
    int n = sb_history_check(h, c->pos[0], &q, c->o.nights, stdout, &err);
    sb_history_close(h);
    if (n < 0) return bad_file(&err);
    return n > 0 ? SB_EXIT_FAILED : SB_EXIT_OK;
}

static int cmd_history_list(const sb_cli *c) {
    if (c->npos) return bad_usage(c);
    sb_history *h = open_history(c, false);
    if (!h) return SB_EXIT_BAD_INPUT;
    sb_err err;
    int rc = sb_history_list(h, stdout, &err) ? SB_EXIT_OK : bad_file(&err);
    sb_history_close(h);
    return rc;
}

static int cmd_history_regressions(const sb_cli *c) {
    if (c->npos) return bad_usage(c);
    sb_history *h = open_history(c, false);
    if (!h) return SB_EXIT_BAD_INPUT;
    sb_history_query q = {.since = c->o.since, .recent = c->o.recent, .noise_floor_pct = c->o.noise_floor};
    char mbuf[1024];
    if (c->o.metrics) q.nmetrics = split_metrics(c->o.metrics, mbuf, sizeof mbuf, q.metrics, 32);
    sb_history_change *ch = NULL;
    sb_err err;
    int n = sb_history_changes(h, &q, &ch, &err), rc = SB_EXIT_OK;
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
        sb_log("%d change(s), %d regression(s) (%d accepted), %d not accepted starting in the newest %d night(s)", n,
               regressions, accepted, recent, q.recent ? q.recent : 3);
        rc = recent > 0 ? SB_EXIT_FAILED : SB_EXIT_OK;
    }
    free(ch);
    sb_history_close(h);
    return rc;
}

static int cmd_bisect(const sb_cli *c) {
    if (c->o.history ? c->npos != 0 : c->npos != 2) return bad_usage(c);
    sb_bisect_cmd b = {.good = c->o.history ? NULL : c->pos[0], .bad = c->o.history ? NULL : c->pos[1],
                       .run_argv = c->tail, .run_argc = c->ntail, .run_cmd = &sb_commands[SB_CMD_RUN],
                       .metric = sb_cli_given(&c->o, "--metric") ? c->o.metrics : NULL, .repeat = c->o.pairs,
                       .threshold_pct = c->o.threshold, .workdir = c->o.workdir,
                       .build_type = (const char *const[]){"release", "debugoptimized", "debug", "plain"}[c->o.build_type],
                       .history = c->o.history,
                       .series = c->o.series};
    return sb_bisect_main(&b);
}

static int cmd_report(const sb_cli *c) {
    if (c->npos > 1 || (c->npos == 1 && c->o.history)) return bad_usage(c);
    char pbuf[4096];
    const char *site = c->o.out;
    sb_site_opts so = {.dir = c->npos == 1 ? c->pos[0] : NULL, .out = site, .recent = c->o.recent};
    if (!so.dir) so.history = history_path(c, pbuf, sizeof pbuf);
    /* the site is a folder of its own: never the set it shows, nor in it, nor the history file */
    if (so.dir ? sb_path_within(site, so.dir) : sb_same_file(site, so.history))
        return bad("report: --out %s is its input or in it: the site's pages would be written among "
                   "its files (give a folder of its own)", site);
    sb_err err;
    if (!sb_site_write(&so, &err)) return bad_file(&err);   /* a set or history it could not read, or a page not written */
    printf("%s/index.html\n", site);
    return SB_EXIT_OK;
}

/* `help [COMMAND]`: --help's text, or the command line's reference as markdown or roff. */
/* ---- flip ---- */

/* An image of the two: read, every value a number in [0, 1] (LDR-FLIP compares displayed images); false: said. */
static bool flip_input(const char *path, int *w, int *h, float **rgb, sb_err *err) {
    if (!sb_image_read_rgb(path, w, h, rgb, err)) return false;
    for (size_t i = 0; i < 3 * (size_t)*w * *h; i++) {
        float v = (*rgb)[i];
        if (v >= 0 && v <= 1) continue;
        size_t p = i / 3;
        sb_fail(err, "%s: pixel (%zu, %zu) holds %g: LDR-FLIP compares displayed images, every value in [0, 1]", path,
                p % (size_t)*w, p / (size_t)*w, v);
        free(*rgb);
        *rgb = NULL;
        return false;
    }
    return true;
}

static int cmd_flip(const sb_cli *c) {
    if (c->npos != 2) return bad_usage(c);
    sb_err err;
    for (int i = 0; c->o.map && i < 2; i++)   /* the map over an input would replace the image it measured */
        if (sb_same_file(c->o.map, c->pos[i])) {
            fprintf(stderr, "shadowbench: flip: --map %s is the input %s: it would be written over (give the map a "
                            "file of its own)\n", c->o.map, c->pos[i]);
            return SB_EXIT_BAD_INPUT;
        }
    if (c->o.map) {   /* the writer picks the format by the name's extension: a name without one writes nothing */
        const char *slash = strrchr(c->o.map, '/'), *dot = strrchr(c->o.map, '.');
        if (!dot || (slash && dot < slash) || !dot[1] || dot == (slash ? slash + 1 : c->o.map))
            return bad("flip: --map %s has no extension to choose its format by (.png, .exr, ...)", c->o.map);
        sb_err werr;
        if (!sb_image_can_write(c->o.map, &werr)) return bad("flip: --map %s", werr.msg);   /* before any work */
    }
    int w[2], h[2];
    float *img[2] = {NULL, NULL};
    for (int i = 0; i < 2; i++)
        if (!flip_input(c->pos[i], &w[i], &h[i], &img[i], &err)) {
            free(img[0]);
            return bad_file(&err);
        }
    if (w[0] != w[1] || h[0] != h[1]) {
        fprintf(stderr, "shadowbench: %s is %dx%d but %s is %dx%d: FLIP compares images of one size\n", c->pos[0],
                w[0], h[0], c->pos[1], w[1], h[1]);
        free(img[0]), free(img[1]);
        return SB_EXIT_BAD_INPUT;
    }
    size_t n = (size_t)w[0] * h[0];
    float *map = c->o.map ? sb_xmalloc(sizeof(float) * n) : NULL;
    sb_flip_stats st = sb_flip(img[0], img[1], w[0], h[0], c->o.ppd, map);
    free(img[0]), free(img[1]);
    if (map) {   /* the map first: a map that cannot be written (its folder named) leaves no figures half-said */
        unsigned char *grey = sb_xmalloc(n);
        for (int y = 0; y < h[0]; y++)   /* read top row first; written from rows given bottom-up (image.h) */
            for (int x = 0; x < w[0]; x++)
                grey[(size_t)(h[0] - 1 - y) * w[0] + x] = (unsigned char)lroundf(255 * map[(size_t)y * w[0] + x]);
        bool ok = sb_image_write_u8(c->o.map, w[0], h[0], 1, grey, &err);
        free(grey);
        free(map);
        if (!ok) {   /* the inputs were good: the write failed */
            sb_say_line(stderr, err.msg);
            return SB_EXIT_WRITE;
        }
    }
    printf("mean %.6f\np95 %.6f\nmax %.6f\n", st.mean, st.p95, st.max);
    return SB_EXIT_OK;
}

static int cmd_help(const sb_cli *c) {
    int w = 0;
    const sb_command_def *cmd = NULL;
    if (c->npos) {
        char *words[3] = {"shadowbench", (char *)c->pos[0], c->npos > 1 ? (char *)c->pos[1] : NULL};
        cmd = sb_command_find(c->npos > 1 ? 3 : 2, words, &w);
        if (!cmd || w != c->npos) return bad("help: no command '%s' (see shadowbench --help)", c->pos[0]);
    }
    if (c->o.format == SB_DOC_TEXT) sb_cli_help(stdout, sb_commands, cmd);
    else if (cmd) return bad("help %s: --format markdown and man write the whole reference; leave the command out",
                             cmd->name);
    else sb_cli_doc(stdout, sb_commands, (sb_doc_format)c->o.format);
    return SB_EXIT_OK;
}

/* ---- the table ---- */

#define MEASURING (SB_CMDF_ANY | SB_CMDF_CONTEXT | SB_CMDF_MEASURE | SB_CMDF_SCENES | SB_CMDF_INTERRUPT | SB_CMDF_RESULTS)

const sb_command_def sb_commands[SB_CMD_COUNT] = {
    {SB_CMD_RUN, "run", "run SCENE PATH SPEC... [--resume DIR]",
     "render each technique spec along the path, write CSV (--resume: keep DIR's complete runs)",
     MEASURING | SB_CMDF_MATRIX, cmd_run},
    {SB_CMD_BATCH, "batch", "batch FILE [--shard I/N] [--resume DIR] [--dry-run]", "run a matrix from a batch file",
     MEASURING | SB_CMDF_MATRIX, cmd_batch},
    {SB_CMD_COMPARE, "compare",
     "compare BASE NEW [--metric M,...] [--threshold PCT] [--format text|csv|markdown]\n"
     "compare RESULTS --pair KEY=A,B",
     "two results sets, or the runs of one set that differ only in KEY; exit 1 on a regression, "
     "3 when none but a compared timing is UNSTABLE",
     SB_CMDF_ANY, cmd_compare},
    {SB_CMD_MERGE, "merge", "merge DIR... --out DIR", "merge shard outputs into one results set", SB_CMDF_ANY, cmd_merge},
    {SB_CMD_TUNE, "tune",
     "tune SCENE [PATH] [SPEC...] --max-err E | --budget-ms B [--max-flicker F] [--max-mb M] [--techniques LIST] "
     "[--time-limit D] [--resume DIR]",
     "the cheapest settings within an error bound (or the most accurate within a frame-time budget), "
     "by successive halving",
     MEASURING, cmd_tune},
    {SB_CMD_STRESS, "stress", "stress [CASE|all [SPEC...]]",
     "numerical-stability battery; SPECs replace the battery's techniques",
     SB_CMDF_ANY | SB_CMDF_CONTEXT | SB_CMDF_INTERRUPT, cmd_stress},
    {SB_CMD_HISTORY_ADD, "history add", "history add DIR...", "keep results sets in the history", SB_CMDF_ANY,
     cmd_history_add},
    {SB_CMD_HISTORY_LIST, "history list", "history list", "the nights of the history", SB_CMDF_ANY, cmd_history_list},
    {SB_CMD_HISTORY_REGRESSIONS, "history regressions",
     "history regressions [--metric M,...] [--since DATE] [--recent N] [--noise-floor PCT] [--format text|csv]",
     "changes across the nights per series (exit 1 when a regression not accepted starts in the newest --recent "
     "nights)",
     SB_CMDF_ANY, cmd_history_regressions},
    {SB_CMD_HISTORY_ANNOTATE, "history annotate", "history annotate NIGHT|COMMIT TEXT [--series PATTERN] [--accept]",
     "a note on a night (--accept: the change starting then was meant)", SB_CMDF_ANY, cmd_history_annotate},
    {SB_CMD_HISTORY_CHECK, "history check", "history check DIR [--nights N] [--metric M,...] [--noise-floor PCT]",
     "a results set against its series' newest nights (exit 1 beyond their band)", SB_CMDF_ANY, cmd_history_check},
    {SB_CMD_BISECT, "bisect",
     "bisect GOOD BAD [--metric M] [--repeat K] [--threshold PCT] [--workdir DIR] [--build-type T] -- run SCENE PATH SPEC "
     "[run options]\n"
     "bisect --history FILE --series TEXT --metric M [-- run options]",
     "the first commit that changes a run's metric: built in a scratch worktree, measured against "
     "GOOD (timings paired and interleaved); exit 1 when GOOD and BAD do not differ",
     SB_CMDF_ANY | SB_CMDF_TAIL, cmd_bisect},
    {SB_CMD_REPORT, "report", "report [DIR | --history FILE] [--out SITE]", "a static site to open in a browser",
     SB_CMDF_ANY, cmd_report},
    {SB_CMD_FLIP, "flip", "flip REFERENCE.png TEST.png [--ppd N] [--map FILE.png]",
     "LDR-FLIP of two images (the perceptual difference a viewer sees between them): the mean, 95th percentile "
     "and largest per-pixel error; --map writes the per-pixel error",
     SB_CMDF_ANY, cmd_flip},
    {SB_CMD_TECHNIQUES, "techniques", "techniques [--format text|markdown]\ntechniques --all-pairs SPEC...", "list techniques and their parameters",
     SB_CMDF_ANY, cmd_techniques},
    {SB_CMD_COLUMNS, "columns", "columns [--format csv|markdown]", "the CSV columns (per frame and per run)",
     SB_CMDF_ANY, cmd_columns},
    {SB_CMD_INFO, "info", "info [SCENE]", "backends, GL renderer and features; or what a scene holds",
     SB_CMDF_ANY | SB_CMDF_SCENES, cmd_info},
    {SB_CMD_PATH, "path", "path PATH [SCENE] [--frames N]", "print the sampled cameras as CSV",
     SB_CMDF_ANY | SB_CMDF_SCENES, cmd_path},
    {SB_CMD_CAMERAS, "cameras", "cameras SCENE PATH [--frames N] [--size WxH] [--twins] [--format json|gltf]",
     "every frame's camera exactly as a run renders it (position, target, up, field of view, near, far, view and "
     "projection matrices, viewport) and the scene's lights, as JSON, or as a glTF of an animated camera and the "
     "lights that an engine imports: another renderer draws the same frames",
     SB_CMDF_ANY | SB_CMDF_SCENES, cmd_cameras},
    {SB_CMD_SCORE, "score",
     "score SCENE PATH DIR --mask FILE [--pattern FILE] [--renderer NAME] [--params TEXT] [--frames N] [--size WxH] "
     "[--sun AZ,EL]",
     "another renderer's frames (its visibility and the mask of what it drew, on the cameras `cameras` exported) "
     "scored against the exact reference like a technique's run: a results set whose technique is the renderer; "
     "a frame whose mask does not line up with the scene is refused",
     SB_CMDF_ANY | SB_CMDF_CONTEXT | SB_CMDF_SCENES | SB_CMDF_INTERRUPT | SB_CMDF_RESULTS, cmd_score},
    {SB_CMD_HELP, "help", "help [COMMAND] [--format text|markdown|man]",
     "every command and option (COMMAND: its options), or the reference docs/cli.md and the man page hold",
     SB_CMDF_ANY, cmd_help},
};

const sb_command_def *sb_command_find(int argc, char **argv, int *words) {
    for (int c = 0; c < SB_CMD_COUNT; c++) {
        const char *name = sb_commands[c].name, *space = strchr(name, ' ');
        size_t head = space ? (size_t)(space - name) : strlen(name);
        if (argc < 2 || strncmp(argv[1], name, head) || argv[1][head]) continue;
        if (!space) return *words = 1, &sb_commands[c];
        if (argc > 2 && !strcmp(argv[2], space + 1)) return *words = 2, &sb_commands[c];
    }
    return NULL;
}

/* "history": the subcommands it has, for a line that names none or another. */
static int bad_subcommand(int argc, char **argv) {
    char subs[256] = "";
    for (int c = 0; c < SB_CMD_COUNT; c++) {
        const char *name = sb_commands[c].name, *space = strchr(name, ' ');
        if (!space || strncmp(name, argv[1], (size_t)(space - name)) || argv[1][space - name]) continue;
        size_t l = strlen(subs);
        snprintf(subs + l, sizeof subs - l, "%s%s", l ? ", " : "", space + 1);
    }
    if (!subs[0]) return bad("unknown command '%s' (see shadowbench --help)", argv[1]);
    fprintf(stderr, "shadowbench: %s: %s%s%s (one of %s; see shadowbench --help)\n", argv[1],
            argc > 2 ? "unknown subcommand '" : "a subcommand is needed", argc > 2 ? argv[2] : "", argc > 2 ? "'" : "",
            subs);
    return SB_EXIT_BAD_INPUT;
}

/* Splits off what follows "--" for a command that passes it on; returns where the options end. */
static int split_tail(sb_cli *c, int argc, char **argv, int first) {
    if (!(c->cmd->flags & SB_CMDF_TAIL)) return argc;
    for (int i = first; i < argc; i++)
        if (!strcmp(argv[i], "--")) {
            c->tail = argv + i + 1;
            c->ntail = argc - i - 1;
            return i;
        }
    return argc;
}

int sb_command_main(int argc, char **argv, const char *version, const char *commit) {
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        sb_cli_help(argc < 2 ? stderr : stdout, sb_commands, NULL);
        return argc < 2 ? SB_EXIT_BAD_INPUT : SB_EXIT_OK;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("shadowbench %s\n", version);
        return SB_EXIT_OK;
    }
    sb_cli c;
    memset(&c, 0, sizeof c);
    int words = 0;
    c.cmd = sb_command_find(argc, argv, &words);
    if (!c.cmd) return bad_subcommand(argc, argv);
    int first = 1 + words, parsed = split_tail(&c, argc, argv, first);
    for (int i = first; i < parsed; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            sb_cli_help(stdout, sb_commands, c.cmd);
            return SB_EXIT_OK;
        }
    c.argc = argc;
    c.argv = argv;
    c.version = version;
    c.commit = commit;
    c.pos = sb_xcalloc((size_t)argc, sizeof *c.pos);   /* never more than the arguments */
    sb_cli_defaults(&c.o, c.cmd);
    c.o.run.progress = isatty(2);
    sb_err err;
    if (!sb_cli_parse(&c.o, c.cmd, parsed, argv, first, c.pos, &c.npos, &err)) {
        free(c.pos);
        return bad("%s", err.msg);
    }
    if (c.o.quiet) sb_set_quiet(true), c.o.run.progress = false;
    if (c.o.verbose) sb_set_verbose(true);
    if (!check_out(&c, &err)) {
        free(c.pos);
        return bad("%s", err.msg);
    }
    if (c.cmd->flags & SB_CMDF_INTERRUPT) sb_interrupt_install();
    int rc = c.cmd->handler(&c);
    if (rc != SB_EXIT_BAD_INPUT && sb_result_writes_failed()) {   /* a cron job must not read a lost row as success */
        fprintf(stderr, "shadowbench: results could not all be written (the files are named above): exit status %d\n",
                SB_EXIT_WRITE);
        rc = SB_EXIT_WRITE;
    }
    free(c.pos);
    return rc;
}
