/* lightgrid.c - lamps found by cluster (see lightgrid.h). */
#include "lightgrid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The camera a frame's pass draws from: the frame's own, or the look's (a flicker twin's lookup). */
static void pass_camera(const sb_frame *f, sb_m4 *view, sb_m4 *proj) {
    *view = f->look ? f->look->view : f->view;
    *proj = f->look ? f->look->proj : f->proj;
}

/* The near and far planes of a GL perspective projection, from its matrix. */
static void planes_of(const sb_m4 *proj, double *near, double *far) {
    *near = proj->m[14] / (proj->m[10] - 1);
    *far = proj->m[14] / (proj->m[10] + 1);
}

bool sb_lamp_footprint_of(const sb_frame *f, sb_v3 pos, double range, sb_lamp_footprint *out) {
    sb_m4 view, proj;
    pass_camera(f, &view, &proj);
    const int w = f->gpu->width, h = f->gpu->height;
    double near, far;
    planes_of(&proj, &near, &far);
    *out = (sb_lamp_footprint){0, 0, w, h, near, far};
    if (range <= 0) return true;
    sb_v3 c = sb_m4_point(view, pos);   /* view space: the camera looks down -z */
    double z0 = -c.z - range, z1 = -c.z + range;
    if (z1 < near || z0 > far) return false;
    z0 = fmax(z0, near);
    z1 = fmin(z1, far);
    out->z0 = fmax(near, z0 * 0.98), out->z1 = fmin(far, z1 * 1.02);
    /* the sphere's box, cut to the depth it spans in front of the near plane: its corners' projections bound it */
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int k = 0; k < 8; k++) {
        sb_v3 p = {c.x + (k & 1 ? range : -range), c.y + (k & 2 ? range : -range), k & 4 ? -z1 : -z0};
        sb_v3 n = sb_m4_point(proj, p);
        lo[0] = fmin(lo[0], n.x), hi[0] = fmax(hi[0], n.x);
        lo[1] = fmin(lo[1], n.y), hi[1] = fmax(hi[1], n.y);
    }
    /* to pixels, a pixel wider each way (a jittered projection moves less than one) */
    double x0 = (lo[0] * 0.5 + 0.5) * w - 1, x1 = (hi[0] * 0.5 + 0.5) * w + 1;
    double y0 = (lo[1] * 0.5 + 0.5) * h - 1, y1 = (hi[1] * 0.5 + 0.5) * h + 1;
    out->x0 = (int)fmax(0, floor(x0)), out->x1 = (int)fmin(w, ceil(x1));
    out->y0 = (int)fmax(0, floor(y0)), out->y1 = (int)fmin(h, ceil(y1));
    return out->x0 < out->x1 && out->y0 < out->y1;
}

void sb_lightgrid_init(sb_lightgrid *g, int width, int height) {
    memset(g, 0, sizeof *g);
    g->tx = (width + SB_GRID_TILE - 1) / SB_GRID_TILE;
    g->ty = (height + SB_GRID_TILE - 1) / SB_GRID_TILE;
    g->slices = SB_GRID_SLICES;
    g->heads = sb_xcalloc((size_t)g->tx * g->ty * g->slices * 2, sizeof *g->heads);
}

void sb_lightgrid_free(sb_lightgrid *g) {
    for (int k = 0; k < 2; k++) {
        if (g->buf[k]) glDeleteBuffers(1, &g->buf[k]);
        if (g->tex[k]) glDeleteTextures(1, &g->tex[k]);
    }
    free(g->heads);
    free(g->items);
    free(g->fp);
    free(g->seen);
    memset(g, 0, sizeof *g);
}

/* The slice of a view depth (clamped to the grid): lightgrid.glsl's rule. */
static int slice_of(const sb_lightgrid *g, double z) {
    int s = (int)floor(log(fmax(z, g->near) / g->near) / log(g->far / g->near) * g->slices);
    return s < 0 ? 0 : s >= g->slices ? g->slices - 1 : s;
}

const uint32_t *sb_lightgrid_cell(const sb_lightgrid *g, double px, double py, double depth) {
    int x = (int)(px / SB_GRID_TILE), y = (int)(py / SB_GRID_TILE);
    x = x < 0 ? 0 : x >= g->tx ? g->tx - 1 : x;
    y = y < 0 ? 0 : y >= g->ty ? g->ty - 1 : y;
    return &g->heads[2 * (((size_t)slice_of(g, depth) * g->ty + y) * g->tx + x)];
}

/* Sends n bytes to buffer k (made, or grown when they do not fit) and ties its texture to it. */
static void upload(sb_lightgrid *g, int k, const void *data, size_t n, GLenum format) {
    if (!g->buf[k]) glGenBuffers(1, &g->buf[k]), glGenTextures(1, &g->tex[k]);
    glBindBuffer(GL_TEXTURE_BUFFER, g->buf[k]);
    if (n > g->gl_cap[k] || !g->gl_cap[k]) {
        g->gl_cap[k] = n > 16 ? n + n / 2 : 16;
        glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)g->gl_cap[k], NULL, GL_STREAM_DRAW);
        glBindTexture(GL_TEXTURE_BUFFER, g->tex[k]);
        glTexBuffer(GL_TEXTURE_BUFFER, format, g->buf[k]);
    }
    if (n) glBufferSubData(GL_TEXTURE_BUFFER, 0, (GLsizeiptr)n, data);
}

uint32_t sb_lightgrid_fill(sb_lightgrid *g, const sb_frame *f, const sb_v3 *pos, const double *range, int n) {
    sb_m4 view, proj;
    pass_camera(f, &view, &proj);
    for (int k = 0; k < 4; k++) g->zrow[k] = view.m[4 * k + 2];   /* a point's view z: the view's third row */
    planes_of(&proj, &g->near, &g->far);
    const size_t cells = (size_t)g->tx * g->ty * g->slices;
    memset(g->heads, 0, cells * 2 * sizeof *g->heads);
    /* twice over the lamps: each cluster's count, then (after the running sum) its lamps, in the order given */
    if (n > g->lamp_cap) {   /* the lamps' footprints: grown, kept across frames */
        g->lamp_cap = n;
        g->fp = sb_xrealloc(g->fp, sizeof *g->fp * (size_t)n);
        g->seen = sb_xrealloc(g->seen, sizeof *g->seen * (size_t)n);
    }
    sb_lamp_footprint *fp = g->fp;
    bool *seen = g->seen;
    for (int pass = 0; pass < 2; pass++) {
        for (int i = 0; i < n; i++) {
            if (!pass) seen[i] = sb_lamp_footprint_of(f, pos[i], range[i], &fp[i]);
            if (!seen[i]) continue;
            int s0 = slice_of(g, fp[i].z0), s1 = slice_of(g, fp[i].z1);
            int x0 = fp[i].x0 / SB_GRID_TILE, x1 = (fp[i].x1 - 1) / SB_GRID_TILE;
            int y0 = fp[i].y0 / SB_GRID_TILE, y1 = (fp[i].y1 - 1) / SB_GRID_TILE;
            for (int s = s0; s <= s1; s++)
                for (int y = y0; y <= y1; y++)
                    for (int x = x0; x <= x1; x++) {
                        uint32_t *h = &g->heads[2 * (((size_t)s * g->ty + y) * g->tx + x)];
                        if (pass) g->items[h[0] + h[1]] = (uint32_t)i;
                        h[1]++;
                    }
        }
        if (pass) break;
        uint32_t total = 0;
        for (size_t c = 0; c < cells; c++) {
            g->heads[2 * c] = total;
            total += g->heads[2 * c + 1];
            g->heads[2 * c + 1] = 0;   /* counted again as the lamps are placed */
        }
        if (total > g->item_cap) {
            g->item_cap = total + total / 2;
            g->items = sb_xrealloc(g->items, g->item_cap * sizeof *g->items);
        }
        g->item_count = total;
    }
    return g->item_count;
}

uint32_t sb_lightgrid_build(sb_lightgrid *g, const sb_frame *f, const sb_v3 *pos, const double *range, int n) {
    uint32_t items = sb_lightgrid_fill(g, f, pos, range, n);
    upload(g, 0, g->heads, (size_t)g->tx * g->ty * g->slices * 2 * sizeof *g->heads, GL_RG32UI);
    upload(g, 1, g->items, (size_t)items * sizeof *g->items, GL_R32UI);
    return items;
}

void sb_lightgrid_locate(sb_lightgrid *g, GLuint prog) {
    static const char *const names[SB_GRID_UNIFORMS] = {"u_grid_heads", "u_grid_items", "u_grid", "u_grid_zrow",
                                                         "u_grid_near"};
    for (int k = 0; k < SB_GRID_UNIFORMS; k++) g->u[k] = glGetUniformLocation(prog, names[k]);
}

void sb_lightgrid_bind(const sb_lightgrid *g, int unit) {
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(GL_TEXTURE_BUFFER, g->tex[0]);
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit + 1);
    glBindTexture(GL_TEXTURE_BUFFER, g->tex[1]);
    glActiveTexture(GL_TEXTURE0);
    glUniform1i(g->u[0], unit);
    glUniform1i(g->u[1], unit + 1);
    /* tile pixels, tiles across, tiles down, slices per log unit of depth past the near plane */
    glUniform4f(g->u[2], (float)SB_GRID_TILE, (float)g->tx, (float)g->ty, (float)(g->slices / log(g->far / g->near)));
    glUniform4f(g->u[3], (float)g->zrow[0], (float)g->zrow[1], (float)g->zrow[2], (float)g->zrow[3]);
    glUniform2f(g->u[4], (float)g->near, (float)g->slices);
}
