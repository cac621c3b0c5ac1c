/* batch.c - batch file parsing, matrix expansion, shards. */
#include "batch.h"

#include <stdlib.h>
#include <string.h>

static int find_path(const sb_batch *b, const char *name) {
    for (int i = 0; i < b->npaths; i++)
        if (!strcmp(b->paths[i].name, name)) return i;
    return -1;
}

static int find_scene(const sb_batch *b, const char *name) {
    for (int i = 0; i < b->nscenes; i++)
        if (!strcmp(b->scenes[i].name, name)) return i;
    return -1;
}

/* Splits a line into whitespace-separated tokens (in place); '#' ends it. */
static int tokens(char *line, char **tok, int max) {
    char *hash = strchr(line, '#');
    if (hash) *hash = 0;
    int n = 0;
    for (char *t = strtok(line, " \t\r"); t && n < max; t = strtok(NULL, " \t\r")) tok[n++] = t;
    return n;
}

typedef struct {
    char *only;                 /* "@a,b" scene filter, or NULL */
    char *specs[32];
    int nspecs;
    int line;
} run_line;

static bool line_applies(const run_line *rl, const char *scene) {
    if (!rl->only) return true;
    char buf[512];
    snprintf(buf, sizeof buf, "%s", rl->only);
    for (char *t = strtok(buf, ","); t; t = strtok(NULL, ","))
        if (!strcmp(t, scene)) return true;
    return false;
}

/* A rough cost model: frames x (geometry per pass x passes + shadow-map fill). */
static double run_cost(const sb_batch *b, const sb_batch_scene *sc, const sb_run_spec *spec) {
    double tris = (double)sb_scene_triangles(&sc->scene);
    double cascades = sb_param_num(&spec->params, "cascades");
    double res = sb_param_num(&spec->params, "res");
    if (isnan(cascades)) cascades = isnan(res) ? 0 : 1;
    if (isnan(res)) res = 0;
    double pixels = (double)b->opts.width * b->opts.height;
    double per_frame = tris * (1 + cascades) + cascades * res * res * 0.25 + pixels;
    if (!strcmp(spec->tech->name, "raycast")) per_frame += pixels * 20;
    return per_frame * (b->opts.frames + b->opts.warmup) * (b->opts.error_every > 0 ? 1.2 : 1.0);
}

static bool batch_build(sb_batch *b, const char *file, char *text, const sb_run_opts *base,
                        const char *const *cli_opts, int ncli, bool load, sb_err *err) {
    memset(b, 0, sizeof *b);
    b->file = sb_strdup(file);
    const char *slash = strrchr(file, '/');
    b->name = sb_strdup(slash ? slash + 1 : file);
    char *dot = strrchr(b->name, '.');
    if (dot && dot != b->name) *dot = 0;
    b->opts = *base;
    run_line *lines = NULL;
    int nlines = 0;
    bool ok = true;
    int lineno = 0;
    char *save = NULL;
    /* strtok_r over lines keeps empty lines out, so count them by hand */
    char *p = text;
    while (ok && p && *p) {
        lineno++;
        char *eol = strchr(p, '\n');
        if (eol) *eol = 0;
        char *line = p;
        p = eol ? eol + 1 : NULL;
        char *tok[64];
        int n = tokens(line, tok, 64);
        if (!n) continue;
        if (!strcmp(tok[0], "scene")) {
            if (n < 3 || n > 4) {
                ok = sb_fail(err, "%s:%d: expected 'scene NAME FILE [PATH-NAME]'", file, lineno);
            } else if (find_scene(b, tok[1]) >= 0) {
                ok = sb_fail(err, "%s:%d: scene '%s' is defined twice", file, lineno, tok[1]);
            } else {
                b->scenes = realloc(b->scenes, (size_t)(b->nscenes + 1) * sizeof *b->scenes);
                sb_batch_scene *sc = &b->scenes[b->nscenes++];
                memset(sc, 0, sizeof *sc);
                sc->name = sb_strdup(tok[1]);
                sc->file = sb_strdup(tok[2]);
                sc->path_name = n == 4 ? sb_strdup(tok[3]) : NULL;
                sc->line = lineno;
            }
        } else if (!strcmp(tok[0], "path")) {
            if (n != 3) {
                ok = sb_fail(err, "%s:%d: expected 'path NAME FILE'", file, lineno);
            } else if (find_path(b, tok[1]) >= 0) {
                ok = sb_fail(err, "%s:%d: path '%s' is defined twice", file, lineno, tok[1]);
            } else {
                b->paths = realloc(b->paths, (size_t)(b->npaths + 1) * sizeof *b->paths);
                b->paths[b->npaths++] = (sb_batch_path){sb_strdup(tok[1]), sb_strdup(tok[2]), lineno};
            }
        } else if (!strcmp(tok[0], "defaults")) {
            for (int i = 1; ok && i < n; i++) {
                if (!strcmp(tok[i], "--progress") || !strcmp(tok[i], "--quiet")) continue;
                if (!strcmp(tok[i], "--allow-external-uris")) {
                    b->opts.allow_external_uris = true;
                    continue;
                }
                sb_err e;
                int rc = sb_run_opts_set(&b->opts, tok[i], i + 1 < n ? tok[i + 1] : NULL, &e);
                if (rc < 0) ok = sb_fail(err, "%s:%d: %s", file, lineno, e.msg);
                else if (rc == 0) ok = sb_fail(err, "%s:%d: '%s' is not a run option", file, lineno, tok[i]);
                else i++;
            }
        } else {
            run_line rl = {0};
            rl.line = lineno;
            int first = 0;
            if (tok[0][0] == '@') {
                rl.only = sb_strdup(tok[0] + 1);
                first = 1;
                if (n == 1) ok = sb_fail(err, "%s:%d: '@%s' with no technique spec", file, lineno, rl.only);
            }
            for (int i = first; ok && i < n && rl.nspecs < 32; i++) {
                /* validate now: nothing renders before the whole file is known good */
                sb_run_spec *tmp = NULL;
                int nt = 0;
                char where[1100];
                snprintf(where, sizeof where, "%s:%d", file, lineno);
                ok = sb_spec_expand(tok[i], where, &tmp, &nt, err);
                free(tmp);
                if (ok) rl.specs[rl.nspecs++] = sb_strdup(tok[i]);
            }
            lines = realloc(lines, (size_t)(nlines + 1) * sizeof *lines);
            lines[nlines++] = rl;
        }
    }
    (void)save;
    /* command-line options win over the file's defaults */
    for (int i = 0; ok && i < ncli; i += 2) {
        sb_err e;
        if (sb_run_opts_set(&b->opts, cli_opts[i], cli_opts[i + 1], &e) < 0) ok = sb_fail(err, "%s", e.msg);
    }
    if (ok && !b->nscenes) ok = sb_fail(err, "%s: no 'scene' lines", file);
    if (ok && !nlines) ok = sb_fail(err, "%s: no run lines (technique specs)", file);
    for (int l = 0; ok && l < nlines; l++)
        if (lines[l].only) {
            char buf[512];
            snprintf(buf, sizeof buf, "%s", lines[l].only);
            for (char *t = strtok(buf, ","); ok && t; t = strtok(NULL, ","))
                if (find_scene(b, t) < 0) ok = sb_fail(err, "%s:%d: no scene named '%s'", file, lines[l].line, t);
        }
    for (int i = 0; ok && !load && i < b->nscenes; i++) {
        const char *pname = b->scenes[i].path_name;
        if (pname && find_path(b, pname) < 0)
            ok = sb_fail(err, "%s:%d: no path named '%s'", file, b->scenes[i].line, pname);
    }
    /* scenes and paths (no GL): contents decide run ids, sizes decide costs */
    for (int i = 0; ok && load && i < b->nscenes; i++) {
        sb_batch_scene *sc = &b->scenes[i];
        sb_err e;
        sb_scene_opts so = {.allow_external_uris = b->opts.allow_external_uris};
        if (!sb_scene_load(&sc->scene, sc->file, &so, &e)) {
            ok = sb_fail(err, "%s:%d: %s", file, sc->line, e.msg);
            break;
        }
        const char *pname = sc->path_name ? sc->path_name : sc->name;
        int pi = find_path(b, pname);
        if (sc->path_name && pi < 0) {
            ok = sb_fail(err, "%s:%d: no path named '%s'", file, sc->line, sc->path_name);
            break;
        }
        snprintf(sc->path_file, sizeof sc->path_file, "%s", pi >= 0 ? b->paths[pi].file : "auto");
        snprintf(sc->path_label, sizeof sc->path_label, "%s", pi >= 0 ? b->paths[pi].name : "auto");
        if (!sb_path_load(&sc->path, sc->path_file, &sc->scene, &e)) {
            ok = sb_fail(err, "%s:%d: %s", file, pi >= 0 ? b->paths[pi].line : sc->line, e.msg);
            break;
        }
    }
    /* the matrix */
    for (int i = 0; ok && load && i < b->nscenes; i++) {
        sb_batch_scene *sc = &b->scenes[i];
        sb_session ids;     /* just what sb_run_id reads */
        memset(&ids, 0, sizeof ids);
        ids.opts = b->opts;
        ids.scene.content_hash = sc->scene.content_hash;
        ids.path.content_hash = sc->path.content_hash;
        for (int l = 0; l < nlines; l++) {
            if (!line_applies(&lines[l], sc->name)) continue;
            for (int k = 0; k < lines[l].nspecs; k++) {
                sb_run_spec *rs = NULL;
                int nr = 0;
                sb_spec_expand(lines[l].specs[k], NULL, &rs, &nr, err);
                b->runs = realloc(b->runs, (size_t)(b->nruns + nr) * sizeof *b->runs);
                for (int r = 0; r < nr; r++) {
                    sb_batch_run *br = &b->runs[b->nruns];
                    br->index = b->nruns++;
                    br->scene = i;
                    br->spec = rs[r];
                    sb_run_id(&ids, &rs[r], br->run_id);
                    br->cost = run_cost(b, sc, &rs[r]);
                }
                free(rs);
            }
        }
    }
    for (int l = 0; l < nlines; l++) {
        free(lines[l].only);
        for (int k = 0; k < lines[l].nspecs; k++) free(lines[l].specs[k]);
    }
    free(lines);
    if (!ok) sb_batch_free(b);
    return ok;
}

bool sb_batch_load(sb_batch *b, const char *file, const sb_run_opts *base, const char *const *cli_opts, int ncli,
                   sb_err *err) {
    char *text = sb_read_file(file, NULL, err);
    if (!text) return false;
    bool ok = batch_build(b, file, text, base, cli_opts, ncli, true, err);
    free(text);
    return ok;
}

bool sb_batch_check(const char *name, const char *text, sb_err *err) {
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    sb_batch b;
    char *copy = sb_strdup(text);
    bool ok = batch_build(&b, name, copy, &o, NULL, 0, false, err);
    if (ok) sb_batch_free(&b);
    free(copy);
    return ok;
}

void sb_batch_free(sb_batch *b) {
    for (int i = 0; i < b->nscenes; i++) {
        free(b->scenes[i].name);
        free(b->scenes[i].file);
        free(b->scenes[i].path_name);
        sb_scene_free(&b->scenes[i].scene);
        sb_path_free(&b->scenes[i].path);
    }
    for (int i = 0; i < b->npaths; i++) {
        free(b->paths[i].name);
        free(b->paths[i].file);
    }
    free(b->scenes);
    free(b->paths);
    free(b->runs);
    free(b->file);
    free(b->name);
    memset(b, 0, sizeof *b);
}

static const sb_batch_run *g_runs;
static int by_cost(const void *a, const void *b) {
    const sb_batch_run *x = &g_runs[*(const int *)a], *y = &g_runs[*(const int *)b];
    if (x->cost != y->cost) return x->cost > y->cost ? -1 : 1;
    return x->index - y->index;
}

void sb_batch_shard(const sb_batch *b, int shard, int nshards, bool *selected) {
    /* longest processing time first: the costliest run goes to the least loaded shard */
    int *order = malloc(sizeof(int) * (size_t)(b->nruns ? b->nruns : 1));
    double *load = calloc((size_t)nshards, sizeof(double));
    for (int i = 0; i < b->nruns; i++) order[i] = i;
    g_runs = b->runs;
    qsort(order, (size_t)b->nruns, sizeof(int), by_cost);
    for (int k = 0; k < b->nruns; k++) {
        int best = 0;
        for (int s = 1; s < nshards; s++)
            if (load[s] < load[best]) best = s;
        load[best] += b->runs[order[k]].cost;
        selected[order[k]] = best == shard - 1;
    }
    free(order);
    free(load);
}
