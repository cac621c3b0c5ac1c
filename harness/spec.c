/* spec.c - parsing and expanding technique specs. */
#include "spec.h"

#include <stdlib.h>
#include <string.h>

#define MAX_VALUES 16

typedef struct {
    int param;                  /* index into the technique's table */
    int nvalues;
    char values[MAX_VALUES][32];
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

/* A combination the technique cannot run (stable with a warp, ...): refused
 * with the combination named, before anything renders. */
static bool check_combination(const sb_technique *t, const sb_params *p, const char *pre, sb_err *err) {
    void *desc = sb_xcalloc(1, t->desc_size ? t->desc_size : 1);
    sb_params_bind(p, t, desc);
    sb_err e;
    bool ok = t->check(desc, &e);
    free(desc);
    if (ok) return true;
    char canon[1024];
    sb_params_canonical(p, canon, sizeof canon);
    return sb_fail(err, "%s%s:%s: %s", pre, t->name, canon, e.msg);
}

bool sb_spec_expand(const char *spec, const char *where, sb_run_spec **runs, int *count, sb_err *err) {
    char pre[256];
    snprintf(pre, sizeof pre, "%s%s", where ? where : "", where ? ": " : "");
    char buf[1024];
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
            if (ax->nvalues == MAX_VALUES) return sb_fail(err, "%s%s: too many values for '%s'", pre, t->name, opt);
            sb_params probe;
            sb_err e;
            if (!sb_param_set(&probe, 0, &t->params[pi], v, t->name, &e)) return sb_fail(err, "%s%s", pre, e.msg);
            snprintf(ax->values[ax->nvalues++], 32, "%s", v);
        }
        if (!ax->nvalues) return sb_fail(err, "%s%s: no value for '%s'", pre, t->name, opt);
    }
    int total = 1;
    for (int a = 0; a < naxes; a++) total *= axes[a].nvalues;
    *runs = sb_xrealloc(*runs, (size_t)(*count + total) * sizeof **runs);
    for (int r = 0; r < total; r++) {
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
        if (t->check && !check_combination(t, &rs->params, pre, err)) return false;
    }
    *count += total;
    return true;
}

void sb_spec_light_size(sb_run_spec *rs, double sun_size_deg) {
    if (sun_size_deg <= 0) return;
    for (int i = 0; i < rs->params.count; i++) {
        const sb_param_def *d = rs->params.v[i].def;
        if (strcmp(d->name, "sun_size") || rs->params.v[i].given) continue;
        char v[32];
        snprintf(v, sizeof v, "%g", sun_size_deg);
        sb_err e;
        sb_param_set(&rs->params, i, d, v, rs->tech->name, &e);   /* in its range: --sun-size's is sun_size's */
    }
}
