/* timing.h - per-stage GPU timing.
 *
 * queries: glQueryCounter(GL_TIMESTAMP) at each frame's start and end and at
 *   stage boundaries, query objects in a ring of `ring` frames, and a fence
 *   (glFenceSync) at the end of every frame. Before frame f the CPU waits for
 *   frame f-ring's fence: that throttles a CPU running ahead of the GPU (the
 *   time is the frame's cpu_wait_ms), and the queries of f-ring are then
 *   complete, so reading them never blocks. The frame's gpu_idle_ms is the
 *   part of its GPU span (start to end timestamp) no stage covers: bubbles
 *   where the GPU waited for the CPU.
 * sync: glFinish + CLOCK_MONOTONIC at stage boundaries. The only honest mode on
 *   software rasterizers, whose timestamps do not cover rasterization.
 * auto: sync on llvmpipe/softpipe/swrast, queries elsewhere. */
#pragma once
#include <stdbool.h>
#include <stdint.h>


/* The stages a frame can time: numbered slots of the ring (the techniques declare and name them: techniques/stage.h;
 * eight are declared, the rest is room for a technique's own). */
#define SB_TIMER_STAGES 12

typedef enum sb_timing_mode { SB_TIMING_AUTO, SB_TIMING_QUERIES, SB_TIMING_SYNC } sb_timing_mode;

const char *sb_timing_name(sb_timing_mode m);

/* The ring bookkeeping, separate from GL so it can be tested on its own. */
typedef struct sb_ring {
    int size;
    int *slot_frame;    /* frame whose queries live in the slot, -1 if none */
} sb_ring;

void sb_ring_init(sb_ring *r, int size);
void sb_ring_free(sb_ring *r);
/* Claims the slot for `frame`; returns the frame previously held there that
 * must be collected first (or -1). */
int sb_ring_claim(sb_ring *r, int frame, int *slot);
/* Slot holding `frame`, or -1. */
int sb_ring_slot_of(const sb_ring *r, int frame);

typedef struct sb_stage_times {
    double ms[SB_TIMER_STAGES];
    unsigned mask;      /* stages measured (bit s: slot s) */
    bool ready;
    double cpu_wait_ms; /* CPU time blocked on the GPU before and in this frame */
    double gpu_idle_ms; /* queries: GPU span of the frame not covered by a stage (NaN in sync mode) */
} sb_stage_times;

typedef struct sb_timer {
    sb_timing_mode mode;        /* resolved: QUERIES or SYNC */
    sb_ring ring;
    unsigned *queries;          /* ring.size * SB_TIMER_QUERIES */
    unsigned *slot_mask;
    void **fences;              /* per slot: the GLsync after its frame */
    sb_stage_times *times;      /* per frame, `frames` long */
    int frames;
    int current;
    double t0[SB_TIMER_STAGES];
    double wait_ms;             /* time this frame spent blocked on the GPU */
} sb_timer;

/* Queries a frame's slot holds: a begin and end a stage, then the frame's own begin and end. */
#define SB_TIMER_QUERIES (SB_TIMER_STAGES * 2 + 2)

void sb_timer_init(sb_timer *t, sb_timing_mode resolved, int ring, int frames);
void sb_timer_free(sb_timer *t);
/* Starts frame `frame`: in queries mode, waits for the fence of the frame the
 * ring slot held and collects its results; in sync mode, glFinish. */
void sb_timer_frame_begin(sb_timer *t, int frame);
/* Ends the current frame: its end timestamp and fence (queries mode). */
void sb_timer_frame_end(sb_timer *t);
void sb_timer_stage_begin(sb_timer *t, int stage);
void sb_timer_stage_end(sb_timer *t, int stage);
/* Collects every outstanding frame (end of a pass of the path: waits for each). */
void sb_timer_drain(sb_timer *t);
