/* context.c - EGL and OSMesa context creation. */
#include "context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "context_osmesa.h"
#include "glad_gl.h"


const char *sb_backend_name(sb_backend b) { return b == SB_BACKEND_OSMESA ? "osmesa" : "egl"; }

static bool has_ext(const char *list, const char *name) {
    if (!list) return false;
    size_t n = strlen(name);
    for (const char *p = list; (p = strstr(p, name)); p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == 0)) return true;
    return false;
}

static bool gl_has_ext(const char *name) {
    GLint n = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &n);
    for (GLint i = 0; i < n; i++) {
        const char *e = (const char *)glGetStringi(GL_EXTENSIONS, (GLuint)i);
        if (e && strcmp(e, name) == 0) return true;
    }
    return false;
}

bool sb_renderer_is_software(const char *renderer) {
    static const char *const names[] = {"llvmpipe", "softpipe", "swrast", "Software", "SwiftShader", "lavapipe"};
    for (size_t i = 0; i < SB_COUNT(names); i++)
        if (strstr(renderer, names[i])) return true;
    return false;
}

static bool finish_gl(sb_context *c, GLADloadfunc load, sb_err *err) {
    int ver = gladLoadGL(load);
    if (!ver) return sb_fail(err, "%s: could not load GL functions", sb_backend_name(c->backend));
    c->gl_major = GLAD_VERSION_MAJOR(ver);
    c->gl_minor = GLAD_VERSION_MINOR(ver);
    snprintf(c->vendor, sizeof c->vendor, "%s", (const char *)glGetString(GL_VENDOR));
    snprintf(c->renderer, sizeof c->renderer, "%s", (const char *)glGetString(GL_RENDERER));
    snprintf(c->version, sizeof c->version, "%s", (const char *)glGetString(GL_VERSION));
    c->software = sb_renderer_is_software(c->renderer);
    if (c->gl_major * 10 + c->gl_minor < 43)
        return sb_fail(err, "%s: GL %d.%d core (%s); shadowbench needs GL 4.3 core", sb_backend_name(c->backend),
                       c->gl_major, c->gl_minor, c->renderer);
    c->has_timer_query = c->gl_major * 10 + c->gl_minor >= 33 || gl_has_ext("GL_ARB_timer_query");
    GLint bits = 0;
    if (c->has_timer_query) {
        glGetQueryiv(GL_TIMESTAMP, GL_QUERY_COUNTER_BITS, &bits);
        c->has_timer_query = bits > 0;
    }
    c->has_compute = c->gl_major * 10 + c->gl_minor >= 43;
    c->has_geometry = c->gl_major * 10 + c->gl_minor >= 32;
    c->has_vs_layer = gl_has_ext("GL_ARB_shader_viewport_layer_array") || gl_has_ext("GL_AMD_vertex_shader_layer");
    c->has_nvx_meminfo = gl_has_ext("GL_NVX_gpu_memory_info");
    c->has_ati_meminfo = gl_has_ext("GL_ATI_meminfo");
    sb_gl_drain_errors();
    return true;
}

void sb_gl_drain_errors(void) {
    /* bounded: a lost context may report GL_CONTEXT_LOST on every call */
    for (int k = 0; k < 64 && glGetError() != GL_NO_ERROR; k++) {}
}

double sb_context_memory_free(const sb_context *c, char *source, size_t len) {
    if (c->memory_limit > 0) {
        snprintf(source, len, "--gpu-memory");
        return c->memory_limit;
    }
    GLint kib[4] = {0, 0, 0, 0};
    if (c->has_nvx_meminfo) {
        glGetIntegerv(0x9049 /* GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX */, kib);
        snprintf(source, len, "free on the GPU (GL_NVX_gpu_memory_info)");
        return 1024.0 * kib[0];
    }
    if (c->has_ati_meminfo) {
        glGetIntegerv(0x87FC /* GL_TEXTURE_FREE_MEMORY_ATI */, kib);
        snprintf(source, len, "free on the GPU (GL_ATI_meminfo)");
        return 1024.0 * kib[0];
    }
    if (c->software) {
        FILE *f = fopen("/proc/meminfo", "r");
        char line[256];
        double avail = 0;
        while (f && fgets(line, sizeof line, f))
            if (sscanf(line, "MemAvailable: %lf kB", &avail) == 1) break;
        if (f) fclose(f);
        snprintf(source, len, "of system memory available to this software rasterizer");
        return 1024.0 * avail;
    }
    snprintf(source, len, "unknown");
    return 0;
}

static GLADapiproc egl_load(const char *name) { return (GLADapiproc)eglGetProcAddress(name); }

static bool egl_try_display(sb_context *c, EGLDisplay dpy, sb_err *err) {
    EGLint maj, min;
    if (!eglInitialize(dpy, &maj, &min)) return sb_fail(err, "egl: eglInitialize failed (0x%x)", eglGetError());
    if (!eglBindAPI(EGL_OPENGL_API)) {
        eglTerminate(dpy);
        return sb_fail(err, "egl: the display has no desktop OpenGL");
    }
    const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig cfg = NULL;
    EGLint n = 0;
    bool have_cfg = eglChooseConfig(dpy, cfg_attr, &cfg, 1, &n) && n > 0;
    if (!have_cfg) {
        const EGLint any[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        have_cfg = eglChooseConfig(dpy, any, &cfg, 1, &n) && n > 0;
    }
    const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    const EGLint ctx_attr43[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 3,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLConfig use_cfg = have_cfg ? cfg : EGL_NO_CONFIG_KHR;
    EGLContext ctx = eglCreateContext(dpy, use_cfg, EGL_NO_CONTEXT, ctx_attr);
    if (ctx == EGL_NO_CONTEXT) ctx = eglCreateContext(dpy, use_cfg, EGL_NO_CONTEXT, ctx_attr43);
    if (ctx == EGL_NO_CONTEXT) {
        eglTerminate(dpy);
        return sb_fail(err, "egl: cannot create a GL 4.3 core context (0x%x)", eglGetError());
    }
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        return sb_fail(err, "egl: surfaceless eglMakeCurrent failed (0x%x); EGL_KHR_surfaceless_context needed",
                       eglGetError());
    }
    c->egl_display = dpy;
    c->egl_context = ctx;
    return finish_gl(c, egl_load, err);
}

static bool egl_create(sb_context *c, sb_err *err) {
    const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    sb_err last = {{0}};
    snprintf(last.msg, sizeof last.msg, "egl: no usable EGL device or platform");
    if (get_display && has_ext(client, "EGL_EXT_device_enumeration") && has_ext(client, "EGL_EXT_platform_device")) {
        PFNEGLQUERYDEVICESEXTPROC query_devices = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
        PFNEGLQUERYDEVICESTRINGEXTPROC query_string =
            (PFNEGLQUERYDEVICESTRINGEXTPROC)eglGetProcAddress("eglQueryDeviceStringEXT");
        EGLDeviceEXT devs[16];
        EGLint nd = 0;
        if (query_devices && query_devices(16, devs, &nd)) {
            /* two passes: hardware devices first, then software */
            for (int pass = 0; pass < 2; pass++)
                for (EGLint i = 0; i < nd; i++) {
                    const char *exts = query_string ? query_string(devs[i], EGL_EXTENSIONS) : NULL;
                    bool sw = has_ext(exts, "EGL_MESA_device_software");
                    if ((pass == 0) == sw) continue;
                    EGLDisplay dpy = get_display(EGL_PLATFORM_DEVICE_EXT, devs[i], NULL);
                    if (dpy == EGL_NO_DISPLAY) continue;
                    const char *drm = has_ext(exts, "EGL_EXT_device_drm") && query_string
                                          ? query_string(devs[i], EGL_DRM_DEVICE_FILE_EXT) : NULL;
                    snprintf(c->device, sizeof c->device, "device %d%s%s%s", (int)i, sw ? " (software)" : "",
                             drm ? " " : "", drm ? drm : "");
                    if (egl_try_display(c, dpy, &last)) return true;
                }
        }
    }
    if (get_display && has_ext(client, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
        snprintf(c->device, sizeof c->device, "surfaceless");
        if (dpy != EGL_NO_DISPLAY && egl_try_display(c, dpy, &last)) return true;
    }
    *err = last;
    return false;
}

static bool osmesa_create(sb_context *c, sb_err *err) {
    char why[SB_ERR_LEN];
    if (!sb_osmesa_open(&c->osmesa_context, &c->osmesa_buffer, why, sizeof why)) return sb_fail(err, "%s", why);
    snprintf(c->device, sizeof c->device, "osmesa");
    return finish_gl(c, (GLADloadfunc)sb_osmesa_proc, err);
}

bool sb_context_create(sb_context *c, sb_backend b, sb_err *err) {
    memset(c, 0, sizeof *c);
    c->backend = b;
    bool ok = b == SB_BACKEND_OSMESA ? osmesa_create(c, err) : egl_create(c, err);
    if (!ok) sb_context_destroy(c);
    return ok;
}

void sb_context_destroy(sb_context *c) {
    if (c->egl_display) {
        eglMakeCurrent(c->egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (c->egl_context) eglDestroyContext(c->egl_display, c->egl_context);
        eglTerminate(c->egl_display);
    }
    if (c->osmesa_context) sb_osmesa_close(c->osmesa_context, c->osmesa_buffer);
    c->egl_display = c->egl_context = c->osmesa_context = c->osmesa_buffer = NULL;
}

void sb_backends_available(const sb_context *have, char *buf, size_t len) {
    buf[0] = 0;
    const sb_backend all[] = {SB_BACKEND_EGL, SB_BACKEND_OSMESA};
    for (size_t i = 0; i < SB_COUNT(all); i++) {
        sb_context c;
        sb_err e;
        bool reuse = have && have->backend == all[i];   /* a second context costs as much again */
        if (!reuse && !sb_context_create(&c, all[i], &e)) continue;
        size_t n = strlen(buf);
        snprintf(buf + n, len - n, "%s%s (%s)", n ? ", " : "", sb_backend_name(all[i]), reuse ? have->renderer : c.renderer);
        if (!reuse) sb_context_destroy(&c);
    }
}
