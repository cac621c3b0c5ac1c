/* frame_images.h - the images of an evaluated frame a run writes (--images), through base/image.h. */
#pragma once
#include "image.h"

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
