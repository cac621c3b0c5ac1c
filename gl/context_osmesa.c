/* context_osmesa.c - the OSMesa backend's calls. Separate from context.c
 * because GL/osmesa.h includes the system GL/gl.h, which glad's header
 * replaces; nothing here calls GL.
 *
 * libOSMesa is opened at run time, on first use: a binary that never asks for
 * the osmesa backend never loads it (nor the LLVM it pulls in), and one built
 * without it (meson -Dosmesa=disabled, no header) says so. */
#include "context_osmesa.h"

#include <stdio.h>
#include <stdlib.h>

#include "util.h"

#if SB_HAVE_OSMESA
#include <GL/osmesa.h>
#include <dlfcn.h>

static struct {
    void *lib;
    OSMesaContext (*create)(const int *attribs, OSMesaContext share);
    GLboolean (*make_current)(OSMesaContext ctx, void *buffer, GLenum type, GLsizei w, GLsizei h);
    OSMESAproc (*proc)(const char *name);
    void (*destroy)(OSMesaContext ctx);
} g;

static bool load(char *why, size_t len) {
    if (g.lib) return true;
    const char *names[] = {"libOSMesa.so.8", "libOSMesa.so"};
    for (size_t i = 0; i < SB_COUNT(names) && !g.lib; i++) g.lib = dlopen(names[i], RTLD_NOW | RTLD_LOCAL);
    if (!g.lib) return snprintf(why, len, "osmesa: cannot load libOSMesa.so.8 (%s)", dlerror()), false;
    *(void **)&g.create = dlsym(g.lib, "OSMesaCreateContextAttribs");
    *(void **)&g.make_current = dlsym(g.lib, "OSMesaMakeCurrent");
    *(void **)&g.proc = dlsym(g.lib, "OSMesaGetProcAddress");
    *(void **)&g.destroy = dlsym(g.lib, "OSMesaDestroyContext");
    if (g.create && g.make_current && g.proc && g.destroy) return true;
    snprintf(why, len, "osmesa: libOSMesa lacks OSMesaCreateContextAttribs (Mesa 11.2 or newer needed)");
    dlclose(g.lib);
    g.lib = NULL;
    return false;
}

bool sb_osmesa_open(void **ctx_out, void **buffer_out, char *why, size_t len) {
    if (!load(why, len)) return false;
    OSMesaContext ctx = NULL;
    for (int minor = 5; minor >= 3 && !ctx; minor--) {
        const int attr[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, minor, 0};
        ctx = g.create(attr, NULL);
    }
    if (!ctx) return snprintf(why, len, "osmesa: cannot create a GL 4.3 core context"), false;
    /* the default framebuffer is a token 16x16; rendering goes to FBOs */
    void *buffer = sb_xcalloc(16 * 16, 4);
    if (!g.make_current(ctx, buffer, GL_UNSIGNED_BYTE, 16, 16)) {
        g.destroy(ctx);
        free(buffer);
        return snprintf(why, len, "osmesa: cannot make the context current"), false;
    }
    *ctx_out = ctx;
    *buffer_out = buffer;
    return true;
}

void *sb_osmesa_proc(const char *name) { return g.proc ? (void *)g.proc(name) : NULL; }

void sb_osmesa_close(void *ctx, void *buffer) {
    if (g.destroy) g.destroy((OSMesaContext)ctx);
    free(buffer);
}

#else

bool sb_osmesa_open(void **ctx, void **buffer, char *why, size_t len) {
    (void)ctx, (void)buffer;
    snprintf(why, len, "osmesa: this shadowbench was built without OSMesa (meson -Dosmesa=disabled); use --backend egl");
    return false;
}
void *sb_osmesa_proc(const char *name) { (void)name; return NULL; }
void sb_osmesa_close(void *ctx, void *buffer) { (void)ctx, (void)buffer; }

#endif
