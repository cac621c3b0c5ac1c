/* runkey.c - the one reader of a results set's identity columns (runkey.h). */
#include "runkey.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util.h"

/* The identity columns, in sb_run_key's order: the only place their names are read. */
static const char *const key_cols[] = {"run_id", "scene", "path", "technique", "params", "light",
                                       "anim", "submit", "renderer", "width", "height", "run_options"};
#define KEY_FIELDS (sizeof key_cols / sizeof key_cols[0])

static void fill(const sb_table *t, int r, const int *col, sb_run_key *k) {
    const char *v[KEY_FIELDS];
    for (size_t i = 0; i < KEY_FIELDS; i++) v[i] = col[i] < 0 || r < 0 || r >= t->nrows ? "" : t->rows[r][col[i]];
    *k = (sb_run_key){.run_id = v[0], .scene = v[1], .path = v[2], .technique = v[3], .params = v[4], .light = v[5],
                      .anim = v[6], .submit = v[7], .renderer = v[8], .width = v[9], .height = v[10],
                      .run_options = v[11]};
}

static void columns(const sb_table *t, int *col) {
    for (size_t i = 0; i < KEY_FIELDS; i++) col[i] = sb_table_col(t, key_cols[i]);
}

const char *sb_run_key_missing(const sb_table *t, bool sized) {
    for (size_t i = 0; i < KEY_FIELDS; i++)
        if ((i < 5 || (sized && (i == 9 || i == 10))) && sb_table_col(t, key_cols[i]) < 0) return key_cols[i];
    return NULL;
}

void sb_run_key_of(const sb_table *t, int r, sb_run_key *k) {
    int col[KEY_FIELDS];
    columns(t, col);
    fill(t, r, col, k);
}

const char *sb_run_key_id(const sb_table *t, int r) {
    int c = sb_table_col(t, key_cols[0]);
    return c < 0 || r < 0 || r >= t->nrows ? "" : t->rows[r][c];
}

sb_run_key *sb_run_keys(const sb_table *t) {
    int col[KEY_FIELDS];
    columns(t, col);
    sb_run_key *k = sb_xmalloc(sizeof *k * (size_t)(t->nrows ? t->nrows : 1));
    for (int r = 0; r < t->nrows; r++) fill(t, r, col, &k[r]);
    return k;
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(const char *const *)a, *(const char *const *)b); }

void sb_run_key_sorted_params(const char *params, char *out, size_t len) {
    char buf[2048];
    const char *items[64];
    int n = 0;
    snprintf(buf, sizeof buf, "%s", params);
    for (char *t = strtok(buf, ":"); t && n < 64; t = strtok(NULL, ":")) items[n++] = t;
    qsort(items, (size_t)n, sizeof(char *), cmp_str);
    out[0] = 0;
    for (int i = 0; i < n; i++) {
        size_t l = strlen(out);
        snprintf(out + l, len - l, "%s%s", i ? ":" : "", items[i]);
    }
}

bool sb_run_key_indirect(const sb_run_key *k) { return !strcmp(k->submit, "indirect"); }

void sb_key_tail(const char *light, const char *anim, bool indirect, const char *run_options, char *out, size_t len) {
    snprintf(out, len, "%s%s%s%s%s%s%s", *light ? "|" : "", light, *anim ? "|anim=" : "", anim,
             indirect ? "|indirect" : "", *run_options ? "|" : "", run_options);
}

void sb_run_key_text(const sb_run_key *k, char *out, size_t len) {
    char p[2048], tail[4096];
    sb_run_key_sorted_params(k->params, p, sizeof p);
    sb_key_tail(k->light, k->anim, sb_run_key_indirect(k), k->run_options, tail, sizeof tail);
    snprintf(out, len, "%s|%s|%s|%s%s", k->scene, k->path, k->technique, p, tail);
}
