/* spec.c - parsing and expanding technique specs. */
#include "spec.h"

#include <stdlib.h>
#include <string.h>

#define MAX_VALUES 16

typedef struct {
    int param;                  /* index into the technique's table */
    int nvalues;
    const char *values[MAX_VALUES];   /* in the spec's copy */
} axis;

static void list_params(const sb_technique *t, char *out, size_t len) {
    out[0] = 0;
    for (int i = 0; i < t->param_count; i++) {
        size_t n = strlen(out);
        snprintf(out + n, len - n, "%s%s", i ? ", " : "", t->params[i].name);
    }
    if (!t->param_count) snprintf(out, len, "none");
}

static void list_techniques(char *out, size_t len) {
    out[0] = 0;
    for (int i = 0; i < sb_technique_count(); i++) {
        size_t n = strlen(out);
        snprintf(out + n, len - n, "%s%s", i ? ", " : "", sb_technique_at(i)->name);
    }
}

void sb_spec_bind(sb_run_spec *rs) {
    if (rs->tech->desc_size > SB_DESC_MAX) {   /* a technique's struct outgrew the spec: say it, never overrun */
        fprintf(stderr, "shadowbench: %s's parameter struct is %zu bytes, more than SB_DESC_MAX (%d): raise it\n",
                rs->tech->name, rs->tech->desc_size, SB_DESC_MAX);
        abort();
    }
    sb_params_bind(&rs->params, rs->tech, rs->desc);
}

void sb_spec_defaults(sb_run_spec *rs, const sb_technique *t) {
    rs->tech = t;
    sb_params_defaults(&rs->params, t);
    sb_spec_bind(rs);
}

double sb_spec_shadow_bytes(const sb_run_spec *rs) {
    return rs->tech->shadow_bytes ? rs->tech->shadow_bytes(rs->tech, rs->desc) : 0;
}

/* A combination the technique cannot run (stable with a warp, ...): refused
 * with the combination named, before anything renders. */
static bool check_combination(const sb_run_spec *rs, const char *pre, sb_err *err) {
    sb_err e;
    if (rs->tech->check(rs->desc, &e)) return true;
    char canon[SB_PARAMS_TEXT_LEN];
    sb_params_canonical(&rs->params, canon, sizeof canon);
    return sb_fail(err, "%s%s:%s: %s", pre, rs->tech->name, canon, e.msg);
}

bool sb_spec_expand(const char *spec, const char *where, sb_run_spec **runs, int *count, sb_err *err) {
    char pre[256];
    snprintf(pre, sizeof pre, "%s%s", where ? where : "", where ? ": " : "");
    char buf[4096];
    if (strlen(spec) >= sizeof buf) return sb_fail(err, "%sspec too long", pre);
    snprintf(buf, sizeof buf, "%s", spec);
    char *save = NULL;
    char *name = strtok_r(buf, ":", &save);
    if (!name || !*name) return sb_fail(err, "%sempty technique spec", pre);
    const sb_technique *t = sb_technique_find(name);
    if (!t) {
        char names[512];
        list_techniques(names, sizeof names);
        return sb_fail(err, "%sunknown technique '%s' (known: %s)", pre, name, names);
    }
    axis axes[SB_MAX_PARAMS];
    int naxes = 0;
    for (char *opt = strtok_r(NULL, ":", &save); opt; opt = strtok_r(NULL, ":", &save)) {
        char *eq = strchr(opt, '=');
        if (!eq || eq == opt || !eq[1])
            return sb_fail(err, "%s%s: option '%s' is not NAME=VALUE[,VALUE...]", pre, t->name, opt);
        *eq = 0;
        int pi = -1;
        for (int i = 0; i < t->param_count; i++)
            if (strcmp(t->params[i].name, opt) == 0) pi = i;
        if (pi < 0) {
            char valid[512];
            list_params(t, valid, sizeof valid);
            return sb_fail(err, "%s%s: unknown parameter '%s' (valid: %s)", pre, t->name, opt, valid);
        }
        for (int a = 0; a < naxes; a++)
            if (axes[a].param == pi) return sb_fail(err, "%s%s: parameter '%s' given twice", pre, t->name, opt);
        axis *ax = &axes[naxes++];
        ax->param = pi;
        ax->nvalues = 0;
        char *vsave = NULL;
        for (char *v = strtok_r(eq + 1, ",", &vsave); v; v = strtok_r(NULL, ",", &vsave)) {
            if (ax->nvalues == MAX_VALUES)
                return sb_fail(err, "%s%s: too many values for '%s' (at most %d a parameter; give another spec for "
                                    "more)", pre, t->name, opt, MAX_VALUES);
            sb_params probe;
            sb_err e;
            if (!sb_param_set(&probe, 0, &t->params[pi], v, t->name, &e)) return sb_fail(err, "%s%s", pre, e.msg);
            ax->values[ax->nvalues++] = v;
        }
        if (!ax->nvalues) return sb_fail(err, "%s%s: no value for '%s'", pre, t->name, opt);
    }
    long total = 1;
    for (int a = 0; a < naxes; a++) total *= axes[a].nvalues;
    if (total > SB_SPEC_MAX_RUNS)
        return sb_fail(err, "%s%s: the grid is %ld runs, more than %d a spec", pre, t->name, total, SB_SPEC_MAX_RUNS);
    *runs = sb_xrealloc(*runs, (size_t)(*count + total) * sizeof **runs);
    for (int r = 0; r < (int)total; r++) {
        sb_run_spec *rs = &(*runs)[*count + r];
        rs->tech = t;
        sb_params_defaults(&rs->params, t);
        /* last axis varies fastest, like nested loops written in order */
        int rem = r;
        for (int a = naxes - 1; a >= 0; a--) {
            int k = rem % axes[a].nvalues;
            rem /= axes[a].nvalues;
            sb_param_set(&rs->params, axes[a].param, &t->params[axes[a].param], axes[a].values[k], t->name, err);
            rs->params.v[axes[a].param].given = true;
        }
        sb_spec_bind(rs);
        if (t->check && !check_combination(rs, pre, err)) return false;
    }
    *count += (int)total;
    return true;
}

void sb_spec_light_size(sb_run_spec *rs, double sun_size_deg) {
    if (sun_size_deg <= 0) return;
    for (int i = 0; i < rs->params.count; i++) {
        const sb_param_def *d = rs->params.v[i].def;
        if (d->role != SB_PARAM_SUN_SIZE || rs->params.v[i].given) continue;
        char v[32];
        snprintf(v, sizeof v, "%g", sun_size_deg);
        sb_err e;
        sb_param_set(&rs->params, i, d, v, rs->tech->name, &e);   /* in its range: --sun-size's is sun_size's */
    }
    sb_spec_bind(rs);
}
