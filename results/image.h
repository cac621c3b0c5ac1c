/* image.h - writing images through OpenImageIO (the module
 * results/image_oiio.cc, opened by results/image_dl.c on first use;
 * results/image_none.c in a build without it).
 * Rows are given bottom-up (GL order) and written top-down. The format
 * follows the file extension (.png, .exr, ...). */
#pragma once
#include <stdbool.h>

#include "util.h"

/* false in a build without OpenImageIO (meson -Dimages=disabled, results/image_none.c)
 * or where the image module cannot be opened; the reason in one line. */
bool sb_images_available(void);
const char *sb_images_unavailable_reason(void);
/* channels 1..4 of unsigned bytes */
bool sb_image_write_u8(const char *path, int w, int h, int channels, const unsigned char *pixels, sb_err *err);
/* channels 1..4 of floats (EXR for float data) */
bool sb_image_write_f32(const char *path, int w, int h, int channels, const float *pixels, sb_err *err);
/* Reads an image as w x h RGB floats (*rgb malloc'd, top row first; a PNG's values sRGB-encoded in [0, 1], an
 * EXR's as stored; a grey image's one channel in all three; an alpha channel ignored, never multiplied in): false
 * with one line naming the file where it cannot. Only a regular file is read (a device, FIFO or folder is refused
 * before it is opened), at most SB_IMAGE_MAX_PIXELS of image_module.h (checked on the header, before anything is allocated), and a
 * NaN or infinite value is refused with its pixel. */
bool sb_image_read_rgb(const char *path, int *w, int *h, float **rgb, sb_err *err);

/* The images of one evaluated frame, DIR/<run_id>_fNNNN_<kind>.<ext>:
 * color.png, vis.png (technique visibility), ref.png (reference: white lit,
 * black shadowed, grey not evaluated), error.png (false shadow red, false
 * light blue, agreement in grey), cascades.png (cascade 0 red, 1 green,
 * 2 blue, 3 cyan, 4 magenta, 5 orange, 6 violet, 7 white, outside every map
 * yellow) and texel_px.exr (shadow texels per pixel, float). */
/* RUN_fNNNN_flicker.png: the flicker twin's map of the frame (eval.h: red lit -> shadowed, blue shadowed -> lit). */
bool sb_images_write_flicker(const char *dir, const char *run_id, int frame, int w, int h, const unsigned char *rgb,
                             sb_err *err);
/* --flip: RUN_fNNNN_shaded.png and _shaded_ref.png (the frame shaded with the technique's and with the reference's
 * visibility, sRGB RGB floats) and _flip.png (the per-pixel LDR-FLIP, grey: black 0, white 1). */
bool sb_images_write_shaded(const char *dir, const char *run_id, int frame, int w, int h, const float *shaded,
                            const float *shaded_ref, const float *flip, sb_err *err);
bool sb_images_write_frame(const char *dir, const char *run_id, int frame, int w, int h, const unsigned char *rgba,
                           const unsigned char *vis, const unsigned char *ref, const float *pos, const float *aux,
                           sb_err *err);
