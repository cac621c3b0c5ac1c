/* context_osmesa.c - the OSMesa backend's calls. Separate from context.c
 * because GL/osmesa.h includes the system GL/gl.h, which glad's header
 * replaces; nothing here calls GL. */
#include <GL/osmesa.h>
#include <stdbool.h>
#include <stdlib.h>

#include "util.h"

bool sb_osmesa_open(void **ctx_out, void **buffer_out);
void *sb_osmesa_proc(const char *name);
void sb_osmesa_close(void *ctx, void *buffer);

bool sb_osmesa_open(void **ctx_out, void **buffer_out) {
    OSMesaContext ctx = NULL;
    for (int minor = 5; minor >= 3 && !ctx; minor--) {
        const int attr[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, minor, 0};
        ctx = OSMesaCreateContextAttribs(attr, NULL);
    }
    if (!ctx) return false;
    /* the default framebuffer is a token 16x16; rendering goes to FBOs */
    void *buffer = sb_xcalloc(16 * 16, 4);
    if (!OSMesaMakeCurrent(ctx, buffer, GL_UNSIGNED_BYTE, 16, 16)) {
        OSMesaDestroyContext(ctx);
        free(buffer);
        return false;
    }
    *ctx_out = ctx;
    *buffer_out = buffer;
    return true;
}

void *sb_osmesa_proc(const char *name) { return (void *)OSMesaGetProcAddress(name); }

void sb_osmesa_close(void *ctx, void *buffer) {
    OSMesaDestroyContext((OSMesaContext)ctx);
    free(buffer);
}
