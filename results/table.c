/* table.c - a small RFC 4180 CSV reader. */
#include "table.h"

#include <stdlib.h>
#include <string.h>

typedef struct {
    char **v;
    int n, cap;
} strvec;

static void push(strvec *s, char *x) {
    if (s->n == s->cap) {
        s->cap = s->cap ? s->cap * 2 : 16;
        s->v = sb_xrealloc(s->v, (size_t)s->cap * sizeof *s->v);
    }
    s->v[s->n++] = x;
}

/* Parses one record starting at *p; returns false at end of input. */
static bool record(const char **p, strvec *fields, char **line, bool *bad) {
    const char *s = *p;
    if (!*s) return false;
    const char *start = s;
    size_t cap = 64, len = 0;
    char *buf = sb_xmalloc(cap);
    for (;;) {
        len = 0;
        bool quoted = *s == '"';
        if (quoted) s++;
        for (;;) {
            char c = *s;
            if (!c) {
                if (quoted) *bad = true;
                break;
            }
            if (quoted && c == '"') {
                if (s[1] == '"') {
                    c = '"';
                    s++;
                } else {
                    s++;
                    quoted = false;
                    continue;
                }
            } else if (!quoted && (c == ',' || c == '\n' || c == '\r')) {
                break;
            }
            if (len + 2 > cap) buf = sb_xrealloc(buf, cap *= 2);
            buf[len++] = c;
            s++;
        }
        buf[len] = 0;
        push(fields, sb_strdup(buf));
        if (*s == ',') {
            s++;
            continue;
        }
        break;
    }
    const char *end = s;
    if (*s == '\r') s++;
    if (*s == '\n') s++;
    *line = sb_xmalloc((size_t)(end - start) + 1);
    memcpy(*line, start, (size_t)(end - start));
    (*line)[end - start] = 0;
    *p = s;
    free(buf);
    return true;
}

bool sb_table_parse(sb_table *t, const char *name, const char *text, sb_err *err) {
    memset(t, 0, sizeof *t);
    const char *p = text;
    strvec hdr = {0};
    char *line;
    bool bad = false;
    if (!record(&p, &hdr, &line, &bad) || bad) {
        free(hdr.v);
        return sb_fail(err, "%s: no CSV header", name);
    }
    free(line);
    t->header = hdr.v;
    t->cols = hdr.n;
    int cap = 0, lineno = 1;
    for (;;) {
        strvec f = {0};
        if (!record(&p, &f, &line, &bad)) break;
        lineno++;
        if (bad || f.n != t->cols) {
            for (int i = 0; i < f.n; i++) free(f.v[i]);
            free(f.v);
            free(line);
            sb_fail(err, "%s:%d: expected %d fields, found %d%s", name, lineno, t->cols, f.n,
                    bad ? " (unterminated quote)" : "");
            sb_table_free(t);
            return false;
        }
        if (t->nrows == cap) {
            cap = cap ? cap * 2 : 16;
            t->rows = sb_xrealloc(t->rows, (size_t)cap * sizeof *t->rows);
            t->lines = sb_xrealloc(t->lines, (size_t)cap * sizeof *t->lines);
        }
        t->rows[t->nrows] = f.v;
        t->lines[t->nrows++] = line;
    }
    return true;
}

bool sb_table_load(sb_table *t, const char *path, sb_err *err) {
    char *text = sb_read_file(path, NULL, err);
    if (!text) return false;
    bool ok = sb_table_parse(t, path, text, err);
    free(text);
    return ok;
}

void sb_table_free(sb_table *t) {
    for (int r = 0; r < t->nrows; r++) {
        for (int c = 0; c < t->cols; c++) free(t->rows[r][c]);
        free(t->rows[r]);
        free(t->lines[r]);
    }
    for (int c = 0; c < t->cols; c++) free(t->header[c]);
    free(t->header);
    free(t->rows);
    free(t->lines);
    memset(t, 0, sizeof *t);
}

int sb_table_col(const sb_table *t, const char *name) {
    for (int c = 0; c < t->cols; c++)
        if (!strcmp(t->header[c], name)) return c;
    return -1;
}

const char *sb_table_get(const sb_table *t, int r, const char *name) {
    int c = sb_table_col(t, name);
    return c < 0 || r < 0 || r >= t->nrows ? "" : t->rows[r][c];
}
