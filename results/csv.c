/* csv.c - CSV formatting and atomic per-run files. */
#include "csv.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void put(sb_csv *c, const char *s, size_t n) {
    if (c->len + n + 1 > c->cap) {
        size_t cap = c->cap ? c->cap : 4096;
        while (cap < c->len + n + 1) cap *= 2;
        c->buf = sb_xrealloc(c->buf, cap);
        c->cap = cap;
    }
    memcpy(c->buf + c->len, s, n);
    c->len += n;
    c->buf[c->len] = 0;
}

static void sep(sb_csv *c) {
    if (c->fields++) put(c, ",", 1);
}

void sb_csv_str(sb_csv *c, const char *s) {
    sep(c);
    if (!s) return;
    if (!strpbrk(s, ",\"\n\r")) {
        put(c, s, strlen(s));
        return;
    }
    put(c, "\"", 1);
    for (const char *p = s; *p; p++) {
        if (*p == '"') put(c, "\"", 1);
        put(c, p, 1);
    }
    put(c, "\"", 1);
}

void sb_csv_num(sb_csv *c, double v) {
    sep(c);
    if (!isfinite(v)) return;
    char b[64];
    int n = snprintf(b, sizeof b, "%.6g", v);
    put(c, b, (size_t)n);
}

void sb_csv_int(sb_csv *c, long long v) {
    sep(c);
    char b[32];
    int n = snprintf(b, sizeof b, "%lld", v);
    put(c, b, (size_t)n);
}

void sb_csv_empty(sb_csv *c) { sep(c); }

void sb_csv_end_row(sb_csv *c) {
    put(c, "\n", 1);
    c->fields = 0;
}

void sb_csv_line(sb_csv *c, const char *row) {
    put(c, row, strlen(row));
    put(c, "\n", 1);
    c->fields = 0;
}

void sb_csv_reset(sb_csv *c) {
    c->len = 0;
    c->fields = 0;
    if (c->buf) c->buf[0] = 0;
}

void sb_csv_free(sb_csv *c) {
    free(c->buf);
    memset(c, 0, sizeof *c);
}

bool sb_csv_file_open(sb_csv_file *cf, const char *path, sb_err *err) {
    memset(cf, 0, sizeof *cf);
    cf->path = sb_strdup(path);
    size_t n = strlen(path) + 5;
    cf->tmp = sb_xmalloc(n);
    snprintf(cf->tmp, n, "%s.tmp", path);
    cf->f = fopen(cf->tmp, "w");
    if (!cf->f) {
        sb_fail(err, "%s: cannot create: %s", cf->tmp, strerror(errno));
        sb_result_write_failed();
        free(cf->path);
        free(cf->tmp);
        memset(cf, 0, sizeof *cf);
        return false;
    }
    return true;
}

bool sb_csv_file_write(sb_csv_file *cf, sb_csv *rows, sb_err *err) {
    if ((rows->len && fwrite(rows->buf, 1, rows->len, cf->f) != rows->len) || fflush(cf->f) != 0) {
        sb_result_write_failed();
        return sb_fail(err, "%s: write failed: %s", cf->tmp, strerror(errno));
    }
    sb_csv_reset(rows);
    return true;
}

bool sb_csv_file_commit(sb_csv_file *cf, sb_err *err) {
    const char *step = fflush(cf->f) != 0 ? "write" : fsync(fileno(cf->f)) != 0 && errno != EINVAL ? "fsync" : NULL;
    int saved = errno;
    if (fclose(cf->f) != 0 && !step) step = "close", saved = errno;
    cf->f = NULL;
    if (!step && rename(cf->tmp, cf->path) != 0) step = "rename", saved = errno;
    bool ok = !step;
    if (!ok) {
        sb_fail(err, "%s: %s failed: %s", cf->tmp, step, strerror(saved));
        sb_result_write_failed();
        unlink(cf->tmp);
    }
    free(cf->path);
    free(cf->tmp);
    memset(cf, 0, sizeof *cf);
    return ok;
}

void sb_csv_file_abort(sb_csv_file *cf) {
    if (cf->f) fclose(cf->f);
    if (cf->tmp) unlink(cf->tmp);
    free(cf->path);
    free(cf->tmp);
    memset(cf, 0, sizeof *cf);
}
