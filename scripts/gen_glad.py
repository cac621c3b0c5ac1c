#!/usr/bin/env python3
"""Generate the glad 2 GL loader into the build directory (called by meson).

Uses the Khronos XML bundled with Debian's python3-glad (--reproducible), so no
network is needed. Output is flattened to glad_gl.c, glad_gl.h and khrplatform.h, and
glad_gl.c is patched to include "glad_gl.h" from the same directory.
"""
import os, shutil, subprocess, sys, tempfile

EXTENSIONS = [
    "GL_ARB_shader_viewport_layer_array", "GL_AMD_vertex_shader_layer",
    "GL_KHR_debug", "GL_ARB_timer_query", "GL_EXT_texture_filter_anisotropic",
    "GL_ARB_depth_clamp", "GL_NV_depth_buffer_float",
]

def main():
    glad, out = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([glad, "--quiet", "--reproducible", "--api", "gl:core=4.6",
                        "--extensions", ",".join(EXTENSIONS), "--out-path", tmp, "c"],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        src = open(os.path.join(tmp, "src", "gl.c")).read()
        src = src.replace("#include <glad/gl.h>", '#include "glad_gl.h"')
        hdr = open(os.path.join(tmp, "include", "glad", "gl.h")).read()
        hdr = hdr.replace("#include <KHR/khrplatform.h>", '#include "khrplatform.h"')
        open(os.path.join(out, "glad_gl.c"), "w").write(src)
        open(os.path.join(out, "glad_gl.h"), "w").write(hdr)
        shutil.copy(os.path.join(tmp, "include", "KHR", "khrplatform.h"), out)

if __name__ == "__main__":
    main()
