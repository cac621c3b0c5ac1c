/* image.h - writing images through OpenImageIO (results/image_oiio.cc).
 * Rows are given bottom-up (GL order) and written top-down. The format
 * follows the file extension (.png, .exr, ...). */
#pragma once
#include <stdbool.h>

#include "util.h"

/* channels 1..4 of unsigned bytes */
bool sb_image_write_u8(const char *path, int w, int h, int channels, const unsigned char *pixels, sb_err *err);
/* channels 1..4 of floats (EXR for float data) */
bool sb_image_write_f32(const char *path, int w, int h, int channels, const float *pixels, sb_err *err);
