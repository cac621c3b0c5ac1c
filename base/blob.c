/* blob.c - write buffer and bounded reader (blob.h). */
#include "blob.h"

#include <stdlib.h>
#include <string.h>

#include "util.h"

void sb_wbuf_put(sb_wbuf *b, const void *data, size_t n) {
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2;
        b->p = sb_xrealloc(b->p, b->cap);
    }
    if (n) memcpy(b->p + b->n, data, n);
    b->n += n;
}

void sb_wbuf_put_u32(sb_wbuf *b, uint32_t v) { sb_wbuf_put(b, &v, sizeof v); }

void sb_wbuf_put_array(sb_wbuf *b, const void *data, size_t n) {
    static const unsigned char zero[SB_BLOB_ALIGN] = {0};
    sb_wbuf_put(b, zero, (SB_BLOB_ALIGN - b->n % SB_BLOB_ALIGN) % SB_BLOB_ALIGN);
    sb_wbuf_put(b, data, n);
}

void sb_wbuf_free(sb_wbuf *b) {
    free(b->p);
    memset(b, 0, sizeof *b);
}

const void *sb_rbuf_take(sb_rbuf *r, size_t n) {
    if (!r->ok || n > r->n - r->at) {
        r->ok = false;
        return NULL;
    }
    const void *q = r->p + r->at;
    r->at += n;
    return q;
}

uint32_t sb_rbuf_take_u32(sb_rbuf *r) {
    const void *q = sb_rbuf_take(r, 4);
    uint32_t v = 0;
    if (q) memcpy(&v, q, 4);
    return v;
}

void *sb_rbuf_take_array(sb_rbuf *r, uint64_t n, size_t sz) {
    size_t pad = (SB_BLOB_ALIGN - (r->base + r->at) % SB_BLOB_ALIGN) % SB_BLOB_ALIGN;
    if (!sb_rbuf_take(r, pad)) return NULL;
    if (n > (r->n - r->at) / (sz ? sz : 1)) {
        r->ok = false;
        return NULL;
    }
    const void *q = sb_rbuf_take(r, (size_t)n * sz);
    return n ? (void *)q : NULL;
}

void sb_base64(const unsigned char *in, size_t n, char *out) {
    static const char tbl[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t o = 0;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) | (i + 2 < n ? in[i + 2] : 0);
        out[o++] = tbl[v >> 18 & 63];
        out[o++] = tbl[v >> 12 & 63];
        out[o++] = i + 1 < n ? tbl[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? tbl[v & 63] : '=';
    }
    out[o] = 0;
}
