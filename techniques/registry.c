/* registry.c - the list of techniques (from techniques/meson.build, through
 * the generated technique_list.h) and their parameter values. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <stdlib.h>

#include "pose.h"
#include "technique.h"

#define SB_TECHNIQUE(name) extern const sb_technique sb_technique_##name;
#include "technique_list.h"
#undef SB_TECHNIQUE

static const sb_technique *const all[] = {
#define SB_TECHNIQUE(name) &sb_technique_##name,
#include "technique_list.h"
#undef SB_TECHNIQUE
};


const sb_technique *sb_technique_find(const char *name) {
    for (size_t i = 0; i < SB_COUNT(all); i++)
        if (strcmp(all[i]->name, name) == 0) return all[i];
    return NULL;
}

int sb_technique_count(void) { return (int)SB_COUNT(all); }
const sb_technique *sb_technique_at(int i) { return all[i]; }

int sb_technique_index(const sb_technique *t) {
    for (size_t i = 0; i < SB_COUNT(all); i++)
        if (all[i] == t) return (int)i;
    return -1;
}

void sb_params_canonical(const sb_params *p, char *out, size_t len) {
    out[0] = 0;
    size_t n = 0;
    for (int i = 0; i < p->count && n + 1 < len; i++) {
        if (p->v[i].def->late && !strcmp(sb_param_text(p, i), p->v[i].def->def)) continue;
        n += (size_t)snprintf(out + n, len - n, "%s%s=", n ? ":" : "", p->v[i].def->name);
        /* a TEXT value may hold what the text joins on (score's words: a renderer named "a:settings=b"): each such
           character escaped, so that two different parameter sets never give one text (nor one run id); a value
           without one is written as it is (every run id from before stands) */
        for (const char *c = sb_param_text(p, i); *c && n + 2 < len; c++) {
            if (*c == ':' || *c == ',' || *c == '\\') out[n++] = '\\';
            out[n++] = *c;
        }
        if (n >= len) n = len - 1;
        out[n] = 0;
    }
}

bool sb_param_set(sb_params *p, int i, const sb_param_def *d, const char *value, const char *tech, sb_err *err) {
    p->v[i].def = d;
    p->v[i].automatic = false;
    if (d->can_auto && strcmp(value, "auto") == 0) {
        p->v[i].automatic = true;
        sb_parse_double(d->def, &p->v[i].num);
        snprintf(p->v[i].text, sizeof p->v[i].text, "auto");
        return true;
    }
    if (d->kind == SB_PARAM_TEXT) {   /* one line of text, or empty */
        char what[96];
        snprintf(what, sizeof what, "%s:%s", tech, d->name);
        if (*value && !sb_name_check(what, value, err)) return false;
        if (strlen(value) > SB_PARAM_TEXT_MAX)
            return sb_fail(err, "%s:%s: the value is %zu characters, more than %d", tech, d->name, strlen(value),
                           SB_PARAM_TEXT_MAX);
        p->v[i].str = sb_intern(value);
        snprintf(p->v[i].text, sizeof p->v[i].text, "%s", value);
        return true;
    }
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
        return sb_fail(err, "%s:%s=%s: expected a number in [%g, %g]%s", tech, d->name, value, d->min, d->max,
                       d->can_auto ? " or auto" : "");
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

bool sb_params_find(const sb_params *p, const char *name, double *out) {
    for (int i = 0; i < p->count; i++)
        if (!strcmp(p->v[i].def->name, name)) {
            *out = p->v[i].num;
            return true;
        }
    return false;
}

bool sb_params_role(const sb_params *p, sb_param_role role, double *out) {
    for (int i = 0; i < p->count; i++)
        if (p->v[i].def->role == role) {
            *out = p->v[i].num;
            return true;
        }
    return false;
}

/* ---- the stages: every declared one, each once, in slot order ---- */

static const sb_stage_def *stage_list[SB_TIMER_STAGES];
static int stage_n;

static void add_stage(const sb_stage_def *d, const char *who) {
    for (int k = 0; k < stage_n; k++)
        if (stage_list[k] == d) return;
    if (stage_n == SB_TIMER_STAGES) {   /* the build's own mistake, found by any test that times a frame */
        fprintf(stderr, "shadowbench: %s: stage '%s' is one more than the timer's ring holds (SB_TIMER_STAGES, %d)\n",
                who, d->name, SB_TIMER_STAGES);
        abort();
    }
    stage_list[stage_n++] = d;
}

static void make_stages(void) {
    if (stage_n) return;
    for (int k = 0; k < sb_stages_shared_count; k++) add_stage(sb_stages_shared[k], "stage.c");
    for (size_t i = 0; i < SB_COUNT(all); i++)
        for (int k = 0; k < all[i]->stage_count; k++) add_stage(all[i]->stages[k], all[i]->name);
    add_stage(&sb_stage_pose, "pose.c");
}

int sb_stage_count(void) {
    make_stages();
    return stage_n;
}

const sb_stage_def *sb_stage_at(int slot) {
    make_stages();
    return slot >= 0 && slot < stage_n ? stage_list[slot] : NULL;
}

int sb_stage_slot(const sb_stage_def *def) {
    make_stages();
    for (int k = 0; k < stage_n; k++)
        if (stage_list[k] == def) return k;
    return -1;
}

unsigned sb_technique_stage_mask(const sb_technique *t) {
    unsigned m = 0;
    for (int k = 0; k < t->stage_count; k++) m |= SB_STAGE_BIT(sb_stage_slot(t->stages[k]));
    return m;
}

bool sb_technique_times(const sb_technique *t, const sb_stage_def *def) {
    for (int k = 0; k < t->stage_count; k++)
        if (t->stages[k] == def) return true;
    return false;
}

const sb_technique *sb_technique_with(unsigned trait) {
    for (int i = 0; i < sb_technique_count(); i++)
        if (sb_technique_at(i)->traits & trait) return sb_technique_at(i);
    return NULL;
}

void sb_params_bind(const sb_params *p, const sb_technique *t, void *desc) {
    if (t->desc_defaults) memcpy(desc, t->desc_defaults, t->desc_size);
    else memset(desc, 0, t->desc_size);
    for (int i = 0; i < p->count; i++) {
        const sb_param_def *d = p->v[i].def;
        char *field = (char *)desc + d->offset;
        if (d->kind == SB_PARAM_TEXT && d->size == sizeof(const char *)) {
            memcpy(field, &p->v[i].str, sizeof(const char *));
        } else if (d->kind == SB_PARAM_FLOAT && d->size == sizeof(double)) {
            memcpy(field, &p->v[i].num, sizeof(double));
        } else if (d->size == sizeof(int)) {
            int v = (int)p->v[i].num;
            memcpy(field, &v, sizeof v);
        }
    }
}



/* A markdown cell: '|' escaped. */
static void md(FILE *out, const char *text) {
    for (const char *p = text; *p; p++) {
        if (*p == '|') fputc('\\', out);
        fputc(*p, out);
    }
}

void sb_techniques_markdown(FILE *out) {
    for (int i = 0; i < sb_technique_count(); i++) {
        const sb_technique *t = sb_technique_at(i);
        fprintf(out, "%s#### `%s`\n\n", i ? "\n" : "", t->name);
        md(out, t->summary);
        fputs(t->param_count ? "\n\n| parameter | values | default | tune searches | meaning |\n|---|---|---|---|---|\n"
                             : "\n\nNo parameters.\n",
              out);
        for (int k = 0; k < t->param_count; k++) {
            const sb_param_def *p = &t->params[k];
            char values[160];
            if (p->kind == SB_PARAM_ENUM) snprintf(values, sizeof values, "%s", p->choices);
            else if (p->kind == SB_PARAM_TEXT) snprintf(values, sizeof values, "text");
            else snprintf(values, sizeof values, "%s %g..%g%s", p->kind == SB_PARAM_INT ? "int" : "float", p->min,
                          p->max, p->can_auto ? " or auto" : "");
            fprintf(out, "| `%s` | ", p->name);
            md(out, values);
            fprintf(out, " | %s | %s | ", p->kind == SB_PARAM_TEXT && !*p->def ? "(none)" : p->def, p->tune ? p->tune : "");
            md(out, p->help);
            fputs(" |\n", out);
        }
    }
}
