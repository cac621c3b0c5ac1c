/* blob.h - a growing byte buffer to write records into, and a bounded reader
 * over bytes (a mapped file): every read is checked against the end, and a
 * short or inconsistent input turns the reader's `ok` false instead of
 * reading past it. Arrays are placed on 16-byte boundaries of the file, so a
 * mapped file can be used in place. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define SB_BLOB_ALIGN 16

typedef struct sb_wbuf {
    unsigned char *p;
    size_t n, cap;
} sb_wbuf;

void sb_wbuf_put(sb_wbuf *b, const void *data, size_t n);
void sb_wbuf_put_u32(sb_wbuf *b, uint32_t v);
/* Pads to SB_BLOB_ALIGN, then the n bytes. */
void sb_wbuf_put_array(sb_wbuf *b, const void *data, size_t n);
void sb_wbuf_free(sb_wbuf *b);
/* n bytes as base64 (RFC 4648, padded) into out, which holds 4 * ((n + 2) / 3) + 1 chars; NUL-terminated. */
void sb_base64(const unsigned char *in, size_t n, char *out);

typedef struct sb_rbuf {
    const unsigned char *p;
    size_t n, at;
    bool ok;
    size_t base;            /* offset of p in the file, for alignment */
} sb_rbuf;

/* The next n bytes, or NULL (and ok false) past the end. */
const void *sb_rbuf_take(sb_rbuf *r, size_t n);
uint32_t sb_rbuf_take_u32(sb_rbuf *r);
/* n elements of size sz where they lie (after the alignment padding): NULL
 * when n is 0 or the input is short (then ok is false). */
void *sb_rbuf_take_array(sb_rbuf *r, uint64_t n, size_t sz);
