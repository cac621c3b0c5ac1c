/* resultset.h - a results set proves it is whole.
 *
 * A set (a run's, a batch's, a merge's, a tune rung's folder) ends with a
 * `manifest`: every file of the folder with its size, a checksum and, for a
 * CSV, its row count, then a checksum of the manifest itself; written last,
 * by rename, each time a command finishes writing the set (a run that is
 * resumed drops it first). Everything that reads a set back (history add and
 * check, compare, merge, report) verifies it first, and refuses a damaged
 * one in one line naming the file and what is wrong: missing, cut short,
 * changed, a per-frame CSV with fewer rows than the summary's frames, or a
 * manifest that was edited. A set from before manifests is read as it is,
 * with a one-line note. */
#pragma once
#include <stdbool.h>

#include "util.h"

#define SB_MANIFEST_NAME "manifest"

/* Writes DIR/manifest for the files now in DIR (hidden files and temporaries
 * left out). */
bool sb_resultset_seal(const char *dir, sb_err *err);
/* Removes DIR/manifest: the set is about to change (a resume). Also removes the temporaries a killed writer
 * left (NAME.PID.tmp of a process that is gone: sb_write_file_atomic's, cut short by kill -9); returns how many. */
int sb_resultset_unseal(const char *dir);
/* Checks DIR against its manifest (see above); true when whole, or when it
 * has no manifest (noted once on stderr). */
bool sb_resultset_verify(const char *dir, sb_err *err);
