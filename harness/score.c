/* score.c - another renderer's frames against the reference (see score.h). */
#include "score.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "image.h"
#include "render.h"

bool sb_score_pattern_ok(const char *pattern, sb_err *err) {
    int conversions = 0;
    for (const char *p = pattern; *p; p++) {
        if (*p != '%') continue;
        if (p[1] == '%') {
            p++;
            continue;
        }
        const char *q = p + 1;
        while (*q >= '0' && *q <= '9') q++;
        if (*q != 'd' || q - p > 4) return sb_fail(err, "'%s': a frame's number is %%d or %%0Nd (e.g. vis_%%04d.png), "
                                                   "not '%.*s'", pattern, (int)(q - p + (*q != 0)), p);
        if (atoi(p + 1) > 16)   /* %999d would name a file of 999 characters, mostly spaces */
            return sb_fail(err, "'%s': a frame's number is at most 16 digits wide, not %d", pattern, atoi(p + 1));
        conversions++;
        p = q;
    }
    if (conversions != 1)
        return sb_fail(err, "'%s': the pattern needs one %%d for the frame's number (e.g. vis_%%04d.png)", pattern);
    return true;
}

void sb_score_file(const sb_score_src *src, const char *pattern, int pf, char *out, size_t len) {
    char name[1024];
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
    snprintf(name, sizeof name, pattern, pf);   /* checked by sb_score_pattern_ok: one integer conversion */
#pragma GCC diagnostic pop
    snprintf(out, len, "%s/%s", src->dir, name);
}

/* An image of the run's size as one grey value per pixel, rows bottom-up. */
static float *read_grey(const char *path, int w, int h, sb_err *err) {
    int iw, ih;
    float *rgb;
    if (!sb_image_read_rgb(path, &iw, &ih, &rgb, err)) return NULL;
    if (iw != w || ih != h) {
        free(rgb);
        sb_fail(err, "%s: %dx%d, the run's --size is %dx%d", path, iw, ih, w, h);
        return NULL;
    }
    float *g = sb_xmalloc(sizeof(float) * (size_t)w * h);
    for (int y = 0; y < h; y++)   /* read top row first */
        for (int x = 0; x < w; x++) {
            const float *p = rgb + 3 * ((size_t)(h - 1 - y) * w + x);
            g[(size_t)y * w + x] = (p[0] + p[1] + p[2]) / 3;
        }
    free(rgb);
    return g;
}

/* Pixels where the mask (read through the mapping) and the tool's geometry disagree. */
static long disagree(const float *mask, const float *aux, int w, int h, bool mirror_x, bool mirror_y) {
    long n = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int mx = mirror_x ? w - 1 - x : x, my = mirror_y ? h - 1 - y : y;
            bool drawn = mask[(size_t)my * w + mx] >= 0.5f, geometry = sb_eval_has_geometry(aux, (size_t)y * w + x);
            n += drawn != geometry;
        }
    return n;
}

bool sb_score_frame(sb_score_src *src, int pf, int w, int h, const float *aux, unsigned char *vis, long *samples,
                    long *mismatches, sb_err *err) {
    char vis_path[2200], mask_path[2200];
    sb_score_file(src, src->pattern, pf, vis_path, sizeof vis_path);
    sb_score_file(src, src->mask, pf, mask_path, sizeof mask_path);
    float *v = read_grey(vis_path, w, h, err), *m = v ? read_grey(mask_path, w, h, err) : NULL;
    if (!m) {
        free(v);
        if (!src->refused) snprintf(src->why, sizeof src->why, "%s", err->msg);
        src->refused = true;
        return false;
    }
    const size_t n = (size_t)w * h;
    for (size_t i = 0; i < n; i++) {
        float x = v[i] < 0 ? 0 : v[i] > 1 ? 1 : v[i];
        vis[i] = (unsigned char)lroundf(255 * x);
    }
    long bad = disagree(m, aux, w, h, false, false);
    *samples = (long)n, *mismatches = bad;
    bool ok = (double)bad / n <= SB_SCORE_ALIGN_MAX;
    if (!ok) {   /* what would line it up, where something simple does */
        const long mx = disagree(m, aux, w, h, true, false), my = disagree(m, aux, w, h, false, true);
        const char *why = "its camera is not the exported one (another field of view, aspect, position or "
                          "direction, or the image shifted)";
        if (mx * 4 < bad && mx <= my)
            why = "it lines up mirrored left to right: a camera of the other handedness (x negated)";
        else if (my * 4 < bad)
            why = "it lines up upside down: rows written bottom row first (the files' top row comes first)";
        sb_fail(err, "%s: frame %d: the mask and the tool's geometry differ at %.2f%% of the pixels (more than "
                "%.2g%%): %s", mask_path, pf, 100.0 * bad / n, 100 * SB_SCORE_ALIGN_MAX, why);
        if (!src->refused) snprintf(src->why, sizeof src->why, "%s", err->msg);
        src->refused = true;
    }
    free(v);
    free(m);
    return ok;
}
