/* gl.c - GL programs, shadow-map textures, error checks and layered rendering's
 * capabilities: what every pass compiles and allocates with, knowing nothing
 * of scenes or techniques. */
#include "gl.h"

#include <stdlib.h>
#include <string.h>

bool sb_gl_check(const char *where, sb_err *err) {
    GLenum e = glGetError();
    if (e == GL_NO_ERROR) return true;
    while (glGetError() != GL_NO_ERROR) {}
    const char *name = e == GL_INVALID_ENUM ? "GL_INVALID_ENUM" : e == GL_INVALID_VALUE ? "GL_INVALID_VALUE"
                     : e == GL_INVALID_OPERATION ? "GL_INVALID_OPERATION" : e == GL_OUT_OF_MEMORY ? "GL_OUT_OF_MEMORY"
                     : e == GL_INVALID_FRAMEBUFFER_OPERATION ? "GL_INVALID_FRAMEBUFFER_OPERATION" : "GL error";
    return sb_fail(err, "%s: %s (0x%x)", where, name, e);
}

/* What every program compiles with after its defines (sb_gl_set_prelude). One GL context a process. */
enum { PRELUDE_MAX = 3 };
static const char *g_prelude[PRELUDE_MAX];
static int g_prelude_n;

void sb_gl_set_prelude(const char *const *parts, int n) {
    g_prelude_n = n < PRELUDE_MAX ? n : PRELUDE_MAX;
    for (int i = 0; i < g_prelude_n; i++) g_prelude[i] = parts[i];
}

static GLuint compile(GLenum type, const char *label, const char *defines, bool to_gs, const char *const *parts, int n,
                      sb_err *err) {
    const char *src[20];
    int k = 0;
    if (n > 14) {
        sb_fail(err, "%s: %d shader parts, at most 14", label, n);
        return 0;
    }
    src[k++] = "#version 430 core\n";
    src[k++] = defines ? defines : "";
    src[k++] = type == GL_VERTEX_SHADER ? (to_gs ? "#define SB_VERTEX\n#define SB_TO_GS\n" : "#define SB_VERTEX\n")
             : type == GL_GEOMETRY_SHADER ? "#define SB_GEOMETRY\n"
             : type == GL_FRAGMENT_SHADER ? "#define SB_FRAGMENT\n" : "#define SB_COMPUTE\n";
    for (int i = 0; i < g_prelude_n; i++) src[k++] = g_prelude[i];
    for (int i = 0; i < n && k < 20; i++) src[k++] = parts[i];
    GLuint s = glCreateShader(type);
    glShaderSource(s, k, src, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = {0};
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        glDeleteShader(s);
        const char *kind = type == GL_VERTEX_SHADER ? "vertex" : type == GL_GEOMETRY_SHADER ? "geometry"
                         : type == GL_COMPUTE_SHADER ? "compute" : "fragment";
        sb_fail(err, "%s: %s shader does not compile: %s", label, kind, log);
        return 0;
    }
    return s;
}

GLuint sb_gpu_link(const char *label, const char *defines, const sb_shader_src *stages, int nstages, sb_err *err) {
    bool gs = false;
    for (int i = 0; i < nstages; i++) gs |= stages[i].type == GL_GEOMETRY_SHADER;
    GLuint p = glCreateProgram();
    for (int i = 0; i < nstages; i++) {
        GLuint s = compile(stages[i].type, label, defines, gs, stages[i].parts, stages[i].count, err);
        if (!s) {
            glDeleteProgram(p);
            return 0;
        }
        glAttachShader(p, s);
        glDeleteShader(s);
    }
    glLinkProgram(p);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = {0};
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        glDeleteProgram(p);
        sb_fail(err, "%s: program does not link: %s", label, log);
        return 0;
    }
    return p;
}

GLuint sb_gpu_program(const char *label, const char *defines, const char *const *vs, int nvs,
                      const char *const *fs, int nfs, sb_err *err) {
    const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, nvs}, {GL_FRAGMENT_SHADER, fs, nfs}};
    return sb_gpu_link(label, defines, st, 2, err);
}

GLuint sb_shadow_texture(GLenum target, GLenum format, int res, int layers, bool linear) {
    GLuint tex;
    glGenTextures(1, &tex);
    glBindTexture(target, tex);
    if (target == GL_TEXTURE_CUBE_MAP) glTexStorage2D(target, 1, format, res, res);
    else glTexStorage3D(target, 1, format, res, res, layers);
    GLint filt = linear ? GL_LINEAR : GL_NEAREST;
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, filt);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, filt);
    glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(target, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    return tex;
}

int sb_layered_resolve(const sb_context *ctx, int layered) {
    if (layered == SB_LAYERED_ON) return ctx->has_vs_layer ? SB_LAYERED_VS : SB_LAYERED_GS;
    return layered;
}

bool sb_layered_supported(const sb_context *ctx, int layered, const char *technique, sb_err *why) {
    if (layered == SB_LAYERED_VS && !ctx->has_vs_layer)
        return sb_fail(why, "%s:layered=vs needs GL_ARB_shader_viewport_layer_array, which %s lacks", technique,
                       ctx->renderer);
    return true;
}
