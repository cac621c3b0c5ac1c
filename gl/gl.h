/* gl.h - the GL layer's programs and textures: GL entry points (glad 2,
 * generated at build time), shader compilation with the session's prelude,
 * shadow-map textures, GL error checks and the layered-rendering capability.
 * It knows nothing of scenes or techniques (docs/architecture.md). */
#pragma once
#include "glad_gl.h"

#include "context.h"

/* One shader stage: its type and the source parts after the prelude. */
typedef struct sb_shader_src {
    GLenum type;
    const char *const *parts;
    int count;
} sb_shader_src;

/* What every program compiles with after "#version 430 core", its defines and
 * the stage's define (SB_VERTEX, SB_FRAGMENT, ...): at most 3 parts, kept by
 * pointer. The GPU session sets the scene's common GLSL here; unset, nothing. */
void sb_gl_set_prelude(const char *const *parts, int n);
/* Compiles each stage as "#version 430 core" + defines + prelude + parts
 * and links them; the label names the program in errors and, where the
 * context has KHR_debug (GL 4.3), as its object label (glGetObjectLabel). */
GLuint sb_gpu_link(const char *label, const char *defines, const sb_shader_src *stages, int nstages, sb_err *err);
/* Vertex + fragment shortcut of sb_gpu_link. */
GLuint sb_gpu_program(const char *label, const char *defines, const char *const *vs, int nvs,
                      const char *const *fs, int nfs, sb_err *err);

/* The default-block uniforms two variants of one program share (the camera
 * pass's timed, alpha-tested and evaluation ones), by location in each: made
 * once, so copying the values a technique set on one to another costs a get
 * and a set a uniform, no name lookup. Plain values, vectors, matrices,
 * arrays and samplers; blocks are bound, not copied. */
#define SB_GL_MAX_LINKS 64
typedef struct sb_gl_link {
    GLint from, to;
    GLenum type;
} sb_gl_link;
typedef struct sb_gl_links {
    sb_gl_link v[SB_GL_MAX_LINKS];
    int n;
} sb_gl_links;
/* False when the programs share more than SB_GL_MAX_LINKS uniforms (array elements count one each). */
bool sb_gl_links_make(sb_gl_links *l, GLuint from, GLuint to);
/* Gives each linked uniform of `to` the value it has in `from`. */
void sb_gl_links_copy(const sb_gl_links *l, GLuint from, GLuint to);

/* Whether the GL allocates a texture array of these dimensions and format:
 * no more layers than GL_MAX_ARRAY_TEXTURE_LAYERS, and past 1 GiB (no
 * renderer here refuses less) one is made with glTexStorage3D, checked for
 * GL_OUT_OF_MEMORY, and deleted (a renderer's total memory is the GPU-memory
 * check's; this is its limit on one texture, which llvmpipe, for one, puts at
 * 2 GiB). When it does not, *layers_fit says how many layers of that size it
 * allocates (found to within a 32nd: a count that does, a few more may). */
bool sb_gl_allocates(GLenum format, int width, int height, int layers, int *layers_fit);
/* Bytes a texel of a sized internal format takes (the depth and colour formats the shadow maps use; 4 else). */
int sb_gl_texel_bytes(GLenum format);
/* A depth texture with hardware comparison (LEQUAL), clamped to its edge: GL_TEXTURE_2D_ARRAY of width x height
 * with `layers` layers, GL_TEXTURE_CUBE_MAP_ARRAY of layers / 6 cubes, GL_TEXTURE_CUBE_MAP or GL_TEXTURE_2D (layers
 * ignored); immutable, so that views of its layers can be made (glTextureView). */
GLuint sb_shadow_texture(GLenum target, GLenum format, int width, int height, int layers, bool linear);
/* A shadow texture's sampling state (the bound one of target): depth compare, clamped, bilinear where linear (a view
 * of one made by sb_shadow_texture gets its own). */
void sb_shadow_texture_params(GLenum target, bool linear);

/* Layered shadow rendering (cascades, cube faces): per layer, routed by a
 * geometry shader, by gl_Layer from the vertex shader, or the best available. */
enum { SB_LAYERED_OFF, SB_LAYERED_GS, SB_LAYERED_VS, SB_LAYERED_ON };
int sb_layered_resolve(const sb_context *ctx, int layered);
/* layered=vs needs GL_ARB_shader_viewport_layer_array: false with the reason when the context lacks it. */
bool sb_layered_supported(const sb_context *ctx, int layered, const char *technique, sb_err *why);

/* GL error check: returns false and fills err if one is pending. */
bool sb_gl_check(const char *where, sb_err *err);
