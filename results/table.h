/* table.h - reading CSV files back (summaries for compare, merge, resume). */
#pragma once
#include <stdbool.h>

#include "util.h"

typedef struct sb_table {
    char **header;
    int cols;
    char ***rows;           /* rows[r][c] */
    char **lines;           /* each row's original text, without the newline */
    int nrows;
} sb_table;

/* Parses RFC 4180 CSV (quotes, doubled quotes, commas and newlines in quotes). */
bool sb_table_parse(sb_table *t, const char *name, const char *text, sb_err *err);
bool sb_table_load(sb_table *t, const char *path, sb_err *err);
void sb_table_free(sb_table *t);
/* Column index by name, or -1. */
int sb_table_col(const sb_table *t, const char *name);
/* Field of row r in the named column ("" if absent). */
const char *sb_table_get(const sb_table *t, int r, const char *name);
