/* score.c - another renderer's shadows, read from its files (score.h): the
 * frames' visibility in the final pass, the mask held against the tool's
 * geometry after each evaluated frame. */
#include "score.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "error.h"
#include "image.h"
#include "render.h"
#include "shaders.h"

typedef struct score_desc {
    const char *dir, *vis, *mask, *renderer, *settings;
} score_desc;

static const sb_param_def score_params[] = {
    SB_PARAM_T(score_desc, dir, "", "the folder of the renderer's frames"),
    SB_PARAM_T(score_desc, vis, "vis_%04d.png",
               "a frame's visibility in the folder, one %d for the frame's number (dark: shadowed)"),
    SB_PARAM_T(score_desc, mask, "", "a frame's mask, numbered as vis: white where the renderer drew geometry"),
    SB_PARAM_T(score_desc, renderer, "", "the renderer's name, its rows' technique (default: the folder's name)"),
    SB_PARAM_T(score_desc, settings, "", "what the user says of its settings, its rows' params"),
};

/* ---- the files ---- */

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

void sb_score_file(const char *dir, const char *pattern, int pf, char *out, size_t len) {
    char name[1024];
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
    snprintf(name, sizeof name, pattern, pf);   /* checked by sb_score_pattern_ok: one integer conversion */
#pragma GCC diagnostic pop
    snprintf(out, len, "%s/%s", dir, name);
}

bool sb_score_files_present(const char *dir, const char *vis, const char *mask, int frames, int every, int w, int h,
                            sb_err *err) {
    char path[2200];
    for (int pf = 0; pf < frames; pf += every)
        for (int k = 0; k < 2; k++) {
            sb_score_file(dir, k ? mask : vis, pf, path, sizeof path);
            if (access(path, R_OK) != 0)
                return sb_fail(err, "%s: frame %d of %d: %s (--frames %d --error-every %d)", path, pf, frames,
                               strerror(errno), frames, every);
        }
    int iw, ih;
    float *rgb;
    sb_score_file(dir, vis, 0, path, sizeof path);
    if (!sb_image_read_rgb(path, &iw, &ih, &rgb, err)) return false;
    free(rgb);
    if (iw != w || ih != h)
        return sb_fail(err, "%s: %dx%d, the run's --size is %dx%d (the size the cameras were exported at)", path, iw,
                       ih, w, h);
    return true;
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

/* ---- the technique ---- */

static bool score_check(const void *desc, sb_err *err) {
    const score_desc *d = desc;
    struct stat st;
    if (!*d->dir) return sb_fail(err, "dir=FOLDER is needed: the folder of the renderer's frames");
    if (stat(d->dir, &st) != 0 || !S_ISDIR(st.st_mode)) return sb_fail(err, "%s: no such folder of frames", d->dir);
    if (!*d->mask)
        return sb_fail(err, "mask=PATTERN is needed: the renderer's mask of the pixels it drew is how score checks "
                       "that its cameras are the exported ones");
    if (!sb_score_pattern_ok(d->vis, err) || !sb_score_pattern_ok(d->mask, err)) return false;
    if (!sb_images_available()) return sb_fail(err, "reading the frames needs images: %s", sb_images_unavailable_reason());
    return true;
}

/* The rows are the renderer's: its name (the folder's last part unless given) and settings. */
static void score_label(const void *desc, sb_label *out) {
    const score_desc *d = desc;
    char name[SB_PARAM_TEXT_MAX + 1];
    snprintf(name, sizeof name, "%s", d->dir);
    for (size_t l = strlen(name); l > 1 && name[l - 1] == '/';) name[--l] = 0;
    const char *base = strrchr(name, '/');
    out->technique = out->renderer = *d->renderer ? d->renderer : sb_intern(base && base[1] ? base + 1 : name);
    out->params = d->settings;
}

/* Another renderer's maps: their size is not known here. */
static double score_shadow_bytes(const sb_technique *t, const void *desc) {
    (void)t;
    (void)desc;
    return NAN;
}

typedef struct {
    score_desc d;
    sb_final_prog fp;
    GLuint tex;
    int w, h;
    unsigned char *vis;         /* the frame's visibility, 255 lit, rows bottom-up */
    float *mask;                /* its mask (>= 0.5: drawn) */
    int frame;                  /* the path frame whose files these are (-1: none read) */
    char why[SB_ERR_LEN];       /* its files could not be read: the line ("" : read) */
} score_state;

static bool score_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    score_state *s = state;
    const sb_gpu *g = rc->gpu;
    s->d = *(const score_desc *)desc;
    s->w = g->width, s->h = g->height;
    s->frame = -1;
    s->vis = sb_xmalloc((size_t)s->w * s->h);
    s->tex = sb_cpu_vis_texture(g);
    if (!sb_final_prog_create(&s->fp, g, "score", sb_shader_vis_cpu_glsl, NULL, err)) return false;
    return sb_gl_check("score", err);
}

/* Frame pf's files into s->vis and s->mask; false with the line in s->why. */
static bool read_frame(score_state *s, int pf) {
    char vis_path[2200], mask_path[2200];
    sb_score_file(s->d.dir, s->d.vis, pf, vis_path, sizeof vis_path);
    sb_score_file(s->d.dir, s->d.mask, pf, mask_path, sizeof mask_path);
    sb_err e;
    free(s->mask);
    s->mask = NULL;
    float *v = read_grey(vis_path, s->w, s->h, &e), *m = v ? read_grey(mask_path, s->w, s->h, &e) : NULL;
    if (!m) {
        free(v);
        snprintf(s->why, sizeof s->why, "%s", e.msg);
        return false;
    }
    for (size_t i = 0; i < (size_t)s->w * s->h; i++) {
        float x = v[i] < 0 ? 0 : v[i] > 1 ? 1 : v[i];
        s->vis[i] = (unsigned char)lroundf(255 * x);
    }
    free(v);
    s->mask = m;
    s->why[0] = 0;
    return true;
}

static void score_frame(void *state, sb_frame *f) {
    score_state *s = state;
    const bool read = s->frame != f->index;   /* a frame's files are read and sent once */
    if (read) {
        s->frame = f->index;
        if (!read_frame(s, f->index)) memset(s->vis, 255, (size_t)s->w * s->h);   /* refused by check_frame */
    }
    glUseProgram(s->fp.prog);
    sb_cpu_vis_bind(s->tex, f->gpu, read ? s->vis : NULL);
    sb_final_pass(f, &s->fp, false);
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

/* The mask against the tool's geometry: refused past SB_SCORE_ALIGN_MAX, saying what would line it up. */
static bool score_check_frame(void *state, int pf, int w, int h, const float *aux, long *samples, long *mismatches,
                              sb_err *err) {
    score_state *s = state;
    if (s->frame != pf) return sb_fail(err, "score: frame %d was not drawn before its check", pf);
    if (s->why[0]) return sb_fail(err, "%s", s->why);
    const long n = (long)w * h, bad = disagree(s->mask, aux, w, h, false, false);
    *samples = n, *mismatches = bad;
    if ((double)bad / n <= SB_SCORE_ALIGN_MAX) return true;
    const long mx = disagree(s->mask, aux, w, h, true, false), my = disagree(s->mask, aux, w, h, false, true);
    const char *why = "its camera is not the exported one (another field of view, aspect, position or direction, or "
                      "the image shifted)";
    if (mx * 4 < bad && mx <= my)
        why = "it lines up mirrored left to right: a camera of the other handedness (x negated)";
    else if (my * 4 < bad)
        why = "it lines up upside down: rows written bottom row first (the files' top row comes first)";
    char mask_path[2200];
    sb_score_file(s->d.dir, s->d.mask, pf, mask_path, sizeof mask_path);
    return sb_fail(err, "%s: frame %d: the mask and the tool's geometry differ at %.2f%% of the pixels (more than "
                   "%.2g%%): %s", mask_path, pf, 100.0 * bad / n, 100 * SB_SCORE_ALIGN_MAX, why);
}

static void score_destroy(void *state) {
    score_state *s = state;
    sb_final_prog_free(&s->fp);
    if (s->tex) glDeleteTextures(1, &s->tex);
    free(s->vis);
    free(s->mask);
}

const sb_technique sb_technique_score = {
    .name = "score",
    .summary = "another renderer's shadows, read from its frames' files (score.h): scored like a technique, timed never",
    .params = score_params,
    .param_count = (int)SB_COUNT(score_params),
    .desc_size = sizeof(score_desc),
    .traits = SB_TRAIT_FOREIGN,
    .state_size = sizeof(score_state),
    .check = score_check,
    .label = score_label,
    .shadow_bytes = score_shadow_bytes,
    .create = score_create,
    .frame = score_frame,
    .check_frame = score_check_frame,
    .destroy = score_destroy,
};
