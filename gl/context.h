/* context.h - headless GL contexts: EGL (device enumeration, GPU first,
 * surfaceless Mesa fallback) and OSMesa. Both render into FBOs. */
#pragma once
#include <stdbool.h>

#include "util.h"

typedef enum sb_backend { SB_BACKEND_EGL, SB_BACKEND_OSMESA } sb_backend;

/* Whether a GL_RENDERER string names a rasterizer that runs on the CPU
 * (llvmpipe, softpipe, swrast, SwiftShader, lavapipe): the one list the
 * context and the history's noise floor share. */
bool sb_renderer_is_software(const char *renderer);

typedef struct sb_context {
    sb_backend backend;
    void *egl_display, *egl_context;
    void *osmesa_context;
    void *osmesa_buffer;
    char vendor[128], renderer[256], version[128];
    char device[256];            /* which EGL device / platform was picked */
    int gl_major, gl_minor;
    bool software;               /* llvmpipe, softpipe, swrast */
    bool has_timer_query, has_compute, has_geometry, has_vs_layer;
    bool has_nvx_meminfo, has_ati_meminfo;
    double memory_limit;         /* --gpu-memory, bytes (0: what the context reports) */
} sb_context;

/* GPU memory a run may allocate, in bytes, and where the figure comes from:
 * --gpu-memory when given; else what the context reports free
 * (GL_NVX_gpu_memory_info, GL_ATI_meminfo); else, on a software rasterizer,
 * the system memory available (its textures live there); else 0, unknown. */
double sb_context_memory_free(const sb_context *c, char *source, size_t len);

/* Reads the pending GL errors away (at most 64: a lost context may report one on every call). */
void sb_gl_drain_errors(void);

const char *sb_backend_name(sb_backend b);
/* Creates a GL 4.3+ core context and loads GL through glad. */
bool sb_context_create(sb_context *c, sb_backend b, sb_err *err);
void sb_context_destroy(sb_context *c);
/* Lists the backends that can create a context here, into buf (", "-separated);
 * `have` (may be NULL): a context already open, whose backend is not tried again. */
void sb_backends_available(const sb_context *have, char *buf, size_t len);
