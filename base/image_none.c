/* image_none.c - the image writer of a build without OpenImageIO (meson
 * -Dimages=disabled, e.g. a GPU machine that has no image stack): --images is
 * refused when the options are read, and a direct call fails with the reason. */
#include "image.h"

#define NO_IMAGES "this shadowbench was built without OpenImageIO (meson -Dimages=disabled): it writes no images"

bool sb_images_available(void) { return false; }

const char *sb_images_unavailable_reason(void) { return NO_IMAGES; }

bool sb_image_can_write(const char *path, sb_err *err) { return sb_fail(err, "%s: " NO_IMAGES, path); }

bool sb_image_write_u8(const char *path, int w, int h, int channels, const unsigned char *pixels, sb_err *err) {
    (void)w, (void)h, (void)channels, (void)pixels;
    return sb_fail(err, "%s: " NO_IMAGES, path);
}

bool sb_image_write_f32(const char *path, int w, int h, int channels, const float *pixels, sb_err *err) {
    (void)w, (void)h, (void)channels, (void)pixels;
    return sb_fail(err, "%s: " NO_IMAGES, path);
}

bool sb_image_read_rgb(const char *path, int *w, int *h, float **rgb, sb_err *err) {
    (void)w, (void)h;
    *rgb = NULL;
    return sb_fail(err, "%s: " NO_IMAGES, path);
}
