/* run_opts.h - the run options: what every rendering command (run, batch,
 * tune, stress) and the scene readers (info, path) are given. Each field is
 * set by a row of the option table (options.h), which also holds its default
 * and whether it is part of a run's identity. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "clocks.h"
#include "context.h"
#include "scene.h"
#include "timing.h"

/* The order of a scene's runs and their repetitions (--order). */
typedef enum sb_order {
    SB_ORDER_MATRIX,            /* each run's repetitions together, runs in matrix order */
    SB_ORDER_INTERLEAVE,        /* rounds: A1 B1 C1, A2 B2 C2, ... */
    SB_ORDER_SHUFFLE,           /* rounds, each in a random order (seeded) */
} sb_order;
const char *sb_order_name(sb_order o);

/* How a pass's draws reach the GL (--submit). */
typedef enum sb_submit_mode {
    SB_SUBMIT_DIRECT,           /* one glDrawElements* per draw */
    SB_SUBMIT_INDIRECT,         /* one glMultiDrawElementsIndirect per pass, layer and state */
} sb_submit_mode;
const char *sb_submit_name(sb_submit_mode m);

typedef struct sb_run_opts {
    sb_backend backend;         /* default egl */
    sb_timing_mode timing;      /* default auto */
    sb_submit_mode submit;      /* --submit direct|indirect (default direct) */
    int ring;                   /* query ring frames, default 3 */
    int frames;                 /* default 60 */
    int warmup;                 /* warm-up frames; -1 (the default): auto, until the GPU is warm */
    int width, height;          /* default 1280x720 */
    bool sun_override;
    double sun_az, sun_el;      /* degrees */
    bool progress;              /* progress line on stderr */
    int images;                 /* write images of every K-th frame (0: none), untimed pass */
    int error_every;            /* evaluate the error of every K-th frame (0: off), untimed pass; default 10 */
    double sun_size;            /* --sun-size: the sun's angular diameter in degrees (0: no size, the hard reference) */
    double lamp_radius;         /* --lamp-radius: point and spot lights' radius (0: none) */
    const char *lights;         /* --lights sun|lamps|all|LIST (NULL: the one light the technique shadows) */
    int ref_samples;            /* --ref-samples: rays over a sized light at a penumbra point (default 64) */
    double flicker_dt;          /* path seconds from an evaluated frame to its flicker twin (0: none); default 1/60 */
    int repeat;                 /* repetitions of the path (default 1) */
    double target_ci;           /* percent: repeat until the gpu_ms CI half-width is within it (0: off) */
    int max_repeat;             /* cap for target_ci (default 10) */
    int threads;                /* reference ray-casting threads (default: all cores, at most 1024) */
    int overlap;                /* --overlap: 1 on, 0 off, -1 auto (the default: on for a GPU, off for a CPU rasterizer) */
    double run_timeout_s;       /* a run taking longer fails with a timeout (0: none) */
    double gpu_memory;          /* --gpu-memory: bytes a run may allocate on the GPU (0: what the context says) */
    bool allow_external_uris;   /* glTF buffers and images may be read from outside the scene's folder */
    bool strict_path;           /* --strict-path: a path whose cameras the check flags is refused (pathcheck.h) */
    bool flip;                  /* --flip: evaluated frames' shaded colour scored with LDR-FLIP (eval.c) */
    int taa;                    /* --taa on|off (1, 0): evaluated frames resolved through TAA too (taa.h) */
    sb_blend_policy blend;      /* --blend-casters mask|opaque|none (default mask) */
    bool pose;                  /* --pose T: the scene at time T of its first animation */
    double pose_time;
    const char *anim;           /* --anim all|none|NAME[,NAME] (NULL: all) */
    double anim_speed;          /* --anim-speed: clip seconds a second of the path's clock (default 1) */
    sb_clocks_mode clocks;      /* --clocks auto|lock|free (default auto) */
    sb_order order;             /* --order matrix|interleave|shuffle (default matrix) */
    uint64_t seed;              /* --seed: shuffle's seed; 0: chosen by sb_run_opts_finish */
    int rerun_unstable;         /* --rerun-unstable N: runs flagged unstable run again at the end, up to N times */
} sb_run_opts;

/* How the options read a scene file. */
sb_scene_opts sb_run_scene_opts(const sb_run_opts *o);
/* After every option is set: picks shuffle's seed when none was given. */
void sb_run_opts_finish(sb_run_opts *o);
