/* timing.c - the query ring and sync timing. */
#include "timing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gl.h"

const char *sb_timing_name(sb_timing_mode m) {
    return m == SB_TIMING_QUERIES ? "queries" : m == SB_TIMING_SYNC ? "sync" : "auto";
}

void sb_ring_init(sb_ring *r, int size) {
    r->size = size < 1 ? 1 : size;
    r->slot_frame = sb_xmalloc((size_t)r->size * sizeof(int));
    for (int i = 0; i < r->size; i++) r->slot_frame[i] = -1;
}

void sb_ring_free(sb_ring *r) {
    free(r->slot_frame);
    r->slot_frame = NULL;
}

int sb_ring_claim(sb_ring *r, int frame, int *slot) {
    int s = frame % r->size;
    int prev = r->slot_frame[s];
    r->slot_frame[s] = frame;
    *slot = s;
    return prev;
}

int sb_ring_slot_of(const sb_ring *r, int frame) {
    int s = frame % r->size;
    return r->slot_frame[s] == frame ? s : -1;
}

void sb_timer_init(sb_timer *t, sb_timing_mode mode, int ring, int frames) {
    memset(t, 0, sizeof *t);
    t->mode = mode;
    t->frames = frames;
    t->current = -1;
    t->times = sb_xcalloc((size_t)frames, sizeof *t->times);
    for (int i = 0; i < frames; i++) t->times[i].gpu_idle_ms = NAN;
    sb_ring_init(&t->ring, ring);
    if (mode == SB_TIMING_QUERIES) {
        size_t n = (size_t)t->ring.size * SB_TIMER_QUERIES;
        t->queries = sb_xcalloc(n, sizeof(unsigned));
        glGenQueries((GLsizei)n, t->queries);
        t->slot_mask = sb_xcalloc((size_t)t->ring.size, sizeof(unsigned));
        t->fences = sb_xcalloc((size_t)t->ring.size, sizeof(void *));
    }
}

void sb_timer_free(sb_timer *t) {
    if (t->queries) glDeleteQueries(t->ring.size * SB_TIMER_QUERIES, t->queries);
    for (int i = 0; t->fences && i < t->ring.size; i++)
        if (t->fences[i]) glDeleteSync((GLsync)t->fences[i]);
    free(t->queries);
    free(t->slot_mask);
    free(t->fences);
    free(t->times);
    sb_ring_free(&t->ring);
    memset(t, 0, sizeof *t);
}

static unsigned *slot_queries(sb_timer *t, int slot) { return t->queries + (size_t)slot * SB_TIMER_QUERIES; }
enum { FRAME_BEGIN = SB_TIMER_STAGES * 2, FRAME_END };
#define ENDED (1u << 31) /* slot_mask: the frame's end timestamp was written */

/* Waits for the slot's fence (the GPU has finished that frame); the time is the CPU's wait. */
static void wait_fence(sb_timer *t, int slot) {
    if (!t->fences[slot]) return;
    double w0 = sb_now_ms();
    while (glClientWaitSync((GLsync)t->fences[slot], GL_SYNC_FLUSH_COMMANDS_BIT, 1000000000ull) == GL_TIMEOUT_EXPIRED) {}
    t->wait_ms += sb_now_ms() - w0;
    glDeleteSync((GLsync)t->fences[slot]);
    t->fences[slot] = NULL;
}

/* Reads one slot's results into its frame's record (its fence has signalled). */
static void collect(sb_timer *t, int frame, int slot) {
    unsigned mask = t->slot_mask[slot];
    unsigned *q = slot_queries(t, slot);
    sb_stage_times *out = frame >= 0 && frame < t->frames ? &t->times[frame] : NULL;
    double covered = 0;
    for (int s = 0; s < SB_TIMER_STAGES; s++) {
        if (!(mask & (1u << s))) continue;
        GLuint64 a = 0, b = 0;
        glGetQueryObjectui64v(q[2 * s], GL_QUERY_RESULT, &a);
        glGetQueryObjectui64v(q[2 * s + 1], GL_QUERY_RESULT, &b);
        covered += (double)(b - a) * 1e-6;
        if (out) {
            out->ms[s] = (double)(b - a) * 1e-6;
            out->mask |= (1u << s);
        }
    }
    if (mask & ENDED) {
        GLuint64 fb = 0, fe = 0;
        glGetQueryObjectui64v(q[FRAME_BEGIN], GL_QUERY_RESULT, &fb);
        glGetQueryObjectui64v(q[FRAME_END], GL_QUERY_RESULT, &fe);
        if (out) out->gpu_idle_ms = fmax((double)(fe - fb) * 1e-6 - covered, 0);
    }
    if (out) out->ready = true;
    t->slot_mask[slot] = 0;
}

void sb_timer_frame_begin(sb_timer *t, int frame) {
    t->current = frame;
    t->wait_ms = 0;
    if (t->mode == SB_TIMING_QUERIES) {
        int slot;
        int prev = sb_ring_claim(&t->ring, frame, &slot);
        wait_fence(t, slot);
        if (prev >= 0) collect(t, prev, slot);
        t->slot_mask[slot] = 0;
        glQueryCounter(slot_queries(t, slot)[FRAME_BEGIN], GL_TIMESTAMP);
    } else {
        double w0 = sb_now_ms();
        glFinish();
        t->wait_ms += sb_now_ms() - w0;
    }
}

void sb_timer_frame_end(sb_timer *t) {
    if (t->mode == SB_TIMING_QUERIES) {
        int slot = sb_ring_slot_of(&t->ring, t->current);
        glQueryCounter(slot_queries(t, slot)[FRAME_END], GL_TIMESTAMP);
        t->slot_mask[slot] |= ENDED;
        t->fences[slot] = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        glFlush();
    }
    if (t->current >= 0 && t->current < t->frames) t->times[t->current].cpu_wait_ms = t->wait_ms;
}

void sb_timer_stage_begin(sb_timer *t, int s) {
    if (t->mode == SB_TIMING_QUERIES) {
        int slot = sb_ring_slot_of(&t->ring, t->current);
        glQueryCounter(slot_queries(t, slot)[2 * s], GL_TIMESTAMP);
    } else {
        t->t0[s] = sb_now_ms();
    }
}

void sb_timer_stage_end(sb_timer *t, int s) {
    if (t->mode == SB_TIMING_QUERIES) {
        int slot = sb_ring_slot_of(&t->ring, t->current);
        glQueryCounter(slot_queries(t, slot)[2 * s + 1], GL_TIMESTAMP);
        t->slot_mask[slot] |= (1u << s);
    } else {
        double w0 = sb_now_ms();
        glFinish();
        double now = sb_now_ms();
        t->wait_ms += now - w0;
        sb_stage_times *out = &t->times[t->current];
        out->ms[s] += now - t->t0[s];
        out->mask |= (1u << s);
        out->ready = true;
    }
}

void sb_timer_drain(sb_timer *t) {
    if (t->mode != SB_TIMING_QUERIES) return;
    for (int slot = 0; slot < t->ring.size; slot++) {
        int f = t->ring.slot_frame[slot];
        wait_fence(t, slot);
        if (f >= 0) collect(t, f, slot);
        t->ring.slot_frame[slot] = -1;
    }
}
