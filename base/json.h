/* json.h - a small JSON reader for checking glTF documents before the glTF
 * library sees them.
 *
 * The glTF library coerces numbers (2^64 - 8 wraps, -12 becomes 0, an index
 * above 2^32 is truncated into a valid one), and reports a syntax error with
 * no position. This reader keeps every number's text, so integers are read
 * exactly (sb_json_u64), and says where a syntax error is (line and column).
 * Values live in one arena freed by sb_json_free; strings are decoded (escapes,
 * \u surrogates to UTF-8) and NUL-terminated. Nesting deeper than
 * SB_JSON_MAX_DEPTH is refused rather than recursed into. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "util.h"

#define SB_JSON_MAX_DEPTH 512

typedef enum sb_json_type {
    SB_JSON_NULL,
    SB_JSON_BOOL,
    SB_JSON_NUMBER,
    SB_JSON_STRING,
    SB_JSON_ARRAY,
    SB_JSON_OBJECT,
} sb_json_type;

typedef struct sb_json sb_json;
struct sb_json {
    sb_json_type type;
    uint32_t count;         /* array/object: children */
    uint32_t line, col;     /* where the value starts (1-based) */
    const char *key;        /* member of an object: its name (decoded); else NULL */
    bool b;                 /* BOOL */
    const char *text;       /* NUMBER: the literal as written; STRING: decoded text */
    double num;             /* NUMBER: as a double */
    sb_json *items;         /* ARRAY/OBJECT: count children, in order */
};

typedef struct sb_json_doc {
    sb_json *root;
    void *arena;            /* private */
} sb_json_doc;

/* Parses text[0..len). On failure fills err with "NAME: JSON syntax error at
 * line L, column C: what was expected" and returns false. */
bool sb_json_parse(sb_json_doc *doc, const char *name, const char *text, size_t len, sb_err *err);
void sb_json_free(sb_json_doc *doc);
/* How many documents this process has parsed (a test holds a glTF load to one). */
uint64_t sb_json_parses(void);

/* Member of an object by name (the first one), or NULL. */
const sb_json *sb_json_get(const sb_json *obj, const char *key);
/* The number as an exact unsigned integer: an integer literal that fits in 64
 * bits, or a literal with a fraction or exponent whose value is a whole number
 * below 2^53. Returns false for negative, fractional or too large values. */
bool sb_json_u64(const sb_json *v, uint64_t *out);
/* Is the number negative (its literal starts with '-' and it is not zero)? */
bool sb_json_negative(const sb_json *v);
const char *sb_json_type_name(sb_json_type t);

/* ---- writing ----
 * The one JSON writer (the report's data files): values into a growable
 * buffer, commas placed by the writer from the nesting it keeps. Strings are
 * escaped, and '<' as \u003c, so the text is safe inside a <script>; a
 * number that is not finite is written null. */
#define SB_JW_MAX_DEPTH 64
typedef struct sb_jw {
    char *buf;              /* NUL-terminated; free with sb_jw_free */
    size_t len, cap;
    int depth;
    bool fresh[SB_JW_MAX_DEPTH];   /* nothing written yet in the container at that depth */
    bool after_key;
} sb_jw;

void sb_jw_free(sb_jw *w);
/* Text as it is (no comma placed): a wrapper around the document. */
void sb_jw_raw(sb_jw *w, const char *text);
void sb_jw_obj(sb_jw *w);
void sb_jw_end_obj(sb_jw *w);
void sb_jw_arr(sb_jw *w);
void sb_jw_end_arr(sb_jw *w);
/* A member's name; its value is what is written next. */
void sb_jw_key(sb_jw *w, const char *key);
void sb_jw_str(sb_jw *w, const char *s);    /* NULL: "" */
void sb_jw_num(sb_jw *w, double v);         /* %.6g */
void sb_jw_num_exact(sb_jw *w, double v);   /* %.17g: reads back as the same double */
void sb_jw_int(sb_jw *w, long long v);      /* every digit: a count, an index, a length */
void sb_jw_bool(sb_jw *w, bool b);
void sb_jw_null(sb_jw *w);
/* "key": value in one call. */
void sb_jw_kstr(sb_jw *w, const char *key, const char *s);
void sb_jw_knum(sb_jw *w, const char *key, double v);
void sb_jw_kint(sb_jw *w, const char *key, long long v);
void sb_jw_kbool(sb_jw *w, const char *key, bool b);
