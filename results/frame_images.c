/* frame_images.c - the debug images of an evaluated frame. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frame_images.h"

bool sb_images_write_frame(const char *dir, const char *run_id, int frame, int w, int h, const unsigned char *rgba,
                           const unsigned char *vis, const unsigned char *ref, const float *pos, const float *aux,
                           sb_err *err) {
    static const unsigned char cascade_rgb[8][3] = {{255, 0, 0},   {0, 255, 0},   {0, 0, 255},   {0, 255, 255},
                                                    {255, 0, 255}, {255, 140, 0}, {140, 0, 255}, {255, 255, 255}};
    const int n = w * h;
    char path[4600];
#define SB_IMG(kind) (snprintf(path, sizeof path, "%s/%s_f%04d_%s", dir, run_id, frame, kind), path)
    bool ok = sb_image_write_u8(SB_IMG("color.png"), w, h, 4, rgba, err) &&
              sb_image_write_u8(SB_IMG("vis.png"), w, h, 1, vis, err) &&
              sb_image_write_u8(SB_IMG("ref.png"), w, h, 1, ref, err);
    unsigned char *rgb = sb_xmalloc((size_t)n * 3);
    float *texel = sb_xmalloc(sizeof(float) * (size_t)n);
    if (ok) {
        for (int i = 0; i < n; i++) {
            unsigned char *o = rgb + 3 * (size_t)i;
            bool tech_shadow = vis[i] < 128;
            if (ref[i] == 128) o[0] = o[1] = o[2] = 0;
            else if (tech_shadow && ref[i] == 255) o[0] = 255, o[1] = 0, o[2] = 0;       /* false shadow */
            else if (!tech_shadow && ref[i] == 0) o[0] = 0, o[1] = 80, o[2] = 255;       /* false light */
            else o[0] = o[1] = o[2] = ref[i] ? 200 : 70;
        }
        ok = sb_image_write_u8(SB_IMG("error.png"), w, h, 3, rgb, err);
    }
    if (ok) {
        for (int i = 0; i < n; i++) {
            const float *a = aux + 4 * (size_t)i;
            unsigned char *o = rgb + 3 * (size_t)i;
            bool sky = a[0] * a[0] + a[1] * a[1] + a[2] * a[2] < 0.25f;
            int k = (int)lroundf(a[3]);
            if (sky) o[0] = o[1] = o[2] = 0;
            else if (k < 0 || k > 7) o[0] = 255, o[1] = 255, o[2] = 0;
            else memcpy(o, cascade_rgb[k], 3);
            texel[i] = pos[4 * (size_t)i + 3];
        }
        ok = sb_image_write_u8(SB_IMG("cascades.png"), w, h, 3, rgb, err) &&
             sb_image_write_f32(SB_IMG("texel_px.exr"), w, h, 1, texel, err);
    }
#undef SB_IMG
    free(rgb);
    free(texel);
    if (!ok) sb_result_write_failed();
    return ok;
}

bool sb_images_write_flicker(const char *dir, const char *run_id, int frame, int w, int h, const unsigned char *rgb,
                             sb_err *err) {
    char path[4600];
    snprintf(path, sizeof path, "%s/%s_f%04d_flicker.png", dir, run_id, frame);
    return sb_image_write_u8(path, w, h, 3, rgb, err);
}

/* --flip: RUN_fNNNN_shaded.png (the technique's), _shaded_ref.png (the reference's): sRGB RGB floats; _flip.png,
 * the per-pixel FLIP in grey (black 0, white 1). Rows bottom-up as every image here. */
bool sb_images_write_shaded(const char *dir, const char *run_id, int frame, int w, int h, const float *shaded,
                            const float *shaded_ref, const float *flip, sb_err *err) {
    size_t n = (size_t)w * h;
    unsigned char *px = sb_xmalloc(3 * n);
    char path[4600];
    bool ok = true;
    const float *rgb[2] = {shaded, shaded_ref};
    const char *kind[2] = {"shaded", "shaded_ref"};
    for (int k = 0; ok && k < 2; k++) {
        for (size_t i = 0; i < 3 * n; i++) px[i] = (unsigned char)lroundf(255 * fminf(fmaxf(rgb[k][i], 0), 1));
        snprintf(path, sizeof path, "%s/%s_f%04d_%s.png", dir, run_id, frame, kind[k]);
        ok = sb_image_write_u8(path, w, h, 3, px, err);
    }
    for (size_t i = 0; ok && i < n; i++) px[i] = (unsigned char)lroundf(255 * fminf(fmaxf(flip[i], 0), 1));
    snprintf(path, sizeof path, "%s/%s_f%04d_flip.png", dir, run_id, frame);
    ok = ok && sb_image_write_u8(path, w, h, 1, px, err);
    free(px);
    return ok;
}
