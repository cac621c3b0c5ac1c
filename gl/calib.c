/* calib.c - the calibration probe (see calib.h). */
#include "calib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stats.h"

static const char probe_vs[] =
    "void main() { vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2); gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }\n";
static const char probe_fs[] =
    "uniform int u_iters;\n"
    "out vec4 o_color;\n"
    "void main() {\n"
    "    vec2 p = gl_FragCoord.xy * 0.001;\n"
    "    float a = 0.0;\n"
    "    for (int i = 0; i < u_iters; i++) a += sin(p.x + float(i) * 0.1) * cos(p.y - a);\n"
    "    o_color = vec4(a);\n"
    "}\n";

bool sb_calib_init(sb_calib *c, const sb_context *ctx, bool queries, sb_err *err) {
    memset(c, 0, sizeof *c);
    c->size = ctx->software ? 256 : 1024;
    c->iters = ctx->software ? 64 : 256;
    c->queries = queries;
    const char *vs[] = {probe_vs}, *fs[] = {probe_fs};
    if (!(c->prog = sb_gpu_program("calibration probe", NULL, vs, 1, fs, 1, err))) return false;
    c->u_iters = glGetUniformLocation(c->prog, "u_iters");
    glGenVertexArrays(1, &c->vao);
    glGenTextures(1, &c->tex);
    glBindTexture(GL_TEXTURE_2D, c->tex);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, c->size, c->size);
    glGenFramebuffers(1, &c->fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, c->fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, c->tex, 0);
    if (queries) glGenQueries(1, &c->query);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return sb_gl_check("calibration probe", err);
}

void sb_calib_free(sb_calib *c) {
    if (c->prog) glDeleteProgram(c->prog);
    if (c->vao) glDeleteVertexArrays(1, &c->vao);
    if (c->tex) glDeleteTextures(1, &c->tex);
    if (c->fbo) glDeleteFramebuffers(1, &c->fbo);
    if (c->query) glDeleteQueries(1, &c->query);
    memset(c, 0, sizeof *c);
}

double sb_calib_measure(sb_calib *c) {
    if (!c->prog) return NAN;
    glBindFramebuffer(GL_FRAMEBUFFER, c->fbo);
    glViewport(0, 0, c->size, c->size);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_STENCIL_TEST);
    glDisable(GL_CULL_FACE);
    glUseProgram(c->prog);
    glUniform1i(c->u_iters, c->iters);
    glBindVertexArray(c->vao);
    /* untimed draws first: the first compiles (or JITs) the shader, and on a
       software rasterizer the first few wake its threads from cold */
    for (int k = c->warmed ? 1 : 10; k > 0; k--) glDrawArrays(GL_TRIANGLES, 0, 3);
    glFinish();
    c->warmed = true;
    double ms[5];
    for (int k = 0; k < 5; k++) {
        if (c->queries) {
            glBeginQuery(GL_TIME_ELAPSED, c->query);
            glDrawArrays(GL_TRIANGLES, 0, 3);
            glEndQuery(GL_TIME_ELAPSED);
            GLuint64 ns = 0;
            glGetQueryObjectui64v(c->query, GL_QUERY_RESULT, &ns);
            ms[k] = (double)ns * 1e-6;
        } else {
            double t0 = sb_now_ms();
            glDrawArrays(GL_TRIANGLES, 0, 3);
            glFinish();
            ms[k] = sb_now_ms() - t0;
        }
    }
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glEnable(GL_DEPTH_TEST);
    return sb_stats_compute(ms, 5).median;
}
