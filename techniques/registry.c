/* registry.c - the list of techniques and their parameter values. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "technique.h"

extern const sb_technique sb_technique_none;
extern const sb_technique sb_technique_sm;
extern const sb_technique sb_technique_pssm;
extern const sb_technique sb_technique_sdsm;
extern const sb_technique sb_technique_raycast;
extern const sb_technique sb_technique_volumes;
extern const sb_technique sb_technique_planar;
extern const sb_technique sb_technique_lispsm;
extern const sb_technique sb_technique_cube;
extern const sb_technique sb_technique_dpsm;
extern const sb_technique sb_technique_tsm;
extern const sb_technique sb_technique_psm;

static const sb_technique *const all[] = {&sb_technique_none,    &sb_technique_sm,      &sb_technique_pssm,
                                          &sb_technique_sdsm,    &sb_technique_raycast, &sb_technique_volumes,
                                          &sb_technique_planar, &sb_technique_lispsm,  &sb_technique_cube,
                                          &sb_technique_dpsm,   &sb_technique_tsm,     &sb_technique_psm};

const char *const sb_stage_names[SB_STAGE_COUNT] = {"zpass", "minmax", "cascade", "final", "volumes", "rays"};

const sb_technique *sb_technique_find(const char *name) {
    for (size_t i = 0; i < SB_COUNT(all); i++)
        if (strcmp(all[i]->name, name) == 0) return all[i];
    return NULL;
}

int sb_technique_count(void) { return (int)SB_COUNT(all); }
const sb_technique *sb_technique_at(int i) { return all[i]; }

static int find_param(const sb_params *p, const char *name) {
    for (int i = 0; i < p->count; i++)
        if (strcmp(p->v[i].def->name, name) == 0) return i;
    return -1;
}

double sb_param_num(const sb_params *p, const char *name) {
    int i = find_param(p, name);
    return i < 0 ? NAN : p->v[i].num;
}

int sb_param_choice(const sb_params *p, const char *name) {
    int i = find_param(p, name);
    return i < 0 ? -1 : (int)p->v[i].num;
}

void sb_params_canonical(const sb_params *p, char *out, size_t len) {
    out[0] = 0;
    for (int i = 0; i < p->count; i++) {
        size_t n = strlen(out);
        snprintf(out + n, len - n, "%s%s=%s", i ? ":" : "", p->v[i].def->name, p->v[i].text);
    }
}

bool sb_param_set(sb_params *p, int i, const sb_param_def *d, const char *value, const char *tech, sb_err *err) {
    p->v[i].def = d;
    if (d->kind == SB_PARAM_ENUM) {
        const char *c = d->choices;
        for (int k = 0; *c; k++) {
            const char *bar = strchr(c, '|');
            size_t n = bar ? (size_t)(bar - c) : strlen(c);
            if (strlen(value) == n && strncmp(value, c, n) == 0) {
                p->v[i].num = k;
                snprintf(p->v[i].text, sizeof p->v[i].text, "%s", value);
                return true;
            }
            c += n + (bar ? 1 : 0);
        }
        return sb_fail(err, "%s:%s=%s: expected one of %s", tech, d->name, value, d->choices);
    }
    double v;
    if (!sb_parse_double(value, &v))
        return sb_fail(err, "%s:%s=%s: expected a number in [%g, %g]", tech, d->name, value, d->min, d->max);
    if (d->kind == SB_PARAM_INT && v != floor(v))
        return sb_fail(err, "%s:%s=%s: expected an integer in [%g, %g]", tech, d->name, value, d->min, d->max);
    if (v < d->min || v > d->max)
        return sb_fail(err, "%s:%s=%s: out of range [%g, %g]", tech, d->name, value, d->min, d->max);
    p->v[i].num = v;
    snprintf(p->v[i].text, sizeof p->v[i].text, "%.10g", v);
    return true;
}

void sb_params_defaults(sb_params *p, const sb_technique *t) {
    memset(p, 0, sizeof *p);
    p->count = t->param_count;
    for (int i = 0; i < t->param_count; i++) {
        sb_err e;
        sb_param_set(p, i, &t->params[i], t->params[i].def, t->name, &e);
    }
}
