/* context_osmesa.h - the OSMesa backend's calls (context_osmesa.c), for
 * context.c. A header of its own, with no GL types, because GL/osmesa.h pulls
 * in the system GL/gl.h, which glad's header replaces. */
#pragma once
#include <stdbool.h>
#include <stddef.h>

/* Opens libOSMesa (on first use) and makes a current context over a new
 * buffer; false with the reason in why. */
bool sb_osmesa_open(void **ctx, void **buffer, char *why, size_t len);
void *sb_osmesa_proc(const char *name);
void sb_osmesa_close(void *ctx, void *buffer);
