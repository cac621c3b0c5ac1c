/* main.c - the shadowbench command line: the process set up, then the command (commands.h). */
#include <stdlib.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include "commands.h"
#include "session.h"
#include "version.h"

/* glibc gives the top of the heap back to the system whenever more than
 * M_TRIM_THRESHOLD is free there (128 KiB until the first large block mmap'd
 * is freed, which raises it). A software rasterizer mallocs and frees its
 * per-frame buffers, so until that first free (in practice, until the first
 * run of the process ends) every frame gave pages back and faulted them in
 * again inside the timed work: the first run of a process measured 1.3-1.4x
 * the identical runs after it (llvmpipe, towers, 640x360). Keeping the heap's
 * top removes that. Setting it also stops glibc raising the mmap threshold
 * as large blocks are freed, so every block of 128 KiB or more (the
 * evaluation's per-frame arrays: 26 MB of reference points at 1280x720) was
 * a fresh mmap whose pages faulted in on first touch, each frame again: with
 * blocks under 256 MiB taken from the heap and reused, an evaluated frame
 * whose reference is reused costs 22 ms instead of 100 (towers, 1280x720). */
static void keep_heap_top(void) {
#ifdef __GLIBC__
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
#endif
}

int main(int argc, char **argv) {
    keep_heap_top();
    sb_session_set_build(SB_BUILD_OPTIONS);
    return sb_command_main(argc, argv, SB_VERSION, SB_GIT_COMMIT);
}
