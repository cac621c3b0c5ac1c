/* batch.c - batch file parsing, matrix expansion, shards. */
#include "scene_load.h"
#include "batch.h"

#include "resultset.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "table.h"
#include "runkey.h"

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
    sb_cli_opts light;          /* the light's size after the specs (--sun-size ...); given[] says which */
} run_line;

/* The run options of a line's runs: the file's, with the line options (the option rows marked line_option: the
 * light's size, a soft-shadow section beside the hard one in one file) the line gave; everything else is the
 * file's or the command line's. */
static sb_run_opts line_opts(const sb_run_opts *file, const run_line *rl) {
    sb_run_opts o = *file;
    sb_cli_copy_line_options(&o, &rl->light);
    return o;
}

static bool line_applies(const run_line *rl, const char *scene) {
    if (!rl->only) return true;
    char buf[512];
    snprintf(buf, sizeof buf, "%s", rl->only);
    for (char *t = strtok(buf, ","); t; t = strtok(NULL, ","))
        if (!strcmp(t, scene)) return true;
    return false;
}

/* A rough cost model: frames x (geometry per pass x passes + shadow-map fill + the pixels' work), from the
 * parameters' roles (a map's resolution, how many maps) and the technique's pixel cost. */
static double run_cost(const sb_batch *b, const sb_batch_scene *sc, const sb_run_spec *spec) {
    double tris = (double)sb_scene_triangles(&sc->scene);
    double maps, res;
    bool has_maps = sb_params_role(&spec->params, SB_PARAM_RES, &res);
    if (!sb_params_role(&spec->params, SB_PARAM_MAPS, &maps)) maps = has_maps ? 1 : 0;
    if (!has_maps) res = 0;
    double pixels = (double)b->opts.width * b->opts.height;
    double per_frame = tris * (1 + maps) + maps * res * res * 0.25 + pixels * (1 + spec->tech->pixel_cost);
    return per_frame * (b->opts.frames + b->opts.warmup) * (b->opts.error_every > 0 ? 1.2 : 1.0);
}

/* The parse's state: the batch, its run lines, where we are. */
typedef struct parse {
    sb_batch *b;
    const char *file;
    int line;
    run_line *lines;
    int nlines;
    sb_err *err;
} parse;

static bool scene_line(parse *ps, char **tok, int n) {
    sb_batch *b = ps->b;
    if (n < 3 || n > 4) return sb_fail(ps->err, "%s:%d: expected 'scene NAME FILE [PATH-NAME]'", ps->file, ps->line);
    if (find_scene(b, tok[1]) >= 0) return sb_fail(ps->err, "%s:%d: scene '%s' is defined twice", ps->file, ps->line, tok[1]);
    sb_err why;   /* the scene's and its path's names: every result's scene and path columns */
    if (!sb_name_check("the scene's name", tok[1], &why) || (n == 4 && !sb_name_check("the path's name", tok[3], &why)))
        return sb_fail(ps->err, "%s:%d: %s", ps->file, ps->line, why.msg);
    b->scenes = sb_xrealloc(b->scenes, (size_t)(b->nscenes + 1) * sizeof *b->scenes);
    sb_batch_scene *sc = &b->scenes[b->nscenes++];
    memset(sc, 0, sizeof *sc);
    sc->name = sb_strdup(tok[1]);
    sc->file = sb_strdup(tok[2]);
    sc->path_name = n == 4 ? sb_strdup(tok[3]) : NULL;
    sc->line = ps->line;
    return true;
}

static bool path_line(parse *ps, char **tok, int n) {
    sb_batch *b = ps->b;
    if (n != 3) return sb_fail(ps->err, "%s:%d: expected 'path NAME FILE'", ps->file, ps->line);
    if (find_path(b, tok[1]) >= 0) return sb_fail(ps->err, "%s:%d: path '%s' is defined twice", ps->file, ps->line, tok[1]);
    b->paths = sb_xrealloc(b->paths, (size_t)(b->npaths + 1) * sizeof *b->paths);
    b->paths[b->npaths++] = (sb_batch_path){sb_strdup(tok[1]), sb_strdup(tok[2]), ps->line};
    return true;
}

/* defaults OPTION...: the run options' rows of the option table (options.h), parsed as on the command line. */
static bool defaults_line(parse *ps, char **tok, int n) {
    sb_cli_opts o;
    memset(&o, 0, sizeof o);
    o.run = ps->b->opts;
    char where[1100];
    snprintf(where, sizeof where, "%s:%d", ps->file, ps->line);
    if (!sb_cli_parse_tokens(&o, tok + 1, n - 1, where, ps->err)) return false;
    ps->b->opts = o.run;
    return true;
}

/* [@SCENE,...] SPEC...: every spec validated now, nothing renders before the whole file is known good. */
static bool run_line_of(parse *ps, char **tok, int n) {
    run_line rl = {0};
    rl.line = ps->line;
    int first = 0;
    bool ok = true;
    if (tok[0][0] == '@') {
        rl.only = sb_strdup(tok[0] + 1);
        first = 1;
        if (n == 1) ok = sb_fail(ps->err, "%s:%d: '@%s' with no technique spec", ps->file, ps->line, rl.only);
    }
    int nspec_tok = n;
    for (int i = first; i < n; i++)
        if (!strncmp(tok[i], "--", 2)) {
            nspec_tok = i;
            break;
        }
    if (ok && nspec_tok < n) {   /* the line's light */
        char where[1100];
        snprintf(where, sizeof where, "%s:%d", ps->file, ps->line);
        rl.light.run = ps->b->opts;
        ok = sb_cli_parse_tokens(&rl.light, tok + nspec_tok, n - nspec_tok, where, ps->err);
        for (int j = 0; ok && j < sb_option_count; j++) {
            if (!rl.light.given[j] || sb_options[j].line_option) continue;
            char allowed[256];
            sb_line_options_text(allowed, sizeof allowed);
            ok = sb_fail(ps->err, "%s:%d: %s: after a run line's specs only %s (the light of its runs); other options "
                                  "go on the defaults line", ps->file, ps->line, sb_options[j].name, allowed);
        }
        if (ok && nspec_tok == first) ok = sb_fail(ps->err, "%s:%d: options with no technique spec", ps->file, ps->line);
    }
    n = nspec_tok;
    for (int i = first; ok && i < n && rl.nspecs < 32; i++) {
        sb_run_spec *tmp = NULL;
        int nt = 0;
        char where[1100];
        snprintf(where, sizeof where, "%s:%d", ps->file, ps->line);
        ok = sb_spec_expand(tok[i], where, &tmp, &nt, ps->err);
        free(tmp);
        if (ok) rl.specs[rl.nspecs++] = sb_strdup(tok[i]);
    }
    ps->lines = sb_xrealloc(ps->lines, (size_t)(ps->nlines + 1) * sizeof *ps->lines);
    ps->lines[ps->nlines++] = rl;
    return ok;
}

/* Every line of the text, in order (empty lines counted for the line numbers). */
static bool parse_lines(parse *ps, char *text) {
    char *p = text;
    while (p && *p) {
        ps->line++;
        char *eol = strchr(p, '\n');
        if (eol) *eol = 0;
        char *line = p;
        p = eol ? eol + 1 : NULL;
        char *tok[64];
        int n = tokens(line, tok, 64);
        if (!n) continue;
        bool ok = !strcmp(tok[0], "scene")      ? scene_line(ps, tok, n)
                  : !strcmp(tok[0], "path")     ? path_line(ps, tok, n)
                  : !strcmp(tok[0], "defaults") ? defaults_line(ps, tok, n)
                                                : run_line_of(ps, tok, n);
        if (!ok) return false;
    }
    return true;
}

/* Names the file refers to exist; the command line's options beat the file's. */
static bool check_references(parse *ps, const sb_cli_opts *cli, bool load) {
    sb_batch *b = ps->b;
    if (cli) sb_cli_copy_given(&b->opts, cli);
    if (!b->nscenes) return sb_fail(ps->err, "%s: no 'scene' lines", ps->file);
    if (!ps->nlines) return sb_fail(ps->err, "%s: no run lines (technique specs)", ps->file);
    for (int l = 0; l < ps->nlines; l++)
        if (ps->lines[l].only) {
            char buf[512];
            snprintf(buf, sizeof buf, "%s", ps->lines[l].only);
            for (char *t = strtok(buf, ","); t; t = strtok(NULL, ","))
                if (find_scene(b, t) < 0)
                    return sb_fail(ps->err, "%s:%d: no scene named '%s'", ps->file, ps->lines[l].line, t);
        }
    for (int i = 0; !load && i < b->nscenes; i++) {
        const char *pname = b->scenes[i].path_name;
        if (pname && find_path(b, pname) < 0)
            return sb_fail(ps->err, "%s:%d: no path named '%s'", ps->file, b->scenes[i].line, pname);
    }
    return true;
}

/* Scenes and paths (no GL): contents decide run ids, sizes decide costs. Each
 * scene is loaded here once; the session takes it over when its runs come. */
static bool load_scenes(parse *ps) {
    sb_batch *b = ps->b;
    for (int i = 0; i < b->nscenes; i++) {
        sb_batch_scene *sc = &b->scenes[i];
        sb_err e;
        sb_scene_opts so = sb_run_scene_opts(&b->opts);
        if (!sb_scene_load(&sc->scene, sc->file, &so, &e)) return sb_fail(ps->err, "%s:%d: %s", ps->file, sc->line, e.msg);
        const char *pname = sc->path_name ? sc->path_name : sc->name;
        int pi = find_path(b, pname);
        if (sc->path_name && pi < 0)
            return sb_fail(ps->err, "%s:%d: no path named '%s'", ps->file, sc->line, sc->path_name);
        snprintf(sc->path_file, sizeof sc->path_file, "%s", pi >= 0 ? b->paths[pi].file : "auto");
        snprintf(sc->path_label, sizeof sc->path_label, "%s", pi >= 0 ? b->paths[pi].name : "auto");
        if (!sb_path_load(&sc->path, sc->path_file, &sc->scene, &e))
            return sb_fail(ps->err, "%s:%d: %s", ps->file, pi >= 0 ? b->paths[pi].line : sc->line, e.msg);
    }
    return true;
}

/* A --lights (the defaults line's, or a run line's) read against every scene its line applies to: a lamp a scene
 * lacks is refused with the line, before anything renders. */
static bool check_lights(parse *ps) {
    sb_batch *b = ps->b;
    for (int l = 0; l < ps->nlines; l++) {
        sb_run_opts ro = line_opts(&b->opts, &ps->lines[l]);
        for (int i = 0; i < b->nscenes; i++) {
            sb_light_set set;
            sb_err e;
            const sb_scene *sc = &b->scenes[i].scene;
            if (!line_applies(&ps->lines[l], b->scenes[i].name)) continue;
            if (ro.lights && !sb_scene_light_set(sc, ro.lights, sc->has_sun || ro.sun_override, &set, &e))
                return sb_fail(ps->err, "%s:%d: scene %s: %s", ps->file, ps->lines[l].line, b->scenes[i].name, e.msg);
            for (int k = 0; k < ps->lines[l].nspecs; k++) {   /* a spec's light=K: a lamp the scene has, not beside --lights */
                sb_run_spec *rs = NULL;
                int nr = 0;
                bool ok = sb_spec_expand(ps->lines[l].specs[k], NULL, &rs, &nr, &e);
                for (int r = 0; ok && r < nr; r++) ok = sb_spec_lights_check(sc, &rs[r], ro.lights, &e);
                free(rs);
                if (!ok)
                    return sb_fail(ps->err, "%s:%d: scene %s: %s", ps->file, ps->lines[l].line, b->scenes[i].name, e.msg);
            }
        }
    }
    return true;
}

/* The matrix: scenes (in file order) x run lines x each line's grid. */
static void expand_matrix(parse *ps) {
    sb_batch *b = ps->b;
    for (int i = 0; i < b->nscenes; i++) {
        sb_batch_scene *sc = &b->scenes[i];
        for (int l = 0; l < ps->nlines; l++) {
            if (!line_applies(&ps->lines[l], sc->name)) continue;
            for (int k = 0; k < ps->lines[l].nspecs; k++) {
                sb_run_spec *rs = NULL;
                int nr = 0;
                sb_spec_expand(ps->lines[l].specs[k], NULL, &rs, &nr, ps->err);
                b->runs = sb_xrealloc(b->runs, (size_t)(b->nruns + nr) * sizeof *b->runs);
                for (int r = 0; r < nr; r++) {
                    sb_batch_run *br = &b->runs[b->nruns];
                    br->index = b->nruns;
                    br->scene = i;
                    br->spec = rs[r];
                    sb_run_opts ro = line_opts(&b->opts, &ps->lines[l]);
                    br->sun_size = ro.sun_size, br->lamp_radius = ro.lamp_radius, br->ref_samples = ro.ref_samples;
                    if (ro.lights) {   /* checked against the scene: its one name (the same set, the same run id) */
                        sb_light_set set;
                        sb_err e;
                        if (sb_scene_light_set(&sc->scene, ro.lights, sc->scene.has_sun || ro.sun_override, &set, &e))
                            ro.lights = sb_lights_name(&sc->scene, &set);
                    }
                    br->lights = ro.lights;
                    sb_run_spec as_run = rs[r];
                    sb_spec_light_size(&as_run, ro.sun_size);
                    sb_run_id(sc->scene.content_hash, sc->path.content_hash, &ro, &as_run, br->run_id);
                    br->cost = run_cost(b, sc, &rs[r]);
                    int twin = -1;   /* the same run again (a spec repeated, a grid naming a value twice): once */
                    for (int e = 0; e < b->nruns && twin < 0; e++)
                        if (!strcmp(b->runs[e].run_id, br->run_id)) twin = e;
                    if (twin < 0) {
                        b->nruns++;
                        continue;
                    }
                    char params[SB_PARAMS_TEXT_LEN];
                    sb_params_canonical(&rs[r].params, params, sizeof params);
                    sb_log("note: %s:%d: %s:%s on %s is run %d of the matrix already (run_id %s): run once", ps->file,
                           ps->lines[l].line, rs[r].tech->name, params, sc->name, twin, br->run_id);
                }
                free(rs);
            }
        }
    }
}

static bool batch_build(sb_batch *b, const char *file, char *text, const sb_run_opts *base, const sb_cli_opts *cli,
                        bool load, sb_err *err) {
    memset(b, 0, sizeof *b);
    b->file = sb_strdup(file);
    const char *slash = strrchr(file, '/');
    b->name = sb_strdup(slash ? slash + 1 : file);
    char *dot = strrchr(b->name, '.');
    if (dot && dot != b->name) *dot = 0;
    b->opts = *base;
    parse ps = {.b = b, .file = file, .err = err};
    bool ok = parse_lines(&ps, text) && check_references(&ps, cli, load) && (!load || (load_scenes(&ps) && check_lights(&ps)));
    if (ok && load) expand_matrix(&ps);
    if (ok) sb_run_opts_finish(&b->opts);
    for (int l = 0; l < ps.nlines; l++) {
        free(ps.lines[l].only);
        for (int k = 0; k < ps.lines[l].nspecs; k++) free(ps.lines[l].specs[k]);
    }
    free(ps.lines);
    if (!ok) sb_batch_free(b);
    return ok;
}

bool sb_batch_load(sb_batch *b, const char *file, const sb_run_opts *base, const sb_cli_opts *cli, sb_err *err) {
    char *text = sb_read_file(file, NULL, err);
    if (!text) return false;
    bool ok = batch_build(b, file, text, base, cli, true, err);
    free(text);
    return ok;
}

bool sb_batch_check(const char *name, const char *text, sb_err *err) {
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    sb_batch b;
    char *copy = sb_strdup(text);
    bool ok = batch_build(&b, name, copy, &o, NULL, false, err);
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

typedef struct {
    double cost;
    int index;
} cost_key;

static int by_cost(const void *a, const void *b) {
    const cost_key *x = a, *y = b;
    if (x->cost != y->cost) return x->cost > y->cost ? -1 : 1;
    return x->index - y->index;
}

void sb_batch_shard(const sb_batch *b, int shard, int nshards, bool *selected) {
    /* longest processing time first: the costliest run goes to the least loaded shard */
    cost_key *order = sb_xmalloc(sizeof *order * (size_t)(b->nruns ? b->nruns : 1));
    double *load = sb_xcalloc((size_t)nshards, sizeof(double));
    for (int i = 0; i < b->nruns; i++) order[i] = (cost_key){b->runs[i].cost, b->runs[i].index};
    qsort(order, (size_t)b->nruns, sizeof *order, by_cost);
    for (int k = 0; k < b->nruns; k++) {
        int best = 0;
        for (int s = 1; s < nshards; s++)
            if (load[s] < load[best]) best = s;
        load[best] += order[k].cost;
        selected[order[k].index] = best == shard - 1;
    }
    free(order);
    free(load);
}

/* ---- running a batch ---- */

static bool write_meta(const sb_batch_cmd *cmd, const char *dir, const sb_session *s, const sb_batch *b,
                       int selected, const char *identity, sb_err *err) {
    char extra[12288], seed[32] = "";
    if (b->opts.order == SB_ORDER_SHUFFLE) snprintf(seed, sizeof seed, "%llu", (unsigned long long)b->opts.seed);
    snprintf(extra, sizeof extra, "batch: %s\nruns: %d of %d%s%s\norder: %s\nseed: %s\n%s", b->file, selected, b->nruns,
             cmd->shard ? ", shard " : "", cmd->shard ? cmd->shard : "", sb_order_name(b->opts.order), seed,
             identity);
    return sb_session_write_meta(s, dir, cmd->command_line, cmd->version, cmd->commit, extra, err);
}

static void print_dry_run(const sb_batch *b, const bool *selected, int nsel, bool sharded) {
    printf("index,run_id,scene,path,technique,params,cost\n");
    for (int i = 0; i < b->nruns; i++) {
        if (!selected[i]) continue;
        const sb_batch_run *r = &b->runs[i];
        char params[SB_PARAMS_TEXT_LEN];
        sb_params_canonical(&r->spec.params, params, sizeof params);
        printf("%d,%s,%s,%s,%s,%s,%.3g\n", r->index, r->run_id, b->scenes[r->scene].name,
               b->scenes[r->scene].path_label, r->spec.tech->name, params, r->cost);
    }
    fprintf(stderr, "%d run(s)%s of %d in the matrix of %s\n", nsel, sharded ? " in this shard" : "", b->nruns, b->file);
}

bool sb_resume_check(const char *dir, const char *identity, const char *const *ids, int n, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/meta", dir);
    char *meta = sb_read_file(path, NULL, NULL), what[2400], command[1200] = "";
    for (const char *p = meta; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : NULL)
        if (!strncmp(p, "command: ", 9)) snprintf(command, sizeof command, " (%.*s)", (int)strcspn(p + 9, "\n"), p + 9);
    bool differs = meta && sb_set_identity_differs(meta, identity, what, sizeof what);
    free(meta);
    if (differs)
        return sb_fail(err, "--resume %s: %s: resume a set with the command that made it%s, or leave --resume out "
                            "for a set of its own", dir, what, command);
    if (n < 0) return true;   /* a folder of results sets (tune's rungs): the identity alone */
    /* a set from before its meta said what made it: its runs must all be this command's */
    snprintf(path, sizeof path, "%s/summary.csv", dir);
    sb_table old;
    sb_err e;
    if (access(path, F_OK) != 0 || !sb_table_load(&old, path, &e)) return true;   /* no run recorded yet */
    int foreign = 0, first = -1;
    for (int r = 0; r < old.nrows; r++) {
        bool mine = false;
        for (int i = 0; i < n && !mine; i++) mine = ids[i] && !strcmp(ids[i], sb_run_key_id(&old, r));
        if (!mine && !foreign++) first = r;
    }
    sb_run_key k;
    sb_run_key_of(&old, first, &k);
    bool ok = !foreign ||
              sb_fail(err, "--resume %s: its summary.csv holds %d run(s) this command does not make (run_id %s: %s %s): "
                           "resume a set with the command that made it%s, or leave --resume out for a set of its own",
                      dir, foreign, k.run_id, k.technique, k.params, command);
    sb_table_free(&old);
    return ok;
}

/* Resume: keeps the runs of the old summary that are complete (a summary row
 * and, unless skipped, the committed per-frame CSV), rows as they were. */
int sb_summary_keep_complete(sb_summary *sum, const char *dir, const char *const *ids, int n, bool *done) {
    sb_table old;
    sb_err err;
    int kept = 0;
    if (!sb_table_load(&old, sum->path, &err)) return 0;
    for (int r = 0; r < old.nrows; r++) {
        const char *id = sb_run_key_id(&old, r);
        sb_status st = sb_status_of(sb_table_get(&old, r, "status"));
        for (int i = 0; i < n; i++) {
            if (!ids[i] || done[i] || strcmp(ids[i], id)) continue;
            char csv[4400];
            snprintf(csv, sizeof csv, "%s/%s.csv", dir, id);
            if (st != SB_STATUS_SKIPPED && (st != SB_STATUS_OK || access(csv, R_OK) != 0)) continue;
            done[i] = true;
            kept++;
            sb_summary_add_line(sum, old.lines[r], st);
        }
    }
    sb_table_free(&old);
    return kept;
}

/* The selected runs' ids (NULL for the others), for the resume's check and its keep. */
static const char **selected_ids(const sb_batch *b, const bool *selected) {
    const char **ids = sb_xcalloc((size_t)(b->nruns ? b->nruns : 1), sizeof *ids);
    for (int i = 0; i < b->nruns; i++) ids[i] = selected[i] ? b->runs[i].run_id : NULL;
    return ids;
}

static void keep_complete_runs(const sb_batch *b, const char *dir, const bool *selected, bool *done, sb_summary *sum) {
    const char **ids = selected_ids(b, selected);
    sb_summary_keep_complete(sum, dir, ids, b->nruns, done);
    free(ids);
}

/* A scene that cannot be opened: each of its runs is recorded as failed. */
static void fail_runs(const sb_batch *b, int i, const char *renderer, const char *why, sb_summary *sum) {
    const sb_batch_run *r = &b->runs[i];
    const sb_batch_scene *bs = &b->scenes[r->scene];
    char params[SB_PARAMS_TEXT_LEN];
    sb_params_canonical(&r->spec.params, params, sizeof params);
    sb_run_info info = {.run_id = r->run_id, .run_index = r->index, .scene = bs->name, .path = bs->path_label,
                        .technique = r->spec.tech->name, .params = params, .backend = sb_backend_name(b->opts.backend),
                        .renderer = renderer, .timing = sb_timing_name(b->opts.timing), .submit = sb_submit_name(b->opts.submit),
                        .status = SB_STATUS_FAILED,
                        .reason = why, .frames = b->opts.frames, .warmup = b->opts.warmup, .width = b->opts.width,
                        .height = b->opts.height};
    sb_summary_add_outcome(sum, &info, sb_technique_stage_mask(r->spec.tech), NULL, NULL, 0);
}

static bool results_dir(const sb_batch_cmd *cmd, const sb_batch *b, char *dir, size_t len, sb_err *err) {
    if (cmd->resume) {
        snprintf(dir, len, "%s", cmd->resume);
        if (access(dir, W_OK) != 0) return sb_fail(err, "--resume %s: no such results folder", cmd->resume);
        return true;
    }
    char base_dir[4096];
    snprintf(base_dir, sizeof base_dir, "%s/%s", cmd->out, b->name);
    return sb_make_stamped_dir(base_dir, dir, len, err);
}

/* The selected runs of each scene, the scene loaded once (by sb_batch_load). */
static void run_scenes(sb_batch *b, const bool *selected, const bool *done, int todo, const char *dir, sb_session *s,
                       sb_summary *sum) {
    sb_err err;
    int k = 0;
    const sb_run_spec **specs = sb_xmalloc(sizeof *specs * (size_t)(b->nruns ? b->nruns : 1));
    int *index = sb_xmalloc(sizeof *index * (size_t)(b->nruns ? b->nruns : 1));
    for (int sc = 0; sc < b->nscenes && !sb_interrupted(); sc++) {
        bool any = false;
        for (int i = 0; i < b->nruns; i++) any |= b->runs[i].scene == sc && selected[i] && !done[i];
        if (!any) continue;
        sb_batch_scene *bs = &b->scenes[sc];
        bool open = sb_session_attach(s, &b->opts, &bs->scene, &bs->path, &err);
        if (open) {
            sb_session_keep_reference(s, dir);
            snprintf(s->scene_name, sizeof s->scene_name, "%s", bs->name);
            snprintf(s->path_name, sizeof s->path_name, "%s", bs->path_label);
        } else {
            sb_say_line(stderr, err.msg);
        }
        /* a group of runs a light: each light's runs together (a soft-shadow section after the hard one),
           the reference given that light's size before them */
        bool *taken = sb_xcalloc((size_t)b->nruns, sizeof *taken);
        for (int first = 0; first < b->nruns; first++) {
            const sb_batch_run *lead = &b->runs[first];
            if (lead->scene != sc || !selected[first] || done[first] || taken[first]) continue;
            int n = 0;
            for (int i = first; i < b->nruns; i++) {
                const sb_batch_run *br = &b->runs[i];
                if (br->scene != sc || !selected[i] || done[i] || taken[i] || br->sun_size != lead->sun_size ||
                    br->lamp_radius != lead->lamp_radius || br->ref_samples != lead->ref_samples ||
                    br->lights != lead->lights)   /* interned: one pointer a text */
                    continue;
                taken[i] = true;
                specs[n] = &b->runs[i].spec, index[n++] = b->runs[i].index;
                if (!open) fail_runs(b, i, s->ctx.renderer, err.msg, sum);
            }
            sb_err le;
            if (open && !sb_session_set_lights(s, lead->lights, &le))   /* checked at load: not expected */
                for (int i = 0; i < n; i++) fail_runs(b, index[i], s->ctx.renderer, le.msg, sum);
            else if (open) {
                sb_session_set_light_size(s, lead->sun_size, lead->lamp_radius, lead->ref_samples);
                sb_run_group(s, specs, index, n, dir, sum, k, todo);
            }
            k += n;
        }
        free(taken);
        if (open) {
            sb_session_close_scene(s);
        } else {
            sb_err e;
            if (!sb_summary_flush(sum, &e)) fprintf(stderr, "shadowbench: %s\n", e.msg);
        }
    }
    free(specs);
    free(index);
}

/* A scene's file and path read again (a session took the first load over and freed it with the scene). */
static bool reload_scene(const sb_batch *b, sb_batch_scene *bs, sb_err *err) {
    sb_scene_opts so = sb_run_scene_opts(&b->opts);
    if (!sb_scene_load(&bs->scene, bs->file, &so, err)) return false;
    if (sb_path_load(&bs->path, bs->path_file, &bs->scene, err)) return true;
    sb_scene_free(&bs->scene);
    return false;
}

/* The runs that ended unstable, run again at the batch's end (--rerun-unstable N), scene by scene, each with its
 * line's light; up to N attempts more, planned on the night's figures (sb_rerun_plan_make: a disturbed night waits
 * for calm or says so and runs nothing again; re-runs take at most a stated share of the night's time). */
static void rerun_unstable(sb_batch *b, const bool *selected, const char *dir, sb_session *s, sb_summary *sum,
                           double night_t0) {
    const double night_s = (sb_now_ms() - night_t0) / 1e3;
    const int nprobe = sum->ncalib;   /* the first attempts' probes: the night as it ran */
    double spent_s = 0;
    for (int attempt = 2; attempt <= 1 + b->opts.rerun_unstable && !sb_interrupted(); attempt++) {
        sb_rerun_round round;
        bool go = sb_rerun_round_plan(s, sum, nprobe, night_s, spent_s, attempt, &round), again = false;
        char **ids = round.ids;
        const bool *pick = round.pick;
        const int nu = round.n;
        double t0 = sb_now_ms();
        for (int sc = 0; go && sc < b->nscenes && !sb_interrupted(); sc++) {
            sb_batch_scene *bs = &b->scenes[sc];
            bool open = false;
            sb_err err;
            for (int i = 0; i < b->nruns && !sb_interrupted(); i++) {
                const sb_batch_run *br = &b->runs[i];
                bool wanted = false;
                for (int u = 0; u < nu && !wanted; u++)
                    wanted = pick[u] && br->scene == sc && selected[i] && !strcmp(ids[u], br->run_id);
                if (!wanted) continue;
                if (!open && !(open = reload_scene(b, bs, &err) && sb_session_attach(s, &b->opts, &bs->scene, &bs->path, &err))) {
                    fprintf(stderr, "shadowbench: %s: cannot run again: %s\n", bs->name, err.msg);
                    break;
                }
                snprintf(s->scene_name, sizeof s->scene_name, "%s", bs->name);
                snprintf(s->path_name, sizeof s->path_name, "%s", bs->path_label);
                sb_session_keep_reference(s, dir);
                sb_session_set_light_size(s, br->sun_size, br->lamp_radius, br->ref_samples);
                if (!sb_session_set_lights(s, br->lights, &err)) continue;   /* it ran with them before */
                const sb_run_spec *spec = &br->spec;
                sb_run_again(s, &spec, &br->index, 1, dir, sum, attempt);
                again = true;
            }
            if (open) sb_session_close_scene(s);
        }
        spent_s += (sb_now_ms() - t0) / 1e3;
        sb_rerun_round_free(&round);
        if (!again) break;
    }
}

int sb_batch_main(const sb_batch_cmd *cmd) {
    sb_err err;
    sb_batch b;
    if (!sb_batch_load(&b, cmd->file, cmd->base, cmd->cli, &err)) {
        sb_say_line(stderr, err.msg);
        return SB_EXIT_BAD_INPUT;
    }
    int rc = SB_EXIT_OK, nsel = 0;
    bool *selected = sb_xmalloc((size_t)(b.nruns ? b.nruns : 1)), *done = sb_xcalloc((size_t)(b.nruns ? b.nruns : 1), 1);
    memset(selected, 1, (size_t)(b.nruns ? b.nruns : 1));
    if (cmd->shard) {
        int si, sn;
        char extra;
        if (sscanf(cmd->shard, "%d/%d%c", &si, &sn, &extra) != 2 || sn < 1 || si < 1 || si > sn) {
            fprintf(stderr, "shadowbench: --shard %s: expected I/N with 1 <= I <= N\n", cmd->shard);
            rc = SB_EXIT_BAD_INPUT;
            goto out;
        }
        sb_batch_shard(&b, si, sn, selected);
    }
    for (int i = 0; i < b.nruns; i++) nsel += selected[i];
    if (!cmd->dry_run && !sb_grid_confirm(nsel, cmd->cli, &err)) {
        fprintf(stderr, "shadowbench: %s: %s\n", cmd->file, err.msg);
        rc = SB_EXIT_BAD_INPUT;
        goto out;
    }
    if (cmd->dry_run) {
        print_dry_run(&b, selected, nsel, cmd->shard != NULL);
        goto out;
    }
    /* what the set is: the command's options and words, and the batch file's bytes (an edited file: another set) */
    char identity[8192];
    size_t flen = 0;
    char *ftext = sb_read_file(cmd->file, &flen, NULL);
    snprintf(identity, sizeof identity, "%sset: batch-file-checksum %016llx\n", cmd->identity ? cmd->identity : "",
             (unsigned long long)sb_fnv1a(SB_FNV_SEED, ftext ? ftext : "", flen));
    free(ftext);
    if (cmd->resume) {
        const char **ids = selected_ids(&b, selected);
        bool ok = sb_resume_check(cmd->resume, identity, ids, b.nruns, &err);
        free(ids);
        if (!ok) {
            sb_say_line(stderr, err.msg);
            rc = SB_EXIT_BAD_INPUT;
            goto out;
        }
    }
    char dir[4096], sum_path[4200];
    if (!results_dir(cmd, &b, dir, sizeof dir, &err)) {
        sb_say_line(stderr, err.msg);
        rc = cmd->resume ? SB_EXIT_BAD_INPUT : SB_EXIT_WRITE;   /* --out was writable when the command began */
        goto out;
    }
    if (cmd->resume) sb_resultset_unseal(dir);   /* the set changes now; sealed again when it ends */
    sb_session s;
    memset(&s, 0, sizeof s);
    if (!sb_context_create(&s.ctx, b.opts.backend, &err) || !sb_session_clocks(&s, &b.opts, &err)) {
        sb_say_line(stderr, err.msg);
        sb_clocks_close(s.clocks);
        sb_context_destroy(&s.ctx);
        rc = SB_EXIT_FAILED;
        goto out;
    }
    if (!write_meta(cmd, dir, &s, &b, nsel, identity, &err) || !sb_columns_write(dir, &err))
        sb_say_line(stderr, err.msg);
    snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
    sb_summary sum;
    sb_summary_open(&sum, sum_path);
    if (cmd->resume) keep_complete_runs(&b, dir, selected, done, &sum);
    int todo = 0;
    for (int i = 0; i < b.nruns; i++) todo += selected[i] && !done[i];
    if (cmd->resume) sb_log("resuming %s: %d run(s) complete, %d to do", dir, nsel - todo, todo);
    if (!sb_summary_flush(&sum, &err)) sb_say_line(stderr, err.msg);
    double t0 = sb_now_ms();
    run_scenes(&b, selected, done, todo, dir, &s, &sum);
    rerun_unstable(&b, selected, dir, &s, &sum, t0);
    if (!sb_summary_flush(&sum, &err) || !sb_resultset_seal(dir, &err)) sb_say_line(stderr, err.msg);
    double wall_s = (sb_now_ms() - t0) / 1e3;
    printf("%s\n", dir);
    /* how much of the batch the GPU spent on what is measured: the rest is the harness's */
    sb_log("gpu busy share: %.1f%% (timed GPU work %.1f s of %.1f s wall); reference: %llu rays cast (for %d evaluated "
           "frame(s) in the background), %d evaluated frame(s) reused",
           wall_s > 0 ? 100.0 * sum.timed_gpu_ms / 1e3 / wall_s : 0.0, sum.timed_gpu_ms / 1e3, wall_s,
           (unsigned long long)sum.ref_rays, sum.ref_background, sum.ref_reused);
    char again[4200];
    snprintf(again, sizeof again, "shadowbench batch %s", cmd->file);
    rc = sb_summary_conclude(&sum, dir, again);
    sb_summary_free(&sum);
    sb_clocks_close(s.clocks);
    sb_context_destroy(&s.ctx);
out:
    sb_batch_free(&b);
    free(selected);
    free(done);
    return rc;
}

bool sb_grid_confirm(int n, const sb_cli_opts *o, sb_err *err) {
    if (n <= SB_GRID_CONFIRM || o->yes) return true;
    const sb_run_opts *r = &o->run;
    double frames = (double)n * r->repeat * (r->frames + (r->warmup > 0 ? r->warmup : 5));
    /* 50 ms a 1280x720 frame of a small scene on a 2-core llvmpipe, in proportion to the pixels (a GPU: a tenth or
       less), the evaluation's frames and rays not counted */
    double s = frames * 0.05 * ((double)r->width * r->height / (1280.0 * 720.0));
    return sb_fail(err, "%d runs (more than %d), %.0f frames: about %.1f h on llvmpipe (50 ms a 1280x720 frame); "
                        "give --yes to start them, or --dry-run to list them", n, SB_GRID_CONFIRM, frames, s / 3600);
}
