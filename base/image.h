/* image.h - reading and writing image files through OpenImageIO (the module
 * base/image_oiio.cc, opened by base/image_dl.c on first use; base/image_none.c
 * in a build without it): below every layer that reads or writes one (a run's
 * frame images, results/frame_images.h; score's frames, techniques/score.c).
 * Rows are given bottom-up (GL order) and written top-down. The format
 * follows the file extension (.png, .exr, ...). */
#pragma once
#include <stdbool.h>

#include "util.h"

/* false in a build without OpenImageIO (meson -Dimages=disabled, base/image_none.c)
 * or where the image module cannot be opened; the reason in one line. */
bool sb_images_available(void);
const char *sb_images_unavailable_reason(void);
/* Whether an image can be written to path: its folder exists and is one, and a writer exists for its extension
 * (nothing is created): what a command checks before it works, so a bad name is bad input (exit 2), not a write
 * that failed at the end. */
bool sb_image_can_write(const char *path, sb_err *err);
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
