/* score.h - another renderer's frames scored against the exact reference.
 *
 * `shadowbench score SCENE PATH DIR` reads, for each frame it scores, the
 * renderer's visibility (DIR/<--pattern>, dark = shadowed) and the mask of the
 * pixels it drew (DIR/<--mask>), both drawn on the cameras `shadowbench
 * cameras` exported. The run loop (run.c) renders nothing timed for it: its
 * evaluation pass draws the tool's own targets (positions and normals, no
 * shadows), puts the renderer's visibility where a technique's would be, and
 * measures the error as for any run (eval.c). Before that, the mask is held
 * against the tool's geometry: a frame whose pixels do not line up (a mirrored
 * camera, rows upside down, another field of view) is refused, saying which.
 * docs/engines.md has the conventions and a worked example. */
#pragma once
#include <stdbool.h>

#include "util.h"

/* Above this share of a frame's pixels where the renderer's mask and the tool's geometry disagree, the frame's
 * cameras do not match and the frame is refused (a right camera on another rasterizer: silhouette pixels only,
 * 0.01 to 0.02 % on the bundled scenes; a field of view 1 degree off: 0.6 % on plane-box, more elsewhere). */
#define SB_SCORE_ALIGN_MAX 0.002

typedef struct sb_score_src {
    const char *dir;            /* the renderer's frames */
    const char *pattern;        /* printf pattern of a frame's visibility file, one %d (e.g. vis_%04d.png) */
    const char *mask;           /* the same for its mask (white: a pixel it drew geometry in) */
    const char *renderer;       /* the technique column's name */
    const char *params;         /* the params column: what the user says of the renderer's settings */
    bool refused;               /* a frame was refused (bad input: the command exits 2) */
    char why[SB_ERR_LEN];       /* the first refusal's line */
} sb_score_src;

/* A pattern with exactly one integer conversion (%d, %04d, %5d); false with the reason. */
bool sb_score_pattern_ok(const char *pattern, sb_err *err);
/* DIR/pattern of frame pf. */
void sb_score_file(const sb_score_src *src, const char *pattern, int pf, char *out, size_t len);

/* Frame pf of a w x h run: the renderer's visibility into vis (255 lit, rows bottom-up as GL reads them), its
 * mask against the tool's geometry (aux: the evaluation target's normals, 0 where no geometry was drawn): *samples pixels, *mismatches where they disagree. A file that cannot be read or has another
 * size, or a mask that does not line up (more than SB_SCORE_ALIGN_MAX), fails with one line naming the file and
 * what was found; src->refused is set. */
bool sb_score_frame(sb_score_src *src, int pf, int w, int h, const float *aux, unsigned char *vis, long *samples,
                    long *mismatches, sb_err *err);
