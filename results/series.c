/* series.c - a series' fields and its key text (series.h). */
#include "series.h"

#include <stdio.h>
#include <string.h>

#include "runkey.h"
#include "util.h"

void sb_series_params_text(const sb_series *s, char *out, size_t len) {
    char tail[sizeof s->light + sizeof s->anim + sizeof s->run_options + 32];
    sb_key_tail(s->light, s->anim, s->indirect, s->run_options, tail, sizeof tail);
    snprintf(out, len, "%s%s", s->params, tail);
}

void sb_series_key(const sb_series *s, char *out, size_t len) {
    char p[sizeof s->params + sizeof s->light + sizeof s->anim + sizeof s->run_options + 32];
    sb_series_params_text(s, p, sizeof p);
    snprintf(out, len, "%s|%s|%s|%s|%s|%s|%s", s->host, s->renderer, s->scene, s->path, s->size, s->technique, p);
}

/* Field k of a '|'-separated text into out; returns where the next field starts (NULL: none). */
static const char *next_field(const char *p, char *out, size_t len) {
    size_t n = strcspn(p, "|");
    snprintf(out, len, "%.*s", (int)n, p);
    return p[n] ? p + n + 1 : NULL;
}

void sb_series_parse(const char *key, sb_series *s) {
    memset(s, 0, sizeof *s);
    char *fields[] = {s->host, s->renderer, s->scene, s->path, s->size, s->technique, s->params};
    size_t sizes[] = {sizeof s->host, sizeof s->renderer, sizeof s->scene, sizeof s->path, sizeof s->size,
                      sizeof s->technique, sizeof s->params};
    const char *p = key;
    for (size_t k = 0; k < SB_COUNT(fields) && p; k++) p = next_field(p, fields[k], sizes[k]);
    while (p) {   /* what follows the parameters: a sized light, the submission */
        char extra[sizeof s->light];
        p = next_field(p, extra, sizeof extra);
        if (!strcmp(extra, "indirect")) s->indirect = true;
        else if (!strncmp(extra, "--", 2))
            snprintf(s->run_options, sizeof s->run_options, "%.*s", (int)sizeof s->run_options - 1, extra);
        else if (!strncmp(extra, "anim=", 5)) snprintf(s->anim, sizeof s->anim, "%.*s", (int)sizeof s->anim - 1, extra + 5);
        else snprintf(s->light, sizeof s->light, "%s", extra);
    }
}

void sb_series_of_row(const sb_table *t, int r, const char *host, const char *renderer, sb_series *s) {
    sb_run_key k;
    sb_run_key_of(t, r, &k);
    memset(s, 0, sizeof *s);
    snprintf(s->host, sizeof s->host, "%s", host);
    snprintf(s->renderer, sizeof s->renderer, "%s", renderer);
    snprintf(s->scene, sizeof s->scene, "%s", k.scene);
    snprintf(s->path, sizeof s->path, "%s", k.path);
    snprintf(s->size, sizeof s->size, "%sx%s", k.width, k.height);
    snprintf(s->technique, sizeof s->technique, "%s", k.technique);
    sb_run_key_sorted_params(k.params, s->params, sizeof s->params);
    snprintf(s->light, sizeof s->light, "%s", k.light);
    snprintf(s->anim, sizeof s->anim, "%s", k.anim);
    snprintf(s->run_options, sizeof s->run_options, "%s", k.run_options);
    s->indirect = sb_run_key_indirect(&k);
}

bool sb_series_equal(const sb_series *a, const sb_series *b) {
    return a->indirect == b->indirect && !strcmp(a->host, b->host) && !strcmp(a->renderer, b->renderer) &&
           !strcmp(a->scene, b->scene) && !strcmp(a->path, b->path) && !strcmp(a->size, b->size) &&
           !strcmp(a->technique, b->technique) && !strcmp(a->params, b->params) && !strcmp(a->light, b->light) &&
           !strcmp(a->anim, b->anim) && !strcmp(a->run_options, b->run_options);
}
