/* bisect.c - `shadowbench bisect` (bisect.h). */
#define _DEFAULT_SOURCE /* realpath */
#include "bisect.h"

#include <errno.h>
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "columns.h"
#include "history.h"
#include "options.h"
#include "stats.h"
#include "table.h"
#include "util.h"

#define MAX_ARGS 256

/* ---- processes ---- */

/* Runs argv (argv[0] looked up in PATH) in cwd (NULL: here). Its stdout goes
 * to cap (NUL-terminated, at most caplen - 1 bytes kept; NULL: to log), its
 * stderr to log (appended; NULL: /dev/null). Returns the exit status (128 +
 * the signal when one killed it), or -1 when it could not be started. */
static int spawn(char *const argv[], const char *cwd, const char *log, char *cap, size_t caplen) {
    int pfd[2] = {-1, -1};
    if (cap && pipe(pfd) != 0) return -1;
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        int lfd = open(log ? log : "/dev/null", O_WRONLY | O_CREAT | O_APPEND, 0644);
        int nfd = open("/dev/null", O_RDONLY);
        if (nfd >= 0) dup2(nfd, 0);
        if (lfd >= 0) dup2(lfd, 2);
        if (cap) dup2(pfd[1], 1), close(pfd[0]), close(pfd[1]);
        else if (lfd >= 0) dup2(lfd, 1);
        if (cwd && chdir(cwd) != 0) _exit(127);
        execvp(argv[0], argv);
        _exit(127);
    }
    size_t n = 0;
    if (cap) {
        close(pfd[1]);
        char buf[4096];
        ssize_t got;
        while ((got = read(pfd[0], buf, sizeof buf)) > 0 || (got < 0 && errno == EINTR)) {
            if (got <= 0) continue;
            size_t keep = caplen > n + 1 ? caplen - 1 - n : 0;
            if ((size_t)got < keep) keep = (size_t)got;
            memcpy(cap + n, buf, keep);
            n += keep;
        }
        close(pfd[0]);
        cap[n] = 0;
        while (n && (cap[n - 1] == '\n' || cap[n - 1] == '\r')) cap[--n] = 0;
    }
    int st;
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR) return -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
}

/* git -C repo ARGS... (NULL-terminated), its stdout in out; true on exit 0. */
static bool git(const char *repo, char *out, size_t len, ...) {
    char *argv[32] = {"git", "-C", (char *)repo};
    int n = 3;
    va_list ap;
    va_start(ap, len);
    for (char *a; n < 31 && (a = va_arg(ap, char *));) argv[n++] = a;
    va_end(ap);
    argv[n] = NULL;
    char dummy[256];
    return spawn(argv, NULL, NULL, out ? out : dummy, out ? len : sizeof dummy) == 0;
}

/* ---- the bisection ---- */

typedef struct commit {
    char sha[48], subject[160];
    bool skipped;
    double build_s;             /* what building it took here (0: built before) */
    char bin[2300];             /* its binary once built ("" not yet) */
} commit;

typedef struct bisect {
    const sb_bisect_cmd *cmd;
    char repo[2048], work[2048], tree[2100];
    sb_metric_cols mc;
    const char *metric;
    bool timing;
    int repeat;                 /* timings: pairs a step */
    double threshold;           /* timings: percent */
    char good_rev[256], bad_rev[256];
    char *args[MAX_ARGS];       /* run SCENE PATH SPEC [options] */
    int nargs;
    /* the --history form's run, which args point into */
    char scene[1024], path[1024], spec[2200], size[64];
    int runs;                   /* results folders made, for their names */
    int cand_renders, good_renders, steps;
    int measured;               /* commits measured against GOOD: BAD and the candidates */
} bisect;

static int bad_input(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static int bad_input(const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fflush(stdout);   /* what was printed before it comes first */
    fputs("shadowbench: bisect: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    return SB_EXIT_BAD_INPUT;
}

/* Builds c (its binary kept in work/bin/SHA): false when it does not build. */
static bool build(bisect *b, commit *c) {
    char bin_dir[2200], log[2200];
    const char *type = b->cmd->build_type ? b->cmd->build_type : "release";
    const bool release = !strcmp(type, "release");   /* another type's binaries and build folder are its own */
    snprintf(bin_dir, sizeof bin_dir, "%s/bin/%s%s%s", b->work, c->sha, release ? "" : ".", release ? "" : type);
    snprintf(c->bin, sizeof c->bin, "%s/shadowbench", bin_dir);
    snprintf(log, sizeof log, "%s/logs/%.12s.build.log", b->work, c->sha);
    if (access(c->bin, X_OK) == 0) return true;   /* built by an earlier bisect */
    char failed[2300];
    snprintf(failed, sizeof failed, "%s/logs/%.12s.failed", b->work, c->sha);
    if (access(failed, F_OK) == 0) return c->bin[0] = 0, false;
    double t0 = sb_now_ms();
    unlink(log);
    char *co[] = {"git", "checkout", "--quiet", "--force", "--detach", c->sha, NULL};
    bool ok = spawn(co, b->tree, log, NULL, 0) == 0;
    char ninja_file[2200];
    char build_dir[64], buildtype[64];
    snprintf(build_dir, sizeof build_dir, "build-bisect%s%s", release ? "" : "-", release ? "" : type);
    snprintf(buildtype, sizeof buildtype, "--buildtype=%s", type);
    snprintf(ninja_file, sizeof ninja_file, "%s/%s/build.ninja", b->tree, build_dir);
    if (ok && access(ninja_file, F_OK) != 0) {
        /* a build (release unless --build-type) without the tests and the image stack, which a run needs
           neither of; a commit older than those options is configured without them */
        char *setup[] = {"meson", "setup", build_dir, buildtype, "-Dtests=false", "-Dimages=disabled", NULL};
        char *plain[] = {"meson", "setup", build_dir, buildtype, NULL};
        ok = spawn(setup, b->tree, log, NULL, 0) == 0 || spawn(plain, b->tree, log, NULL, 0) == 0;
    }
    char *ninja[] = {"ninja", "-C", build_dir, NULL};
    if (ok) ok = spawn(ninja, b->tree, log, NULL, 0) == 0;
    /* the binary and the bundled scenes it finds beside itself (a commit may change how they are made) */
    sb_err err;
    char built[2200], from[2600], to[2600];
    snprintf(built, sizeof built, "%s/%s", b->tree, build_dir);
    DIR *d = ok ? opendir(built) : NULL;
    ok = d && sb_mkdir_p(bin_dir, &err);
    for (struct dirent *e; ok && (e = readdir(d));) {
        size_t l = strlen(e->d_name);
        bool scene = (l > 4 && !strcmp(e->d_name + l - 4, ".glb")) || (l > 5 && !strcmp(e->d_name + l - 5, ".path"));
        if (!scene && strcmp(e->d_name, "shadowbench")) continue;
        snprintf(from, sizeof from, "%s/%s", built, e->d_name);
        snprintf(to, sizeof to, "%s/%s", bin_dir, e->d_name);
        ok = sb_copy_file(from, to, &err);
    }
    if (d) closedir(d);
    if (ok) ok = chmod(c->bin, 0755) == 0;
    if (!ok) {
        /* remembered: a later bisect over the same commit skips it at once */
        char failed[2300];
        snprintf(failed, sizeof failed, "%s/logs/%.12s.failed", b->work, c->sha);
        sb_write_file_atomic(failed, "", 0, &err);
        c->bin[0] = 0;
        return false;
    }
    c->build_s = (sb_now_ms() - t0) / 1000;
    return true;
}

static void print_built(const commit *c) {
    if (c->build_s > 0) printf("built in %.1f s", c->build_s);
    else printf("built before");
}

/* One run of bin: the metric's figure, or NaN (why says). */
static double measure(bisect *b, const commit *c, char *why, size_t wlen) {
    char log[2200], base[2200];
    snprintf(base, sizeof base, "%s/runs/%d", b->work, ++b->runs);
    snprintf(log, sizeof log, "%s/logs/run-%d.log", b->work, b->runs);
    char *argv[MAX_ARGS + 8];
    int n = 0;
    argv[n++] = (char *)c->bin;
    for (int i = 0; i < b->nargs; i++) argv[n++] = b->args[i];
    argv[n++] = "--out";
    argv[n++] = base;
    argv[n++] = "--quiet";
    argv[n] = NULL;
    char dir[8192];
    int rc = spawn(argv, NULL, log, dir, sizeof dir);
    char *last = strrchr(dir, '\n');
    last = last ? last + 1 : dir;
    double v = NAN;
    char path[8300];
    snprintf(path, sizeof path, "%s/summary.csv", last);
    sb_table t;
    sb_err err;
    if (rc != 0 && rc != SB_EXIT_FAILED) {
        snprintf(why, wlen, "the run exited %d (log: %s)", rc, log);
    } else if (!sb_table_load(&t, path, &err)) {
        snprintf(why, wlen, "no summary (%s; log: %s)", err.msg, log);
    } else {
        if (t.nrows != 1) snprintf(why, wlen, "%d runs in its summary, not 1", t.nrows);
        else if (sb_status_of(sb_table_get(&t, 0, "status")) != SB_STATUS_OK)
            snprintf(why, wlen, "the run %s: %s", sb_table_get(&t, 0, "status"), sb_table_get(&t, 0, "reason"));
        else if (sb_table_col(&t, b->mc.center) < 0 || !sb_parse_double(sb_table_get(&t, 0, b->mc.center), &v))
            snprintf(why, wlen, "no %s in its summary", b->mc.center), v = NAN;
        sb_table_free(&t);
    }
    char *rm[] = {"rm", "-rf", base, NULL};
    spawn(rm, NULL, NULL, NULL, 0);
    if (!isnan(v)) unlink(log);
    return v;
}

/* A timing step: `pairs` runs of cand and of good, alternately first. */
typedef struct paired {
    double diff, ci, good, cand;   /* mean difference cand - good, its 95% CI, the means */
    int n;
    sb_paired whole;               /* the same, as stats.h computes and judges it */
} paired;

static bool pair_runs(bisect *b, const commit *cand, const commit *good, int pairs, double *dc, double *dg, int *n,
                      char *why, size_t wlen) {
    for (int i = 0; i < pairs; i++) {
        double x = NAN, y = NAN;
        if (i % 2 == 0) x = measure(b, cand, why, wlen), y = isnan(x) ? NAN : measure(b, good, why, wlen);
        else y = measure(b, good, why, wlen), x = isnan(y) ? NAN : measure(b, cand, why, wlen);
        if (isnan(x) || isnan(y)) return false;
        dc[*n] = x, dg[*n] = y, (*n)++;
        b->cand_renders++, b->good_renders++;
    }
    return true;
}

static paired summarize(const double *dc, const double *dg, int n) {
    sb_paired s = sb_paired_compute(dg, dc, n);   /* the candidate against GOOD, pair by pair */
    return (paired){.n = s.n, .good = s.a, .cand = s.b, .diff = s.diff, .ci = s.ci, .whole = s};
}

static void print_pair(const bisect *b, const paired *p) {
    printf("%s %.4g against GOOD %.4g: %+.4g %s ± %.2g (%+.1f %%) over %d pairs", b->metric, p->cand, p->good, p->diff,
           b->mc.unit, p->ci, 100 * p->diff / p->good, p->n);
}

/* ---- the command, in steps; each returns an exit status, or -1 to go on ---- */

/* The metric, the repository and the defaults. */
static int setup(bisect *b, const sb_bisect_cmd *cmd) {
    b->cmd = cmd;
    b->metric = cmd->metric ? cmd->metric : sb_columns_role(SB_ROLE_TIME);
    if (!sb_columns_metric(b->metric, &b->mc))
        return bad_input("unknown metric '%s' (a summary metric: `shadowbench columns` lists them)", b->metric);
    b->timing = b->mc.unit && !strcmp(b->mc.unit, "ms");
    b->repeat = cmd->repeat > 0 ? cmd->repeat : 5;
    b->threshold = cmd->threshold_pct > 0 ? cmd->threshold_pct : 5;
    if (!git(".", b->repo, sizeof b->repo, "rev-parse", "--show-toplevel", NULL))
        return bad_input("not in a git repository (run it in the shadowbench checkout to bisect)");
    return -1;
}

/* The newest regression of a series of the metric in the history. */
static int pick_regression(bisect *b, sb_history_change *pick) {
    const sb_bisect_cmd *cmd = b->cmd;
    sb_err err;
    sb_history *h = sb_history_open(cmd->history, false, &err);
    if (!h) return bad_input("%s", err.msg);
    sb_history_query q = {.metrics = {b->metric}, .nmetrics = 1};
    sb_history_change *ch = NULL;
    int n = sb_history_changes(h, &q, &ch, &err), found = -1;
    sb_history_close(h);
    if (n < 0) return bad_input("%s", err.msg);
    for (int i = 0; i < n; i++)
        if (ch[i].regression && (strstr(ch[i].label, cmd->series) || strstr(ch[i].key, cmd->series)) &&
            (found < 0 || ch[i].night_after > ch[found].night_after))
            found = i;
    if (found >= 0) *pick = ch[found];
    free(ch);
    if (found < 0)
        return bad_input("%s: no regression of %s in a series matching '%s' (`history regressions` lists them)",
                         cmd->history, b->metric, cmd->series);
    return -1;
}

/* The --history form: the regression names the commits and the run. */
static int from_history(bisect *b) {
    const sb_bisect_cmd *cmd = b->cmd;
    if (!cmd->series || !cmd->metric) return bad_input("--history needs --series TEXT and --metric M");
    if (cmd->good || cmd->bad) return bad_input("give GOOD BAD or --history, not both");
    sb_history_change pick;
    int rc = pick_regression(b, &pick);
    if (rc >= 0) return rc;
    snprintf(b->good_rev, sizeof b->good_rev, "%s", pick.commit_before);
    snprintf(b->bad_rev, sizeof b->bad_rev, "%s", pick.commit_after);
    printf("regression: %s %s %+.1f %% on night %lld (%s..%s)\n", pick.label, b->metric, 100 * pick.rel,
           pick.night_after, b->good_rev, b->bad_rev);
    const sb_series *se = &pick.series;
    snprintf(b->scene, sizeof b->scene, "%s", se->scene);
    snprintf(b->path, sizeof b->path, "%s", se->path);
    snprintf(b->size, sizeof b->size, "%s", se->size);
    snprintf(b->spec, sizeof b->spec, "%s%s%.2048s", se->technique, se->params[0] ? ":" : "", se->params);
    char *run[] = {"run", b->scene, b->path, b->spec, "--size", b->size};
    for (size_t i = 0; i < SB_COUNT(run); i++) b->args[b->nargs++] = run[i];
    if (se->indirect) b->args[b->nargs++] = "--submit", b->args[b->nargs++] = "indirect";
    /* "-dirty" builds are bisected from their commit */
    for (char *r = b->good_rev; r; r = r == b->good_rev ? b->bad_rev : NULL) {
        char *d = strstr(r, "-dirty");
        if (d) *d = 0;
    }
    if (!strcmp(b->good_rev, b->bad_rev))
        return bad_input("%s: the nights either side of the change ran the same commit (%s): nothing to bisect "
                         "(did the machine change? `history list`)", cmd->history, b->good_rev);
    return -1;
}

/* The run after `--`, checked as `shadowbench run` would take it before anything is built. */
static int take_run(bisect *b) {
    const sb_bisect_cmd *cmd = b->cmd;
    if (!cmd->history) {
        if (!cmd->good || !cmd->bad) return bad_input("usage: shadowbench bisect GOOD BAD -- run SCENE PATH SPEC [options]");
        snprintf(b->good_rev, sizeof b->good_rev, "%s", cmd->good);
        snprintf(b->bad_rev, sizeof b->bad_rev, "%s", cmd->bad);
        if (cmd->run_argc < 1 || strcmp(cmd->run_argv[0], "run"))
            return bad_input("after `--` give the run to measure: run SCENE PATH SPEC [run options]");
    }
    for (int i = 0; i < cmd->run_argc && b->nargs < MAX_ARGS; i++) {
        const char *a = cmd->run_argv[i];
        if (!strcmp(a, "--out") || !strcmp(a, "--resume") || !strncmp(a, "--out=", 6) || !strncmp(a, "--resume=", 9))
            return bad_input("%s: bisect chooses where each run goes; leave it out", a);
        if (!strcmp(a, "--repeat") && b->timing)
            return bad_input("--repeat: give it to bisect (before `--`): its runs are paired and interleaved");
        b->args[b->nargs++] = cmd->run_argv[i];
    }
    /* the run's options and specs, as this shadowbench reads them: a typo is found now, not after a build */
    sb_cli_opts o;
    sb_cli_defaults(&o, cmd->run_cmd);
    const char **pos = sb_xcalloc((size_t)b->nargs + 1, sizeof *pos);
    int npos = 0;
    sb_err err;
    bool ok = sb_cli_parse(&o, cmd->run_cmd, b->nargs, b->args, 1, pos, &npos, &err);
    if (ok && npos < 3) ok = sb_fail(&err, "the run needs SCENE PATH SPEC");
    sb_run_spec *runs = NULL;
    int nruns = 0;
    for (int i = 2; ok && i < npos; i++) ok = sb_spec_expand(pos[i], NULL, &runs, &nruns, &err);
    if (ok && nruns != 1) ok = sb_fail(&err, "the run has %d runs: bisect measures one run of one technique", nruns);
    free(runs);
    free(pos);
    return ok ? -1 : bad_input("the run after `--`: %s", err.msg);
}

/* The commits: GOOD, then first-parent descendants up to BAD, with their subjects. */
static int list_commits(bisect *b, commit **out, int *count) {
    commit good = {0}, badc = {0};
    char rev[300];
    snprintf(rev, sizeof rev, "%s^{commit}", b->good_rev);
    if (!git(b->repo, good.sha, sizeof good.sha, "rev-parse", "--verify", "--quiet", rev, NULL))
        return bad_input("GOOD '%s' is not a commit of %s", b->good_rev, b->repo);
    snprintf(rev, sizeof rev, "%s^{commit}", b->bad_rev);
    if (!git(b->repo, badc.sha, sizeof badc.sha, "rev-parse", "--verify", "--quiet", rev, NULL))
        return bad_input("BAD '%s' is not a commit of %s", b->bad_rev, b->repo);
    if (!strcmp(good.sha, badc.sha)) {
        printf("GOOD and BAD are the same commit (%.12s): they do not differ\n", good.sha);
        return SB_EXIT_FAILED;
    }
    if (!git(b->repo, NULL, 0, "merge-base", "--is-ancestor", good.sha, badc.sha, NULL))
        return bad_input("GOOD %.12s is not an ancestor of BAD %.12s", good.sha, badc.sha);
    char range[120];
    snprintf(range, sizeof range, "%s..%s", good.sha, badc.sha);
    char *buf = sb_xmalloc(1 << 16);
    if (!git(b->repo, buf, 1 << 16, "rev-list", "--first-parent", "--ancestry-path", "--reverse", range, NULL)) {
        free(buf);
        return bad_input("cannot list the commits %s", range);
    }
    int n = 0, cap = 16;
    commit *c = sb_xcalloc((size_t)cap, sizeof *c);
    c[n++] = good;
    for (char *line = strtok(buf, "\n"); line; line = strtok(NULL, "\n")) {
        if (n == cap) c = sb_xrealloc(c, sizeof *c * (size_t)(cap *= 2)), memset(c + n, 0, sizeof *c * (size_t)(cap - n));
        snprintf(c[n++].sha, sizeof c->sha, "%s", line);
    }
    free(buf);
    if (strcmp(c[n - 1].sha, badc.sha)) {
        free(c);
        return bad_input("BAD %.12s is not on GOOD's first-parent line", badc.sha);
    }
    for (int i = 0; i < n; i++) git(b->repo, c[i].subject, sizeof c[i].subject, "log", "-1", "--format=%s", c[i].sha, NULL);
    *out = c;
    *count = n;
    return -1;
}

/* The scratch worktree and the folders of binaries, logs and runs, kept for the next bisect. */
static int make_workdir(bisect *b, const char *good_sha) {
    char common[1900];
    if (b->cmd->workdir) snprintf(b->work, sizeof b->work, "%.2000s", b->cmd->workdir);
    else {
        if (!git(b->repo, common, sizeof common, "rev-parse", "--git-common-dir", NULL)) return bad_input("no git directory");
        char abs[2000];
        if (common[0] != '/') snprintf(abs, sizeof abs, "%.1000s/%.990s", b->repo, common);
        else snprintf(abs, sizeof abs, "%.1990s", common);
        snprintf(b->work, sizeof b->work, "%.1990s/shadowbench-bisect", abs);
    }
    sb_err err;
    char sub[2100];
    const char *subs[] = {"bin", "logs", "runs"};
    for (int i = 0; i < 3; i++) {
        snprintf(sub, sizeof sub, "%.2040s/%s", b->work, subs[i]);
        if (!sb_mkdir_p(sub, &err)) return bad_input("%s", err.msg);
    }
    snprintf(b->tree, sizeof b->tree, "%.2040s/tree", b->work);
    char dotgit[2200];
    snprintf(dotgit, sizeof dotgit, "%.2090s/.git", b->tree);
    if (access(dotgit, F_OK) == 0) return -1;
    git(b->repo, NULL, 0, "worktree", "prune", NULL);
    if (!git(b->repo, NULL, 0, "worktree", "add", "--detach", "--force", b->tree, good_sha, NULL))
        return bad_input("cannot make the scratch worktree %s", b->tree);
    return -1;
}

/* GOOD and BAD built. */
static int build_ends(bisect *b, commit *c, int last) {
    printf("bisect %s (%s) over %d commit(s) after GOOD %.12s up to BAD %.12s\n", b->metric,
           b->timing ? "paired timing" : "exact", last, c[0].sha, c[last].sha);
    printf("run:");
    for (int i = 0; i < b->nargs; i++) printf(" %s", b->args[i]);
    printf("\n");
    fflush(stdout);
    for (int e = 0; e <= last; e += last) {
        if (!build(b, &c[e]))
            return bad_input("%s %.12s (%s) does not build: log %s/logs/%.12s.build.log", e ? "BAD" : "GOOD", c[e].sha,
                             c[e].subject, b->work, c[e].sha);
        printf("%s %.12s  %s  ", e ? "BAD " : "GOOD", c[e].sha, c[e].subject);
        print_built(&c[e]);
        printf("\n");
    }
    return -1;
}

/* Pairs of x and GOOD until the difference is told from `from` (the middle), up to four times --repeat. */
static bool pairs_until(bisect *b, const commit *x, const commit *good, double from, paired *p, char *why, size_t wlen) {
    double dc[4 * 100], dg[4 * 100];
    int k = 0;
    bool ok = pair_runs(b, x, good, b->repeat, dc, dg, &k, why, wlen);
    if (ok) *p = summarize(dc, dg, k);
    while (ok && !(fabs(p->diff - from) > p->ci) && k + b->repeat <= 4 * b->repeat) {
        ok = pair_runs(b, x, good, b->repeat, dc, dg, &k, why, wlen);
        if (ok) *p = summarize(dc, dg, k);
    }
    return ok;
}

/* BAD against GOOD: a timing must differ beyond the noise and the threshold, an exact figure at all. */
static int measure_ends(bisect *b, commit *c, int last, paired *whole, double *good_v) {
    char why[8600];
    if (b->timing) {
        if (!pairs_until(b, &c[last], &c[0], 0, whole, why, sizeof why))
            return bad_input("GOOD or BAD cannot be measured: %s", why);
        b->measured++;
        printf("BAD against GOOD: ");
        print_pair(b, whole);
        printf("\n");
        if (!sb_paired_differs(&whole->whole, b->threshold)) {
            printf("GOOD and BAD do not differ beyond the noise: %+.4g %s ± %.2g (%+.1f %%; --threshold %g %%)\n",
                   whole->diff, b->mc.unit, whole->ci, 100 * whole->diff / whole->good, b->threshold);
            return SB_EXIT_FAILED;
        }
        return -1;
    }
    *good_v = measure(b, &c[0], why, sizeof why);
    double bad_v = isnan(*good_v) ? NAN : measure(b, &c[last], why, sizeof why);
    if (isnan(*good_v) || isnan(bad_v)) return bad_input("GOOD or BAD cannot be measured: %s", why);
    b->good_renders++, b->cand_renders++, b->measured++;
    printf("BAD against GOOD: %s %.9g against %.9g\n", b->metric, bad_v, *good_v);
    if (*good_v == bad_v) {
        printf("GOOD and BAD do not differ: %s is %.9g on both\n", b->metric, *good_v);
        return SB_EXIT_FAILED;
    }
    return -1;
}

/* One candidate judged: 1 bad, 0 good, -1 skipped (cannot be built or measured). */
static int judge(bisect *b, commit *x, const commit *good, const paired *whole, double good_v) {
    char why[8600];
    if (!build(b, x)) {
        printf("  skipped: does not build (log %s/logs/%.12s.build.log)\n", b->work, x->sha);
        return -1;
    }
    printf("  ");
    print_built(x);
    printf(": ");
    bool is_bad;
    if (b->timing) {
        paired p;
        if (!pairs_until(b, x, good, whole->diff / 2, &p, why, sizeof why)) {
            printf("skipped: cannot be measured (%s)\n", why);
            return -1;
        }
        print_pair(b, &p);
        is_bad = (p.diff - whole->diff / 2) * (whole->diff > 0 ? 1 : -1) > 0;
    } else {
        double v = measure(b, x, why, sizeof why);
        if (isnan(v)) {
            printf("skipped: cannot be measured (%s)\n", why);
            return -1;
        }
        b->cand_renders++;
        printf("%s %.9g against GOOD %.9g", b->metric, v, good_v);
        is_bad = v != good_v;
    }
    b->measured++;
    printf("  -> %s\n", is_bad ? "bad" : "good");
    fflush(stdout);
    return is_bad;
}

/* The bisection proper: lo is good, hi is bad; the nearest untried commit to the middle next. */
static void narrow(bisect *b, commit *c, int last, const paired *whole, double good_v, int *lo, int *hi) {
    *lo = 0, *hi = last;
    for (;;) {
        int pick = -1, mid = (*lo + *hi) / 2;
        for (int i = *lo + 1; i < *hi; i++)
            if (!c[i].skipped && (pick < 0 || abs(i - mid) < abs(pick - mid))) pick = i;
        if (pick < 0) return;
        commit *x = &c[pick];
        b->steps++;
        printf("step %d  %.12s  (%d of %d, %d left)  %s\n", b->steps, x->sha, pick, last, *hi - *lo - 1, x->subject);
        fflush(stdout);
        int v = judge(b, x, &c[0], whole, good_v);
        if (v < 0) x->skipped = true;
        else if (v) *hi = pick;
        else *lo = pick;
    }
}

static void print_result(const bisect *b, const commit *c, int last, int lo, int hi) {
    for (int i = 1; i < last; i++)
        if (c[i].skipped) printf("skipped %.12s %s\n", c[i].sha, c[i].subject);
    if (hi - lo > 1) {
        printf("the first bad commit is one of these (the others between could not be built or measured):\n");
        for (int i = lo + 1; i <= hi; i++) printf("  %.12s %s%s\n", c[i].sha, c[i].subject, c[i].skipped ? " (skipped)" : "");
    } else {
        printf("first bad commit: %s %s\n", c[hi].sha, c[hi].subject);
    }
    int bound = 2;
    while ((1 << (bound - 2)) < last) bound++;
    printf("measured: %d commit(s) against GOOD (BAD and %d candidate(s); ceil(log2 %d) + 2 = %d); runs: %d of theirs, "
           "%d of GOOD's\n", b->measured, b->measured - 1, last, bound, b->cand_renders, b->good_renders);
}

int sb_bisect_main(const sb_bisect_cmd *cmd) {
    bisect *b = sb_xcalloc(1, sizeof *b);
    commit *c = NULL;
    int n = 0, rc = setup(b, cmd);
    if (rc < 0 && cmd->history) rc = from_history(b);
    if (rc < 0) rc = take_run(b);
    if (rc < 0) rc = list_commits(b, &c, &n);
    if (rc < 0) rc = make_workdir(b, c[0].sha);
    if (rc < 0) rc = build_ends(b, c, n - 1);
    paired whole = {0};
    double good_v = NAN;
    if (rc < 0) rc = measure_ends(b, c, n - 1, &whole, &good_v);
    if (rc < 0) {
        int lo, hi;
        narrow(b, c, n - 1, &whole, good_v, &lo, &hi);
        print_result(b, c, n - 1, lo, hi);
        rc = SB_EXIT_OK;
    }
    free(c);
    free(b);
    return rc;
}

bool sb_git_is_ancestor(const char *ancestor, const char *rev) {
    char a[128], r[128];
    snprintf(a, sizeof a, "%s", ancestor);
    snprintf(r, sizeof r, "%s", rev);
    char *d = strstr(r, "-dirty");   /* a night built from a changed tree: its commit */
    if (d) *d = 0;
    return a[0] && r[0] && git(".", NULL, 0, "merge-base", "--is-ancestor", a, r, NULL);
}
