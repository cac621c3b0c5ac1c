/* pathcheck.h - whether a path's cameras stand where a camera can: not inside
 * closed geometry, not under a surface that faces up, not closer to a surface
 * than the near plane. A camera that does any of these shows the rasterizer
 * one picture and the reference's rays another (geom_mismatch), so the tool
 * says which frames and why before it renders (`path PATH SCENE`, a run's
 * warnings, --strict-path).
 *
 * Per frame, from the camera's position, rays that meet both faces of every
 * triangle (sb_reference_rays_all_faces): 32 directions spread over the
 * sphere (inside: at least 3 in 4 of them meet something, and more than half
 * of those meet the back of a single-sided triangle first), straight up (below:
 * it meets the back of a surface whose front faces up), and the view's
 * centre and four near-plane corners (near: a surface before the near plane
 * along one of them). */
#pragma once
#include "path.h"
#include "reference.h"
#include "scene.h"

/* Ordered by severity: a frame gets the worst it has. */
typedef enum sb_path_verdict {
    SB_PATH_CLEAR,
    SB_PATH_NEAR,       /* a surface closer than the near plane */
    SB_PATH_BELOW,      /* under a surface that faces up */
    SB_PATH_INSIDE,     /* inside closed geometry */
    SB_PATH_VERDICTS
} sb_path_verdict;

extern const char *const sb_path_verdict_names[SB_PATH_VERDICTS];   /* "clear", "near", "below", "inside" */

typedef struct sb_path_frame {
    sb_path_verdict verdict;
    int64_t node;               /* the node of the surface that decided it (-1: none) */
} sb_path_frame;

/* Checks frames first..first+n-1 of a path of `of` frames into out[n] (a scene that moves: one frame at a time,
 * the scene posed at its time); how many are not clear. */
int sb_path_check_frames(const sb_reference *r, const sb_scene *s, const sb_path *p, int first, int n, int of,
                         double aspect, sb_path_frame *out, int threads);
/* Checks frames 0..n-1 of the path (aspect: the render's) into out[n]; how many are not clear. */
int sb_path_check(const sb_reference *r, const sb_scene *s, const sb_path *p, int n, double aspect, sb_path_frame *out,
                  int threads);
/* The frames that are not clear, as one line: "frames 7-9: the camera is
 * inside closed geometry (node 12); frame 20: ..." ("" when all are clear). */
void sb_path_check_text(const sb_path_frame *f, int n, char *out, size_t len);
