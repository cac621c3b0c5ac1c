/* cameras.h - a run's cameras and lights for another renderer: every frame's
 * camera exactly as sb_frame_setup renders it (world space: the scene's
 * origin put back), the sun and every point and spot light, as JSON for a
 * script or as a glTF 2.0 document an engine imports (docs/engines.md). */
#pragma once
#include <stdbool.h>

#include "path.h"
#include "run_opts.h"
#include "scene.h"

typedef enum sb_cameras_format { SB_CAMERAS_JSON, SB_CAMERAS_GLTF } sb_cameras_format;

typedef struct sb_cameras_req {
    const char *scene_name, *path_name;   /* as given: written into the document */
    const sb_scene *scene;
    const sb_path *path;
    const sb_run_opts *opts;              /* frames, size, --sun, --sun-size, --flicker-dt */
    bool twins;                           /* each frame's flicker twin too (--flicker-dt later) */
    sb_cameras_format format;
} sb_cameras_req;

/* The document, NUL-terminated (malloc'd: the caller frees it). */
char *sb_cameras_document(const sb_cameras_req *r);
