/* json.c - the JSON reader (see json.h): recursive descent with a depth
 * limit; a container's children are gathered on one scratch stack and moved
 * into the arena when it closes, so each container's items are contiguous. */
#include "json.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- arena: blocks of at least 64 KiB, freed together ---- */

typedef struct block {
    struct block *next;
    size_t used, cap;
    max_align_t data[];
} block;

static void *arena_alloc(void **arena, size_t n) {
    n = (n + sizeof(max_align_t) - 1) / sizeof(max_align_t) * sizeof(max_align_t);
    block *b = *arena;
    if (!b || b->cap - b->used < n) {
        size_t cap = n > 65536 ? n : 65536;
        block *nb = malloc(sizeof *nb + cap);
        if (!nb) return NULL;
        nb->next = b;
        nb->used = 0;
        nb->cap = cap;
        *arena = b = nb;
    }
    void *p = (char *)b->data + b->used;
    b->used += n;
    return p;
}

static void arena_free(void *arena) {
    for (block *b = arena; b;) {
        block *next = b->next;
        free(b);
        b = next;
    }
}

/* ---- parser ---- */

typedef struct parser {
    const char *name, *s;
    size_t len, pos;
    uint32_t line;
    size_t line_start;
    void *arena;
    sb_json *stack;         /* children of the open containers */
    size_t top, cap;
    sb_err *err;
    bool failed;
} parser;

static bool fail_at(parser *p, size_t pos, const char *what) {
    if (!p->failed) {
        size_t line_start = p->line_start <= pos ? p->line_start : pos;
        sb_fail(p->err, "%s: JSON syntax error at line %u, column %zu: %s", p->name, p->line, pos - line_start + 1,
                what);
    }
    p->failed = true;
    return false;
}

static bool oom(parser *p) {
    if (!p->failed) sb_fail(p->err, "%s: out of memory reading the JSON", p->name);
    p->failed = true;
    return false;
}

static void skip_ws(parser *p) {
    while (p->pos < p->len) {
        char c = p->s[p->pos];
        if (c == '\n') {
            p->line++;
            p->line_start = ++p->pos;
        } else if (c == ' ' || c == '\t' || c == '\r') {
            p->pos++;
        } else {
            break;
        }
    }
}

static bool push(parser *p, const sb_json *v) {
    if (p->top == p->cap) {
        size_t cap = p->cap ? p->cap * 2 : 256;
        sb_json *ns = realloc(p->stack, cap * sizeof *ns);
        if (!ns) return oom(p);
        p->stack = ns;
        p->cap = cap;
    }
    p->stack[p->top++] = *v;
    return true;
}

static int hexval(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

static bool read_hex4(parser *p, uint32_t *out) {
    if (p->len - p->pos < 4) return fail_at(p, p->pos, "a \\u escape needs four hex digits");
    uint32_t v = 0;
    for (int i = 0; i < 4; i++) {
        int h = hexval(p->s[p->pos + i]);
        if (h < 0) return fail_at(p, p->pos + i, "a \\u escape needs four hex digits");
        v = v * 16 + (uint32_t)h;
    }
    p->pos += 4;
    *out = v;
    return true;
}

static size_t put_utf8(char *o, uint32_t cp) {
    if (cp < 0x80) {
        o[0] = (char)cp;
        return 1;
    }
    if (cp < 0x800) {
        o[0] = (char)(0xc0 | (cp >> 6));
        o[1] = (char)(0x80 | (cp & 0x3f));
        return 2;
    }
    if (cp < 0x10000) {
        o[0] = (char)(0xe0 | (cp >> 12));
        o[1] = (char)(0x80 | ((cp >> 6) & 0x3f));
        o[2] = (char)(0x80 | (cp & 0x3f));
        return 3;
    }
    o[0] = (char)(0xf0 | (cp >> 18));
    o[1] = (char)(0x80 | ((cp >> 12) & 0x3f));
    o[2] = (char)(0x80 | ((cp >> 6) & 0x3f));
    o[3] = (char)(0x80 | (cp & 0x3f));
    return 4;
}

/* At the opening quote; decodes into the arena. */
static bool parse_string(parser *p, const char **out) {
    size_t start = ++p->pos, end = start;
    while (end < p->len && p->s[end] != '"') {
        if (p->s[end] == '\\') end++;
        end++;
    }
    if (end >= p->len) return fail_at(p, start - 1, "a string is not closed");
    char *o = arena_alloc(&p->arena, end - start + 1); /* decoding never grows the text */
    if (!o) return oom(p);
    size_t n = 0;
    while (p->pos < end) {
        unsigned char c = (unsigned char)p->s[p->pos];
        if (c < 0x20) return fail_at(p, p->pos, "a control character inside a string (escape it)");
        if (c != '\\') {
            o[n++] = (char)c;
            p->pos++;
            continue;
        }
        char e = p->s[++p->pos];
        p->pos++;
        switch (e) {
        case '"': o[n++] = '"'; break;
        case '\\': o[n++] = '\\'; break;
        case '/': o[n++] = '/'; break;
        case 'b': o[n++] = '\b'; break;
        case 'f': o[n++] = '\f'; break;
        case 'n': o[n++] = '\n'; break;
        case 'r': o[n++] = '\r'; break;
        case 't': o[n++] = '\t'; break;
        case 'u': {
            uint32_t cp;
            if (!read_hex4(p, &cp)) return false;
            if (cp >= 0xd800 && cp < 0xdc00) { /* a high surrogate needs its low half */
                uint32_t lo;
                if (p->pos + 2 > end || p->s[p->pos] != '\\' || p->s[p->pos + 1] != 'u')
                    return fail_at(p, p->pos, "a \\u high surrogate without its low surrogate");
                p->pos += 2;
                if (!read_hex4(p, &lo)) return false;
                if (lo < 0xdc00 || lo >= 0xe000) return fail_at(p, p->pos - 4, "an invalid \\u low surrogate");
                cp = 0x10000 + ((cp - 0xd800) << 10) + (lo - 0xdc00);
            } else if (cp >= 0xdc00 && cp < 0xe000) {
                return fail_at(p, p->pos - 4, "a \\u low surrogate without its high surrogate");
            }
            n += put_utf8(o + n, cp);
            break;
        }
        default: return fail_at(p, p->pos - 1, "an unknown escape in a string");
        }
    }
    o[n] = 0;
    p->pos = end + 1;
    *out = o;
    return true;
}

static bool is_digit(char c) { return c >= '0' && c <= '9'; }

static bool parse_number(parser *p, sb_json *v) {
    size_t start = p->pos, i = p->pos;
    if (i < p->len && p->s[i] == '-') i++;
    if (i >= p->len || !is_digit(p->s[i])) return fail_at(p, start, "expected a value");
    if (p->s[i] == '0') i++;
    else
        while (i < p->len && is_digit(p->s[i])) i++;
    if (i < p->len && p->s[i] == '.') {
        i++;
        if (i >= p->len || !is_digit(p->s[i])) return fail_at(p, i, "expected a digit after the decimal point");
        while (i < p->len && is_digit(p->s[i])) i++;
    }
    if (i < p->len && (p->s[i] == 'e' || p->s[i] == 'E')) {
        i++;
        if (i < p->len && (p->s[i] == '+' || p->s[i] == '-')) i++;
        if (i >= p->len || !is_digit(p->s[i])) return fail_at(p, i, "expected a digit in the exponent");
        while (i < p->len && is_digit(p->s[i])) i++;
    }
    char *t = arena_alloc(&p->arena, i - start + 1);
    if (!t) return oom(p);
    memcpy(t, p->s + start, i - start);
    t[i - start] = 0;
    v->type = SB_JSON_NUMBER;
    v->text = t;
    v->num = strtod(t, NULL);
    p->pos = i;
    return true;
}

static bool literal(parser *p, const char *word) {
    size_t n = strlen(word);
    if (p->len - p->pos < n || memcmp(p->s + p->pos, word, n) != 0) return fail_at(p, p->pos, "expected a value");
    p->pos += n;
    return true;
}

static bool parse_value(parser *p, sb_json *v, int depth);

/* Moves the children gathered since `first` into the arena. */
static bool close_container(parser *p, sb_json *v, size_t first) {
    size_t n = p->top - first;
    if (n > UINT32_MAX) return fail_at(p, p->pos, "a container with more than 2^32 items");
    v->count = (uint32_t)n;
    v->items = NULL;
    if (n) {
        v->items = arena_alloc(&p->arena, n * sizeof(sb_json));
        if (!v->items) return oom(p);
        memcpy(v->items, p->stack + first, n * sizeof(sb_json));
    }
    p->top = first;
    return true;
}

static bool parse_container(parser *p, sb_json *v, int depth) {
    bool object = p->s[p->pos] == '{';
    char close = object ? '}' : ']';
    v->type = object ? SB_JSON_OBJECT : SB_JSON_ARRAY;
    if (depth >= SB_JSON_MAX_DEPTH) return fail_at(p, p->pos, "nesting deeper than 512 levels");
    p->pos++;
    size_t first = p->top;
    skip_ws(p);
    if (p->pos < p->len && p->s[p->pos] == close) {
        p->pos++;
        return close_container(p, v, first);
    }
    for (;;) {
        skip_ws(p);
        const char *key = NULL;
        if (object) {
            if (p->pos >= p->len || p->s[p->pos] != '"') return fail_at(p, p->pos, "expected a member name in quotes");
            if (!parse_string(p, &key)) return false;
            skip_ws(p);
            if (p->pos >= p->len || p->s[p->pos] != ':') return fail_at(p, p->pos, "expected ':' after a member name");
            p->pos++;
            skip_ws(p);
        }
        sb_json child;
        if (!parse_value(p, &child, depth + 1)) return false;
        child.key = key;
        if (!push(p, &child)) return false;
        skip_ws(p);
        if (p->pos < p->len && p->s[p->pos] == ',') {
            p->pos++;
            continue;
        }
        if (p->pos < p->len && p->s[p->pos] == close) {
            p->pos++;
            return close_container(p, v, first);
        }
        return fail_at(p, p->pos, object ? "expected ',' or '}'" : "expected ',' or ']'");
    }
}

static bool parse_value(parser *p, sb_json *v, int depth) {
    memset(v, 0, sizeof *v);
    skip_ws(p);
    v->line = p->line;
    v->col = (uint32_t)(p->pos - p->line_start + 1);
    if (p->pos >= p->len) return fail_at(p, p->pos, "expected a value, found the end of the text");
    char c = p->s[p->pos];
    switch (c) {
    case '{':
    case '[': return parse_container(p, v, depth);
    case '"': v->type = SB_JSON_STRING; return parse_string(p, &v->text);
    case 't': v->type = SB_JSON_BOOL; v->b = true; return literal(p, "true");
    case 'f': v->type = SB_JSON_BOOL; return literal(p, "false");
    case 'n': v->type = SB_JSON_NULL; return literal(p, "null");
    default: return parse_number(p, v);
    }
}

static uint64_t g_parses;
uint64_t sb_json_parses(void) { return g_parses; }

bool sb_json_parse(sb_json_doc *doc, const char *name, const char *text, size_t len, sb_err *err) {
    g_parses++;
    memset(doc, 0, sizeof *doc);
    parser p = {.name = name, .s = text, .len = len, .line = 1, .err = err};
    if (len >= 3 && !memcmp(text, "\xef\xbb\xbf", 3)) p.pos = p.line_start = 3; /* a UTF-8 byte order mark */
    sb_json root;
    bool ok = parse_value(&p, &root, 0);
    if (ok) {
        skip_ws(&p);
        if (p.pos < p.len) ok = fail_at(&p, p.pos, "text after the end of the JSON value");
    }
    if (ok) {
        doc->root = arena_alloc(&p.arena, sizeof root);
        if (doc->root) *doc->root = root;
        else ok = oom(&p);
    }
    free(p.stack);
    if (!ok) {
        arena_free(p.arena);
        doc->root = NULL;
        return false;
    }
    doc->arena = p.arena;
    return true;
}

void sb_json_free(sb_json_doc *doc) {
    arena_free(doc->arena);
    memset(doc, 0, sizeof *doc);
}

const sb_json *sb_json_get(const sb_json *obj, const char *key) {
    if (!obj || obj->type != SB_JSON_OBJECT) return NULL;
    for (uint32_t i = 0; i < obj->count; i++)
        if (!strcmp(obj->items[i].key, key)) return &obj->items[i];
    return NULL;
}

bool sb_json_negative(const sb_json *v) {
    return v && v->type == SB_JSON_NUMBER && v->text[0] == '-' && v->num != 0;
}

bool sb_json_u64(const sb_json *v, uint64_t *out) {
    if (!v || v->type != SB_JSON_NUMBER) return false;
    const char *t = v->text;
    if (t[0] == '-') {
        if (v->num != 0) return false;
        *out = 0;   /* -0 */
        return true;
    }
    if (!strpbrk(t, ".eE")) { /* an integer literal: exact, with overflow detection */
        uint64_t x = 0;
        for (; *t; t++) {
            uint64_t d = (uint64_t)(*t - '0');
            if (x > (UINT64_MAX - d) / 10) return false;
            x = x * 10 + d;
        }
        *out = x;
        return true;
    }
    double d = v->num; /* 3.0, 1e3: whole numbers a double holds exactly */
    if (!(d >= 0) || d > 9007199254740992.0 || d != floor(d)) return false;
    *out = (uint64_t)d;
    return true;
}

const char *sb_json_type_name(sb_json_type t) {
    static const char *const names[] = {"null", "a boolean", "a number", "a string", "an array", "an object"};
    return (unsigned)t < SB_COUNT(names) ? names[t] : "?";
}

/* ---- writing ---- */

void sb_jw_free(sb_jw *w) {
    free(w->buf);
    memset(w, 0, sizeof *w);
}

static void jw_put(sb_jw *w, const char *s, size_t n) {
    if (w->len + n + 1 > w->cap) {
        w->cap = (w->len + n + 1) * 2;
        w->buf = sb_xrealloc(w->buf, w->cap);
    }
    memcpy(w->buf + w->len, s, n);
    w->len += n;
    w->buf[w->len] = 0;
}

void sb_jw_raw(sb_jw *w, const char *text) { jw_put(w, text, strlen(text)); }

/* Before a value or a key: the comma its container needs. */
static void jw_sep(sb_jw *w) {
    if (w->after_key) {
        w->after_key = false;
        return;
    }
    int d = (w->depth > SB_JW_MAX_DEPTH ? SB_JW_MAX_DEPTH : w->depth) - 1;
    if (d < 0) return;
    if (!w->fresh[d]) jw_put(w, ",", 1);
    w->fresh[d] = false;
}

static void jw_open(sb_jw *w, char c) {
    jw_sep(w);
    jw_put(w, &c, 1);
    if (w->depth < SB_JW_MAX_DEPTH) w->fresh[w->depth] = true;   /* deeper: commas as in the deepest */
    w->depth++;
}

static void jw_close(sb_jw *w, char c) {
    if (w->depth > 0) w->depth--;
    jw_put(w, &c, 1);
}

void sb_jw_obj(sb_jw *w) { jw_open(w, '{'); }
void sb_jw_end_obj(sb_jw *w) { jw_close(w, '}'); }
void sb_jw_arr(sb_jw *w) { jw_open(w, '['); }
void sb_jw_end_arr(sb_jw *w) { jw_close(w, ']'); }

/* The bytes of one well-formed UTF-8 character at p (1 to 4), or 0 where they are none (a stray continuation, a
 * cut or overlong sequence, a surrogate, past U+10FFFF). */
static int utf8_char(const unsigned char *p) {
    if (p[0] < 0x80) return 1;
    int n = p[0] >= 0xf0 && p[0] <= 0xf4 ? 4 : p[0] >= 0xe0 ? 3 : p[0] >= 0xc2 && p[0] < 0xe0 ? 2 : 0;
    if (!n || (p[0] >= 0xf0 && n != 4)) return 0;
    unsigned cp = p[0] & (0x7f >> n);
    for (int i = 1; i < n; i++) {
        if ((p[i] & 0xc0) != 0x80) return 0;
        cp = cp << 6 | (p[i] & 0x3f);
    }
    static const unsigned least[5] = {0, 0, 0x80, 0x800, 0x10000};
    return cp < least[n] || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff) ? 0 : n;
}

static void jw_string(sb_jw *w, const char *s) {
    jw_put(w, "\"", 1);
    for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; p++) {
        char e[8];
        if (*p >= 0x80) {   /* JSON is UTF-8: a byte that is no character of it is written as U+FFFD */
            int n = utf8_char(p);
            if (n) jw_put(w, (const char *)p, (size_t)n), p += n - 1;
            else jw_put(w, "\\ufffd", 6);
            continue;
        }
        if (*p == '"' || *p == '\\') e[0] = '\\', e[1] = (char)*p, e[2] = 0;
        else if (*p == '\n') strcpy(e, "\\n");
        else if (*p == '<') strcpy(e, "\\u003c");   /* never "</script>" inside a script */
        else if (*p < 0x20) snprintf(e, sizeof e, "\\u%04x", *p);
        else e[0] = (char)*p, e[1] = 0;
        jw_put(w, e, strlen(e));
    }
    jw_put(w, "\"", 1);
}

void sb_jw_key(sb_jw *w, const char *key) {
    jw_sep(w);
    jw_string(w, key);
    jw_put(w, ":", 1);
    w->after_key = true;
}

void sb_jw_str(sb_jw *w, const char *s) {
    jw_sep(w);
    jw_string(w, s);
}

static void jw_number(sb_jw *w, double v, int digits) {
    char b[40];
    if (!isfinite(v)) snprintf(b, sizeof b, "null");
    else snprintf(b, sizeof b, "%.*g", digits, v);
    jw_sep(w);
    jw_put(w, b, strlen(b));
}

void sb_jw_num(sb_jw *w, double v) { jw_number(w, v, 6); }
void sb_jw_num_exact(sb_jw *w, double v) { jw_number(w, v, 17); }
void sb_jw_int(sb_jw *w, long long v) {
    char buf[32];
    snprintf(buf, sizeof buf, "%lld", v);
    jw_sep(w);
    sb_jw_raw(w, buf);
}
void sb_jw_kint(sb_jw *w, const char *key, long long v) { sb_jw_key(w, key), sb_jw_int(w, v); }

void sb_jw_bool(sb_jw *w, bool b) {
    jw_sep(w);
    sb_jw_raw(w, b ? "true" : "false");
}

void sb_jw_null(sb_jw *w) {
    jw_sep(w);
    sb_jw_raw(w, "null");
}

void sb_jw_kstr(sb_jw *w, const char *key, const char *s) { sb_jw_key(w, key), sb_jw_str(w, s); }
void sb_jw_knum(sb_jw *w, const char *key, double v) { sb_jw_key(w, key), sb_jw_num(w, v); }
void sb_jw_kbool(sb_jw *w, const char *key, bool b) { sb_jw_key(w, key), sb_jw_bool(w, b); }
