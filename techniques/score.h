/* score.h - another renderer's frames as a technique (score.c): its visibility is read from files.
 *
 * `score:dir=DIR:mask=PATTERN[:vis=PATTERN][:renderer=NAME][:settings=TEXT]`
 * reads, for each frame a run evaluates, the renderer's visibility
 * (DIR/<vis>, dark = shadowed) and the mask of the pixels it drew
 * (DIR/<mask>), both drawn on the cameras `shadowbench cameras` exported.
 * Its final pass puts that visibility where a technique's own would be, so the
 * evaluation measures its error as any run's. It declares no stage (nothing of
 * another renderer is timed here) and has no frame between the path's (trait
 * SB_TRAIT_FOREIGN: no flicker twin, no TAA). After each evaluated frame the
 * mask is held against the tool's geometry (check_frame): a frame whose pixels
 * do not line up (a mirrored camera, rows upside down, another field of view)
 * is refused, saying which, and the command exits 2. Its rows are the
 * renderer's: technique NAME (default: DIR's last part), params TEXT.
 * `shadowbench score SCENE PATH DIR` is the command that builds this spec
 * (docs/engines.md: the conventions and a worked example). */
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "util.h"

/* Above this share of a frame's pixels where the renderer's mask and the tool's geometry disagree, the frame's
 * cameras do not match and the frame is refused (a right camera on another rasterizer: silhouette pixels only,
 * 0.01 to 0.02 % on the bundled scenes; a field of view 1 degree off: 0.6 % on plane-box, more elsewhere). */
#define SB_SCORE_ALIGN_MAX 0.002

/* A pattern with exactly one integer conversion (%d, %04d, %5d); false with the reason. */
bool sb_score_pattern_ok(const char *pattern, sb_err *err);
/* DIR/pattern of frame pf. */
void sb_score_file(const char *dir, const char *pattern, int pf, char *out, size_t len);
/* The files a run of `frames` frames evaluating every `every` reads are there (each evaluated frame's visibility and
 * mask), and the first is w x h: checked before anything is written; false with one line naming the file. */
bool sb_score_files_present(const char *dir, const char *vis, const char *mask, int frames, int every, int w, int h,
                            sb_err *err);
