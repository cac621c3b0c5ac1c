/* The option table walked row by row: every option is taken by exactly the
 * commands its row lists and refused by the others (naming the command), is
 * in each of its commands' --help, in the man page and in docs/cli.md; a value
 * out of range is refused with the range; every default parses; the batch
 * file's defaults line takes the run options and nothing else; and the exit
 * statuses of the table are the ones the docs say. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "compare.h"
#include "support.h"

/* A value the row accepts. */
static const char *good_value(const sb_option *o, char *buf, size_t len) {
    switch (o->kind) {
    case SB_OPT_FLAG: return NULL;
    case SB_OPT_CHOICE: snprintf(buf, len, "%.*s", (int)strcspn(o->arg, "|"), o->arg); return buf;
    case SB_OPT_TEXT: return strcmp(o->name, "--since") ? "x" : "2026-01-05";   /* a date the row checks */
    case SB_OPT_SIZE: return "64x32";
    case SB_OPT_ANGLES: return "30,40";
    case SB_OPT_BYTES: return "1G";
    case SB_OPT_DURATION: return "90s";
    default: snprintf(buf, len, "%.15g", isinf(o->min) ? 1 : o->open_min ? o->min + 0.5 : o->min); return buf;
    }
}

/* A value just out of the row's range (NULL: the kind has none to test). */
static const char *bad_value(const sb_option *o, char *buf, size_t len) {
    switch (o->kind) {
    case SB_OPT_INT:
    case SB_OPT_NUM:
    case SB_OPT_SEED:
        if (isinf(o->min)) return "nan";
        snprintf(buf, len, "%.15g", o->open_min ? o->min : o->min - 1);
        return buf;
    case SB_OPT_SIZE: snprintf(buf, len, "%.15gx10", o->max + 1); return buf;
    case SB_OPT_ANGLES: snprintf(buf, len, "0,%.15g", o->max + 1); return buf;
    case SB_OPT_CHOICE: return "sideways";
    case SB_OPT_DURATION: return "0";
    case SB_OPT_BYTES: return "12";
    default: return NULL;
    }
}

#define CMD(c) (&sb_commands[c])

static bool parse(sb_command cmd, const char *name, const char *value, sb_cli_opts *o, sb_err *err) {
    char *argv[] = {"shadowbench", (char *)sb_commands[cmd].name, (char *)name, (char *)value, NULL};
    const char *pos[5];
    int npos;
    sb_cli_defaults(o, CMD(cmd));
    return sb_cli_parse(o, CMD(cmd), value ? 4 : 3, argv, 2, pos, &npos, err) && npos == 0;
}

/* Every command takes an option through its own row: the test's view of "takes". */
static bool takes(const sb_option *opt, int c) { return sb_option_taken(opt, CMD(c)); }

static void test_every_option_by_command(void **st) {
    (void)st;
    int checks = 0;
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        assert_true(opt->commands != 0 || opt->with != 0);
        for (int c = 0; c < SB_CMD_COUNT; c++) {
            const sb_option *row = sb_option_find(opt->name, CMD(c));
            char buf[64];
            const char *v = good_value(row ? row : opt, buf, sizeof buf);
            sb_cli_opts o;
            sb_err err = {{0}};
            bool ok = parse((sb_command)c, opt->name, v, &o, &err);
            if (row) { /* taken: and marked given */
                if (!ok) print_error("%s %s %s: %s\n", sb_commands[c].name, opt->name, v ? v : "", err.msg);
                assert_true(ok);
                assert_true(sb_cli_given(&o, opt->name));
            } else { /* refused, naming the command and the option */
                assert_false(ok);
                char want[128];
                snprintf(want, sizeof want, "%s: %s is not an option of %s", sb_commands[c].name, opt->name,
                         sb_commands[c].name);
                if (!strstr(err.msg, want)) print_error("'%s' lacks '%s'\n", err.msg, want);
                assert_non_null(strstr(err.msg, want));
            }
            checks++;
        }
    }
    print_message("%d option x command checks\n", checks);
}

static void test_out_of_range_names_the_range(void **st) {
    (void)st;
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        char buf[64];
        const char *v = bad_value(opt, buf, sizeof buf);
        if (!v) continue;
        int cmd = 0;
        while (!takes(opt, cmd)) cmd++;
        sb_cli_opts o;
        sb_err err;
        assert_false(parse((sb_command)cmd, opt->name, v, &o, &err));
        print_message("%s\n", err.msg);
        char head[128];
        snprintf(head, sizeof head, "%s %s: expected ", opt->name, v);
        assert_non_null(strstr(err.msg, head));
        char range[64] = "";
        if (opt->kind == SB_OPT_CHOICE) snprintf(range, sizeof range, "%.*s", (int)strcspn(opt->arg, "|"), opt->arg);
        else if (!isinf(opt->max) && opt->kind != SB_OPT_BYTES) snprintf(range, sizeof range, "%.15g]", opt->max);
        else if (!isinf(opt->min)) snprintf(range, sizeof range, "%.15g", opt->min);
        assert_non_null(strstr(err.msg, range));
    }
}

static void test_defaults_parse(void **st) {
    (void)st;
    for (int c = 0; c < SB_CMD_COUNT; c++) {
        sb_cli_opts o;
        sb_cli_defaults(&o, CMD(c));   /* aborts on a row whose default is out of its own range */
        for (int i = 0; i < sb_option_count; i++) assert_false(o.given[i]);
    }
    sb_run_opts r;
    sb_run_opts_defaults(&r);
    assert_int_equal(r.frames, 60);
    assert_int_equal(r.width, 1280);
    assert_int_equal(r.height, 720);
    assert_int_equal(r.warmup, -1);
    assert_int_equal(r.overlap, -1);
    assert_int_equal(r.error_every, 10);
    assert_true(r.threads >= 1);
    /* the per-command rows of one field keep their own defaults */
    sb_cli_opts o;
    sb_cli_defaults(&o, CMD(SB_CMD_COLUMNS));
    assert_int_equal(o.format, SB_OUTPUT_CSV);
    sb_cli_defaults(&o, CMD(SB_CMD_COMPARE));
    assert_int_equal(o.format, SB_OUTPUT_TEXT);
    assert_string_equal(o.out ? o.out : "", "");
    sb_cli_defaults(&o, CMD(SB_CMD_REPORT));
    assert_string_equal(o.out, "out/report");
    /* a command's own defaults, from the rows (tune: 33 frames, one warm-up frame, every frame's error, no flicker
       twins, seed 1, shuffled; stress: 3 frames at 320x180, no warm-up) */
    sb_cli_defaults(&o, CMD(SB_CMD_TUNE));
    assert_int_equal(o.run.frames, 33);
    assert_int_equal(o.run.warmup, 1);
    assert_int_equal(o.run.error_every, 1);
    assert_true(o.run.flicker_dt == 0);
    assert_true(o.run.seed == 1);
    assert_int_equal(o.run.order, SB_ORDER_SHUFFLE);
    sb_cli_defaults(&o, CMD(SB_CMD_STRESS));
    assert_int_equal(o.run.frames, 3);
    assert_int_equal(o.run.width, 320);
    assert_int_equal(o.run.height, 180);
    assert_int_equal(o.run.warmup, 0);
    sb_cli_defaults(&o, CMD(SB_CMD_RUN));
    assert_int_equal(o.run.frames, 60);
}

static void test_values_reach_their_fields(void **st) {
    (void)st;
    sb_cli_opts o;
    sb_err err;
    assert_true(parse(SB_CMD_RUN, "--size", "320x180", &o, &err));
    assert_int_equal(o.run.width, 320);
    assert_int_equal(o.run.height, 180);
    assert_true(parse(SB_CMD_RUN, "--sun", "-30,45", &o, &err));
    assert_true(o.run.sun_override);
    assert_true(o.run.sun_az == -30 && o.run.sun_el == 45);
    assert_true(parse(SB_CMD_RUN, "--overlap", "off", &o, &err));
    assert_int_equal(o.run.overlap, 0);
    assert_true(parse(SB_CMD_RUN, "--warmup", "auto", &o, &err));
    assert_int_equal(o.run.warmup, -1);
    assert_true(parse(SB_CMD_RUN, "--gpu-memory", "512M", &o, &err));
    assert_true(o.run.gpu_memory == 512.0 * 1048576);
    assert_true(parse(SB_CMD_TUNE, "--time-limit", "1.5h", &o, &err));
    assert_true(o.time_limit_s == 5400);
    assert_true(parse(SB_CMD_HISTORY_REGRESSIONS, "--format", "csv", &o, &err));
    assert_int_equal(o.format, SB_OUTPUT_CSV);
    assert_true(parse(SB_CMD_RUN, "--pose", "-2.5", &o, &err));
    assert_true(o.run.pose && o.run.pose_time == -2.5);
    /* the value is the next word, even one that starts with a dash */
    assert_false(parse(SB_CMD_RUN, "--frames", NULL, &o, &err));
    assert_non_null(strstr(err.msg, "--frames needs a value"));
    /* a format of another command is not this one's */
    assert_false(parse(SB_CMD_HISTORY_REGRESSIONS, "--format", "markdown", &o, &err));
    assert_non_null(strstr(err.msg, "expected text or csv"));
    /* --name=value is --name value */
    assert_true(parse(SB_CMD_RUN, "--size=640x360", NULL, &o, &err));
    assert_int_equal(o.run.width, 640);
    assert_true(sb_cli_given(&o, "--size"));
    assert_false(parse(SB_CMD_RUN, "--frames=", NULL, &o, &err));
    assert_false(parse(SB_CMD_RUN, "--quiet=yes", NULL, &o, &err));
    assert_non_null(strstr(err.msg, "--quiet takes no value"));
    /* options that contradict each other are refused, naming both */
    assert_false(parse(SB_CMD_RUN, "--quiet", "--verbose", &o, &err));
    assert_non_null(strstr(err.msg, "--quiet and --verbose"));
}

/* The run id as it was hashed before the identity was a column of the option table (run.c until then): the ids
 * of every series must hold. */
static void legacy_run_id(uint64_t scene_hash, uint64_t path_hash, const sb_run_opts *o, const sb_run_spec *spec,
                          char out[17]) {
    char params[1024];
    sb_params_canonical(&spec->params, params, sizeof params);
    uint64_t h = SB_FNV_SEED;
    h = sb_fnv1a(h, &scene_hash, sizeof scene_hash);
    h = sb_fnv1a(h, &path_hash, sizeof path_hash);
    h = sb_fnv1a(h, spec->tech->name, strlen(spec->tech->name) + 1);
    h = sb_fnv1a(h, params, strlen(params) + 1);
    int dims[4] = {o->frames, o->width, o->height, (int)o->backend};
    h = sb_fnv1a(h, dims, sizeof dims);
    if (o->sun_override) {
        double sun[2] = {o->sun_az, o->sun_el};
        h = sb_fnv1a(h, sun, sizeof sun);
    }
    if (o->submit != SB_SUBMIT_DIRECT) h = sb_fnv1a(h, "indirect", 9);
    if (o->sun_size > 0 || o->lamp_radius > 0) {
        double size[3] = {o->sun_size, o->lamp_radius, o->ref_samples};
        h = sb_fnv1a(h, size, sizeof size);
    }
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

/* A run's identity is the rows marked for it: another value of one of them is another run, any other option is
 * the same run; and every id is the one the hash gave before the identity was a column of the table. */
static void test_run_identity(void **st) {
    (void)st;
    sb_run_spec spec;
    sb_spec_defaults(&spec, sb_technique_find("sm"));
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    char base[17], id[17], legacy[17];
    sb_run_id(1, 2, &o, &spec, base);
    legacy_run_id(1, 2, &o, &spec, legacy);
    assert_string_equal(base, legacy);
    struct { const char *name, *value; bool identity; } cases[] = {
        {"--frames", "61", true},      {"--size", "640x360", true},   {"--backend", "osmesa", true},
        {"--sun", "10,20", true},      {"--submit", "indirect", true}, {"--sun-size", "0.5", true},
        {"--lamp-radius", "0.1", true}, {"--ref-samples", "32", false}, {"--ring", "2", false},
        {"--error-every", "3", false}, {"--threads", "1", false},      {"--warmup", "4", false},
    };
    for (size_t i = 0; i < SB_COUNT(cases); i++) {
        sb_cli_opts c;
        sb_err err;
        char *tok[] = {(char *)cases[i].name, (char *)cases[i].value};
        sb_cli_defaults(&c, NULL);
        assert_true(sb_cli_parse_tokens(&c, tok, 2, "id", &err));
        sb_run_id(1, 2, &c.run, &spec, id);
        legacy_run_id(1, 2, &c.run, &spec, legacy);
        if ((strcmp(id, base) != 0) != cases[i].identity) print_error("%s %s\n", cases[i].name, cases[i].value);
        assert_true((strcmp(id, base) != 0) == cases[i].identity);
        assert_string_equal(id, legacy);
    }
}

/* Every identity option reaches a run's key: a row with a summary column of its own names one that exists, and every
 * other row not at its default is in the run_options text (as "--NAME VALUE") by being a row: a new identity row
 * needs nothing else to keep its runs apart in compare and the history. */
static void test_run_options_text(void **st) {
    (void)st;
    sb_cli_opts c;
    sb_err err;
    char text[640];
    sb_cli_defaults(&c, NULL);
    sb_run_options_text(&c.run, text, sizeof text);
    assert_string_equal(text, "");
    char *tok[] = {"--sun", "10,20", "--taa", "on", "--submit", "indirect", "--frames", "7"};
    assert_true(sb_cli_parse_tokens(&c, tok, (int)SB_COUNT(tok), "id", &err));
    sb_run_options_text(&c.run, text, sizeof text);
    assert_string_equal(text, "--sun 10,20 --taa on");   /* submit has its column; frames is a dimension */
    int nrun, generic = 0;
    const sb_run_col *rc = sb_run_cols(&nrun);
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        if (opt->identity == SB_ID_NONE || opt->identity == SB_ID_DIM || opt->identity == SB_ID_LIGHT) continue;
        if (opt->id_column) {   /* its own column: one the summary has */
            bool found = false;
            for (int k = 0; k < nrun; k++) found |= !strcmp(rc[k].name, opt->id_column);
            if (!found) print_error("%s: no summary column %s\n", opt->name, opt->id_column);
            assert_true(found);
            continue;
        }
        sb_cli_defaults(&c, NULL);
        char *at = (char *)&c + opt->field;
        if (opt->identity == SB_ID_GIVEN) *(bool *)((char *)&c + opt->given_field) = true;
        else if (opt->identity == SB_ID_NAMED) *(int *)at = !strcmp(opt->def, "off") || *(int *)at == 0 ? 1 : 0;
        else *(const char **)at = "x";
        sb_run_options_text(&c.run, text, sizeof text);
        char want[80];
        snprintf(want, sizeof want, "%s ", opt->name);
        if (strncmp(text, want, strlen(want))) print_error("%s: run_options '%s'\n", opt->name, text);
        assert_int_equal(strncmp(text, want, strlen(want)), 0);
        generic++;
    }
    assert_true(generic >= 2);   /* --sun, --taa */
}

static void test_batch_defaults_line(void **st) {
    (void)st;
    for (int i = 0; i < sb_option_count; i++) {
        const sb_option *opt = &sb_options[i];
        bool run_option = false;
        for (int k = 0; k < sb_option_count; k++)
            run_option |= !strcmp(sb_options[k].name, opt->name) && sb_options[k].run_option;
        if (!run_option) {
            /* not a run option: the defaults line refuses it */
            char *tok[] = {(char *)opt->name, "1"};
            sb_cli_opts o;
            sb_err err;
            sb_cli_defaults(&o, NULL);
            assert_false(sb_cli_parse_tokens(&o, tok, 2, "n.bench:3", &err));
            assert_non_null(strstr(err.msg, "n.bench:3: '"));
            assert_non_null(strstr(err.msg, "is not a run option"));
        }
    }
    /* the command line's run options beat the file's, field by field */
    sb_cli_opts file, cli;
    sb_err err;
    sb_cli_defaults(&file, NULL);
    char *tok[] = {"--frames", "30", "--size", "96x54", "--sun", "10,20"};
    assert_true(sb_cli_parse_tokens(&file, tok, 6, "n.bench:2", &err));
    assert_true(parse(SB_CMD_BATCH, "--size", "64x32", &cli, &err));
    sb_run_opts r = file.run;
    sb_cli_copy_given(&r, &cli);
    assert_int_equal(r.frames, 30);
    assert_int_equal(r.width, 64);
    assert_int_equal(r.height, 32);
    assert_true(r.sun_override && r.sun_el == 20);
}

static char *source_file(const char *rel) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", getenv("SB_SOURCE_ROOT"), rel);
    sb_err err;
    char *text = sb_read_file(path, NULL, &err);
    assert_non_null(text);
    return text;
}

static void test_help_and_docs_name_every_option(void **st) {
    (void)st;
    char *man = source_file("docs/shadowbench.1"), *cli = source_file("docs/cli.md");
    /* the man page writes "\-" for "-" */
    for (char *r = man, *w = man;; r++) {
        if (r[0] == '\\' && r[1] == '-') r++;
        *w++ = *r;
        if (!*r) break;
    }
    for (int c = 0; c < SB_CMD_COUNT; c++) {
        char *help = NULL;
        size_t len = 0;
        FILE *f = open_memstream(&help, &len);
        sb_cli_help(f, sb_commands, CMD(c));
        fclose(f);
        for (int i = 0; i < sb_option_count; i++) {
            const sb_option *opt = &sb_options[i];
            char syn[64];
            sb_option_synopsis(opt, syn, sizeof syn);
            bool t = takes(opt, c);
            if (t != (strstr(help, syn) != NULL) && !(!t && sb_option_find(opt->name, CMD(c))))
                print_error("shadowbench %s --help %s %s\n", sb_commands[c].name, t ? "lacks" : "lists", syn);
            if (t) assert_non_null(strstr(help, syn));
            else if (!sb_option_find(opt->name, CMD(c))) assert_null(strstr(help, opt->name));
        }
        free(help);
    }
    for (int i = 0; i < sb_option_count; i++) {
        const char *n = sb_options[i].name;
        if (!strstr(man, n)) print_error("docs/shadowbench.1 does not name %s\n", n);
        if (!strstr(cli, n)) print_error("docs/cli.md does not name %s\n", n);
        assert_non_null(strstr(man, n));
        assert_non_null(strstr(cli, n));
    }
    for (int c = 0; c < SB_CMD_COUNT; c++) {
        char want[64];
        snprintf(want, sizeof want, "shadowbench %s", sb_commands[c].name);
        assert_non_null(strstr(cli, want));
    }
    /* every exit status of the table, with its code, in both */
    for (int i = 0; i < sb_exit_status_count; i++) {
        char code[16];
        snprintf(code, sizeof code, "%d", sb_exit_statuses[i].code);
        if (!strstr(man, code) || !strstr(cli, code)) print_error("exit status %s not in the docs\n", code);
        assert_non_null(strstr(man, code));
        assert_non_null(strstr(cli, code));
    }
    free(man);
    free(cli);
}

/* docs/cli.md's reference and the man page's synopsis, options and exit statuses are the tables themselves, as
 * `shadowbench help --format markdown|man` prints them; docs/techniques.md's parameter tables the technique rows;
 * and --help says every exit status of the table. */
static void cli_markdown(FILE *f) { sb_cli_doc(f, sb_commands, SB_DOC_MARKDOWN); }
static void cli_man(FILE *f) { sb_cli_doc(f, sb_commands, SB_DOC_MAN); }

static void test_docs_are_the_tables(void **st) {
    (void)st;
    assert_generated("docs/cli.md", "<!-- generated by `shadowbench help --format markdown`", NULL, cli_markdown);
    assert_generated("docs/shadowbench.1", ".\\\" generated by `shadowbench help --format man`",
                     ".\\\" end of the generated part", cli_man);
    assert_generated("docs/techniques.md", "<!-- generated by `shadowbench techniques --format markdown`", NULL,
                     sb_techniques_markdown);
    char *help = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&help, &len);
    sb_cli_help(f, sb_commands, NULL);
    fclose(f);
    char *w = help;   /* --help wraps its text: its runs of white space as one space */
    for (const char *r = help; *r; r++)
        if (!(*r == ' ' || *r == '\n') || (w > help && w[-1] != ' ')) *w++ = *r == '\n' ? ' ' : *r;
    *w = 0;
    for (int i = 0; i < sb_exit_status_count; i++) {
        char line[64];
        snprintf(line, sizeof line, "%d %s", sb_exit_statuses[i].code, sb_exit_statuses[i].name);
        assert_non_null(strstr(help, line));
        if (!strstr(help, sb_exit_statuses[i].meaning)) print_error("--help lacks: %s\n", sb_exit_statuses[i].meaning);
        assert_non_null(strstr(help, sb_exit_statuses[i].meaning));
    }
    /* what the exit statuses say covers the commands that exit 1 for a finding */
    const char *finders[] = {"compare", "history regressions", "history check", "bisect"};
    for (size_t k = 0; k < SB_COUNT(finders); k++) assert_non_null(strstr(sb_exit_statuses[1].meaning, finders[k]));
    free(help);
}

/* score's spec set from the command's words, name by name (the command does it so). */
static void score_words(sb_run_spec *spec, const char *const words[][2], int n) {
    const sb_technique *t = sb_technique_find("score");
    sb_spec_defaults(spec, t);
    sb_err err;
    for (int k = 0; k < n; k++)
        for (int i = 0; i < t->param_count; i++)
            if (!strcmp(t->params[i].name, words[k][0]))
                assert_true(sb_param_set(&spec->params, i, &t->params[i], words[k][1], t->name, &err));
    sb_spec_bind(spec);
}

/* Two parameter sets that differ only in where a separator stands are two runs: the canonical text escapes what
 * it joins on (renderer a:settings=b and renderer a with settings b gave one run id, and merged, one renderer's
 * frames were lost); a text without a separator is as it was. */
static void test_run_id_separators(void **st) {
    (void)st;
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    static const char *const pairs[][2][2][2] = {
        /* the issue's: joined unescaped, both are renderer=a:settings=b:settings= */
        {{{"renderer", "a"}, {"settings", "b:settings="}}, {{"renderer", "a:settings=b"}, {"settings", ""}}},
        {{{"dir", "d:vis=v"}, {"vis", "w"}}, {{"dir", "d"}, {"vis", "v:vis=w"}}},
        {{{"renderer", "a"}, {"settings", "b"}}, {{"renderer", "a:settings=b"}, {"settings", ""}}},
        {{{"renderer", "a"}, {"settings", "x=1:y=2"}}, {{"renderer", "a:settings=x=1"}, {"settings", "y=2"}}},
        {{{"renderer", "a,b"}, {"settings", ""}}, {{"renderer", "a"}, {"settings", ",b"}}},
        {{{"renderer", "a\\"}, {"settings", ":b"}}, {{"renderer", "a\\:"}, {"settings", "b"}}},
        {{{"dir", "d:renderer=r"}, {"renderer", "s"}}, {{"dir", "d"}, {"renderer", "r:renderer=s"}}},
    };
    for (size_t k = 0; k < SB_COUNT(pairs); k++) {
        sb_run_spec a, b;
        score_words(&a, pairs[k][0], 2);
        score_words(&b, pairs[k][1], 2);
        char ta[SB_PARAMS_TEXT_LEN], tb[SB_PARAMS_TEXT_LEN], ia[17], ib[17];
        sb_params_canonical(&a.params, ta, sizeof ta);
        sb_params_canonical(&b.params, tb, sizeof tb);
        sb_run_id(1, 2, &o, &a, ia);
        sb_run_id(1, 2, &o, &b, ib);
        print_message("%s (%s) against %s (%s)\n", ta, ia, tb, ib);
        assert_string_not_equal(ta, tb);
        assert_string_not_equal(ia, ib);
    }
    /* no separator: the text as it always was */
    sb_run_spec plain;
    score_words(&plain, (const char *const[][2]){{"dir", "frames"}, {"renderer", "three.js"}}, 2);
    char t[SB_PARAMS_TEXT_LEN];
    sb_params_canonical(&plain.params, t, sizeof t);
    assert_non_null(strstr(t, "dir=frames:"));
    assert_non_null(strstr(t, ":renderer=three.js"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_option_by_command),  cmocka_unit_test(test_out_of_range_names_the_range),
        cmocka_unit_test(test_defaults_parse),           cmocka_unit_test(test_values_reach_their_fields),
        cmocka_unit_test(test_batch_defaults_line),      cmocka_unit_test(test_help_and_docs_name_every_option),
        cmocka_unit_test(test_run_identity),             cmocka_unit_test(test_docs_are_the_tables),
        cmocka_unit_test(test_run_options_text),         cmocka_unit_test(test_run_id_separators),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
