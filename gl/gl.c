/* gl.c - GL programs, shadow-map textures, error checks and layered rendering's
 * capabilities: what every pass compiles and allocates with, knowing nothing
 * of scenes or techniques. */
#include "gl.h"

#include <stdlib.h>
#include <string.h>

bool sb_gl_check(const char *where, sb_err *err) {
    GLenum e = glGetError();
    if (e == GL_NO_ERROR) return true;
    sb_gl_drain_errors();
    const char *name = e == GL_INVALID_ENUM ? "GL_INVALID_ENUM" : e == GL_INVALID_VALUE ? "GL_INVALID_VALUE"
                     : e == GL_INVALID_OPERATION ? "GL_INVALID_OPERATION" : e == GL_OUT_OF_MEMORY ? "GL_OUT_OF_MEMORY"
                     : e == GL_INVALID_FRAMEBUFFER_OPERATION ? "GL_INVALID_FRAMEBUFFER_OPERATION"
                     : e == GL_CONTEXT_LOST ? "GL_CONTEXT_LOST" : "GL error";
    return sb_fail(err, "%s: %s (0x%x)", where, name, e);
}

/* What every program compiles with after its defines (sb_gl_set_prelude). One GL context a process. */
enum { PRELUDE_MAX = 4 };
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
    /* the scene's vertices (a vec3 at location 0) reach a vertex stage only through sb_world (common.glsl): a
       stage that reads them without it draws shared geometry at its first placement (tiled levels) */
    for (int i = 0; type == GL_VERTEX_SHADER && i < n; i++)
        if (strstr(parts[i], "layout(location = 0) in vec3") && !strstr(parts[i], "sb_world(")) {
            sb_fail(err, "%s: its vertex shader reads the scene's vertices without sb_world (common.glsl)", label);
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
    if (glObjectLabel) glObjectLabel(GL_PROGRAM, p, -1, label);   /* named in GL debuggers (and the tests) */
    return p;
}

GLuint sb_gpu_program(const char *label, const char *defines, const char *const *vs, int nvs,
                      const char *const *fs, int nfs, sb_err *err) {
    const sb_shader_src st[] = {{GL_VERTEX_SHADER, vs, nvs}, {GL_FRAGMENT_SHADER, fs, nfs}};
    return sb_gpu_link(label, defines, st, 2, err);
}

void sb_shadow_texture_params(GLenum target, bool linear) {
    GLint filt = linear ? GL_LINEAR : GL_NEAREST;
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, filt);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, filt);
    glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(target, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
}

GLuint sb_shadow_texture(GLenum target, GLenum format, int width, int height, int layers, bool linear) {
    GLuint tex;
    glGenTextures(1, &tex);
    glBindTexture(target, tex);
    if (target == GL_TEXTURE_2D_ARRAY || target == GL_TEXTURE_CUBE_MAP_ARRAY)
        glTexStorage3D(target, 1, format, width, height, layers);
    else glTexStorage2D(target, 1, format, width, height);
    sb_shadow_texture_params(target, linear);
    return tex;
}

int sb_gl_texel_bytes(GLenum format) {
    switch (format) {
    case GL_DEPTH_COMPONENT16: return 2;
    case GL_RG32F: return 8;
    case GL_RGBA32F: return 16;
    default: return 4;   /* DEPTH_COMPONENT24 (padded to 32 bits), DEPTH_COMPONENT32F, R32F */
    }
}

/* One try: a texture array of these layers, made and deleted; false on GL_OUT_OF_MEMORY. */
static bool allocates(GLenum format, int width, int height, int layers) {
    sb_gl_drain_errors();
    GLuint tex;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D_ARRAY, tex);
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, format, width, height, layers);
    bool ok = glGetError() == GL_NO_ERROR;
    glDeleteTextures(1, &tex);
    sb_gl_drain_errors();
    return ok;
}

bool sb_gl_allocates(GLenum format, int width, int height, int layers, int *layers_fit) {
    GLint max_layers = 0;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    if (max_layers > 0 && layers > max_layers) {
        int fit = 0;
        *layers_fit = sb_gl_allocates(format, width, height, max_layers, &fit) ? max_layers : fit;
        return false;
    }
    if ((double)width * height * layers * sb_gl_texel_bytes(format) <= 1073741824.0) return true;
    if (allocates(format, width, height, layers)) return true;
    /* lo allocates (0: none tried), hi does not; to within a 32nd of hi: each try makes (and llvmpipe clears) up to
       2 GiB, and nine tries took 6-17 s to say a count no one needs to the layer */
    int lo = 0, hi = layers;
    while (hi - lo > 1 && hi - lo > hi / 32) {
        int mid = (lo + hi) / 2;
        if (allocates(format, width, height, mid)) lo = mid;
        else hi = mid;
    }
    *layers_fit = lo;
    return false;
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

/* Components and kind (f float, i int, bool or sampler, u unsigned) of a uniform type. */
static int uniform_shape(GLenum type, char *kind) {
    *kind = 'f';
    switch (type) {
    case GL_FLOAT: return 1;
    case GL_FLOAT_VEC2: return 2;
    case GL_FLOAT_VEC3: return 3;
    case GL_FLOAT_VEC4: case GL_FLOAT_MAT2: return 4;
    case GL_FLOAT_MAT3: return 9;
    case GL_FLOAT_MAT4: return 16;
    case GL_UNSIGNED_INT: *kind = 'u'; return 1;
    case GL_UNSIGNED_INT_VEC2: *kind = 'u'; return 2;
    case GL_UNSIGNED_INT_VEC3: *kind = 'u'; return 3;
    case GL_UNSIGNED_INT_VEC4: *kind = 'u'; return 4;
    case GL_INT_VEC2: case GL_BOOL_VEC2: *kind = 'i'; return 2;
    case GL_INT_VEC3: case GL_BOOL_VEC3: *kind = 'i'; return 3;
    case GL_INT_VEC4: case GL_BOOL_VEC4: *kind = 'i'; return 4;
    default: *kind = 'i'; return 1;   /* int, bool, every sampler and image */
    }
}

static bool link_add(sb_gl_links *l, GLuint from, GLuint to, const char *name, GLenum type) {
    GLint lf = glGetUniformLocation(from, name), lt = glGetUniformLocation(to, name);
    if (lf < 0 || lt < 0) return true;
    if (l->n == SB_GL_MAX_LINKS) return false;
    l->v[l->n++] = (sb_gl_link){lf, lt, type};
    return true;
}

bool sb_gl_links_make(sb_gl_links *l, GLuint from, GLuint to) {
    memset(l, 0, sizeof *l);
    GLint count = 0;
    glGetProgramiv(from, GL_ACTIVE_UNIFORMS, &count);
    for (GLuint i = 0; i < (GLuint)count; i++) {
        char name[256];
        GLint size = 0, block = -1;
        GLenum type = 0;
        glGetActiveUniform(from, i, sizeof name, NULL, &size, &type, name);
        glGetActiveUniformsiv(from, 1, &i, GL_UNIFORM_BLOCK_INDEX, &block);
        if (block >= 0) continue;   /* a block's members live in its buffer, bound alike for both */
        char *bracket = strstr(name, "[0]");
        if (!bracket || size <= 1) {
            if (!link_add(l, from, to, name, type)) return false;
            continue;
        }
        *bracket = 0;
        for (GLint e = 0; e < size; e++) {
            char elem[300];
            snprintf(elem, sizeof elem, "%s[%d]", name, e);
            if (!link_add(l, from, to, elem, type)) return false;
        }
    }
    return true;
}

void sb_gl_links_copy(const sb_gl_links *l, GLuint from, GLuint to) {
    for (int k = 0; k < l->n; k++) {
        const sb_gl_link *u = &l->v[k];
        char kind;
        int n = uniform_shape(u->type, &kind);
        if (kind == 'f') {
            GLfloat v[16];
            glGetUniformfv(from, u->from, v);
            if (u->type == GL_FLOAT_MAT2) glProgramUniformMatrix2fv(to, u->to, 1, GL_FALSE, v);
            else if (u->type == GL_FLOAT_MAT3) glProgramUniformMatrix3fv(to, u->to, 1, GL_FALSE, v);
            else if (u->type == GL_FLOAT_MAT4) glProgramUniformMatrix4fv(to, u->to, 1, GL_FALSE, v);
            else if (n == 1) glProgramUniform1fv(to, u->to, 1, v);
            else if (n == 2) glProgramUniform2fv(to, u->to, 1, v);
            else if (n == 3) glProgramUniform3fv(to, u->to, 1, v);
            else glProgramUniform4fv(to, u->to, 1, v);
        } else if (kind == 'u') {
            GLuint v[4];
            glGetUniformuiv(from, u->from, v);
            if (n == 1) glProgramUniform1uiv(to, u->to, 1, v);
            else if (n == 2) glProgramUniform2uiv(to, u->to, 1, v);
            else if (n == 3) glProgramUniform3uiv(to, u->to, 1, v);
            else glProgramUniform4uiv(to, u->to, 1, v);
        } else {
            GLint v[4];
            glGetUniformiv(from, u->from, v);
            if (n == 1) glProgramUniform1iv(to, u->to, 1, v);
            else if (n == 2) glProgramUniform2iv(to, u->to, 1, v);
            else if (n == 3) glProgramUniform3iv(to, u->to, 1, v);
            else glProgramUniform4iv(to, u->to, 1, v);
        }
    }
}
