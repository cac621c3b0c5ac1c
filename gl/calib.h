/* calib.h - the calibration probe: a fixed GPU workload of known size (a
 * full-screen pass of a fragment loop into a small target), timed the way the
 * run is timed (GL_TIME_ELAPSED with queries, glFinish and the clock in sync
 * mode). The run times it just before and just after its timed frames; a
 * probe that moves says the device moved (clocks, load, neighbours), whatever
 * the technique did. Its size depends only on the kind of renderer: 1024x1024
 * pixels x 256 iterations on a GPU (a fraction of a millisecond), 256x256 x 64
 * on a software rasterizer (about 6 ms on 2 cores). Each timing is the median
 * of five, after untimed draws (ten the first time: a cold start is slow). */
#pragma once
#include "gl.h"

typedef struct sb_calib {
    GLuint fbo, tex, prog, vao, query;
    GLint u_iters;
    int size, iters;
    bool queries, warmed;
} sb_calib;

bool sb_calib_init(sb_calib *c, const sb_context *ctx, bool queries, sb_err *err);
void sb_calib_free(sb_calib *c);
/* The median of five timings of the probe, in ms (the GL state it touches is left unbound). */
double sb_calib_measure(sb_calib *c);
