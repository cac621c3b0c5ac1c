/* image_module.h - the contract between the binary and the image module
 * (libsbimages.so, base/image_oiio.cc), which base/image_dl.c opens
 * at run time: one C function, rows bottom-up as image.h says. */
#pragma once
#include <stdbool.h>
#include <stddef.h>

#define SB_IMAGE_MODULE_FILE "libsbimages.so"
#define SB_IMAGE_MODULE_ENTRY sb_image_module_write
#define SB_IMAGE_MODULE_SYMBOL "sb_image_module_write"

/* Writes w x h pixels of `channels` unsigned bytes (is_float 0) or floats
 * (is_float 1) to path, in the format its extension names, under a
 * temporary name renamed when complete. false with a message in err. */
typedef bool (*sb_image_module_fn)(const char *path, int w, int h, int channels, int is_float, const void *pixels,
                                   char *err, size_t err_len);

/* Reads an image (PNG 8 or 16 bits, EXR, ...) as RGB floats, top row first: stored integers to [0, 1] as they
 * are (sRGB-encoded for a PNG), one channel repeated to three, alpha dropped. *pixels is malloc'd (the caller
 * frees it). false with a message naming the file in err. */
#define SB_IMAGE_MODULE_READ_ENTRY sb_image_module_read
#define SB_IMAGE_MODULE_READ_SYMBOL "sb_image_module_read"
typedef bool (*sb_image_module_read_fn)(const char *path, int *w, int *h, float **pixels, char *err, size_t err_len);

/* Whether an image can be written there: its folder is one, and a writer exists for its extension (nothing is
 * created). false with a message naming the path in err. */
#define SB_IMAGE_MODULE_CAN_WRITE_ENTRY sb_image_module_can_write
#define SB_IMAGE_MODULE_CAN_WRITE_SYMBOL "sb_image_module_can_write"
typedef bool (*sb_image_module_can_write_fn)(const char *path, char *err, size_t err_len);
/* The most pixels an image read from outside may claim (16384 x 16384), checked on its header before anything is
 * allocated (the fuzzer's build of the reader sets a smaller one). */
#ifndef SB_IMAGE_MAX_PIXELS
#define SB_IMAGE_MAX_PIXELS (16384.0 * 16384.0)
#endif
/* And what it claims against what the file holds: deflate (PNG, EXR's zip) packs at most 1032 bytes in one, so a
 * header whose pixels as stored come to more than this many bytes per byte of file (above a floor of
 * SB_IMAGE_RATIO_FLOOR bytes, where a small image of one colour sits) claims what no data behind it holds. */
#define SB_IMAGE_MAX_RATIO 4096.0
#define SB_IMAGE_RATIO_FLOOR (64.0 * 1024 * 1024)
