/* csv.h - RFC 4180 CSV rows into a growable buffer, and a per-run CSV file
 * written under a temporary name and renamed only when complete. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "util.h"

typedef struct sb_csv {
    char *buf;
    size_t len, cap;
    int fields;             /* fields in the current row */
} sb_csv;

void sb_csv_str(sb_csv *c, const char *s);          /* quoted when needed */
void sb_csv_num(sb_csv *c, double v);               /* NaN -> empty field */
void sb_csv_int(sb_csv *c, long long v);
void sb_csv_empty(sb_csv *c);
void sb_csv_end_row(sb_csv *c);
void sb_csv_line(sb_csv *c, const char *row);       /* appends an already formatted row */
void sb_csv_reset(sb_csv *c);
void sb_csv_free(sb_csv *c);

/* A CSV file being written: rows go to PATH.tmp as they complete; commit
 * renames it to PATH, abort removes it. */
typedef struct sb_csv_file {
    FILE *f;
    char *path, *tmp;
} sb_csv_file;

bool sb_csv_file_open(sb_csv_file *cf, const char *path, sb_err *err);
bool sb_csv_file_write(sb_csv_file *cf, sb_csv *rows, sb_err *err);   /* writes and clears rows */
bool sb_csv_file_commit(sb_csv_file *cf, sb_err *err);
void sb_csv_file_abort(sb_csv_file *cf);
