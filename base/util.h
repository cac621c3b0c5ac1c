/* util.h - small shared helpers: errors, files, hashing, clocks. */
#pragma once
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define SB_ERR_LEN 512
#define SB_COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* An error message buffer threaded through loaders and parsers. The message is
 * one line, naming the file and place ("scene.glb: /meshes/0/...: expected ..."). */
typedef struct sb_err {
    char msg[SB_ERR_LEN];
} sb_err;

bool sb_fail(sb_err *e, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void sb_log(const char *fmt, ...) __attribute__((format(printf, 1, 2)));   /* stderr, newline added */
void sb_set_quiet(bool quiet);
/* Notes a user cannot act on (what a software rasterizer lacks, and the like):
 * printed only with --verbose (and never when quiet), never captured. */
void sb_verbose(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
void sb_set_verbose(bool verbose);
bool sb_is_verbose(void);
/* While on, sb_log also keeps its lines (newline-terminated; quiet or not):
 * what a load said, for the scene cache to say again. on=true clears them. */
void sb_log_capture(bool on);
const char *sb_log_captured(void);

/* The one way a file is opened for reading: without blocking (a FIFO or a device is refused, never waited on) and
 * only a regular file (through links); err names the file and what it is. A descriptor (blocking again) and, where
 * size is given, the file's size; or -1. */
int sb_open_read(const char *path, size_t *size, sb_err *err);
/* Reads a whole file (through sb_open_read); returns NULL and fills err on failure. *size excludes the added NUL. */
char *sb_read_file(const char *path, size_t *size, sb_err *err);
/* The running binary's identity (size, time and inode of /proc/self/exe): what
 * it wrote to a cache is read back only by the same build. 0 when unknown. */
uint64_t sb_binary_identity(void);
/* Maps a regular, non-empty file whole (pre-faulted: a file in the page cache
 * costs no page faults later); writable: a private copy-on-write mapping. NULL otherwise. */
void *sb_map_file(const char *path, size_t *size, bool writable);
void sb_unmap_file(void *p, size_t size);
/* Writes a result file atomically (PATH.PID.tmp, fsync, close, rename; each
 * checked): on failure err names the file and the OS error, the temporary is
 * removed, what was there before stays whole, and the process is marked
 * (sb_result_write_failed). */
bool sb_write_file_atomic(const char *path, const void *data, size_t size, sb_err *err);
/* The same for a cache (the scene cache, kept reference answers), which a run
 * can do without: a failure is a warning, said once a process, not a mark. */
bool sb_write_cache_file_atomic(const char *path, const void *data, size_t size, const char *what);
/* A cache that cannot be kept (its folder, its file): the one warning a process. */
void sb_cache_unkept(const char *what, const char *why);
/* The exit statuses, one table (sb_exit_statuses): every command exits with
 * one of these, `shadowbench --help` lists them, and the docs check reads
 * them from there into docs/cli.md and the man page. */
enum {
    SB_EXIT_OK = 0,
    SB_EXIT_FAILED = 1,         /* a run failed (recorded; the others ran), or compare/history found a regression */
    SB_EXIT_BAD_INPUT = 2,      /* options, unreadable or invalid scene, path, batch, results or history files */
    SB_EXIT_UNSTABLE = 3,       /* compare: no regression, but a compared timing is UNSTABLE */
    SB_EXIT_WRITE = 4,          /* a result (CSV, summary, meta, image, report page) could not be written whole */
    SB_EXIT_SIGNAL = 128,       /* + the signal: SIGINT (130) or SIGTERM (143) stopped it in order */
};
typedef struct sb_exit_status {
    int code;
    const char *name;           /* one word: ok, failed, bad-input, ... */
    const char *meaning;
} sb_exit_status;
extern const sb_exit_status sb_exit_statuses[];
extern const int sb_exit_status_count;

/* SIGINT and SIGTERM: the first asks for an orderly stop (the frame in flight
 * finishes, completed runs keep their rows, the interrupted run gets a row of
 * status `interrupted`, the process exits 128 + the signal); a second one ends
 * the process at once. sb_interrupted(): the signal asked for, or 0. */
void sb_interrupt_install(void);
int sb_interrupted(void);
/* "SIGINT" or "SIGTERM": the signal sb_interrupted() reports. */
const char *sb_interrupt_name(void);
void sb_result_write_failed(void);
bool sb_result_writes_failed(void);
/* Whether two paths name one file, by any spelling (./, .., a symlink, a hard link): both exist, with one device and
 * inode. An output that is one of a command's inputs is refused with it. */
bool sb_same_file(const char *a, const char *b);
/* A name every writer prints (a scene's, a path's, a renderer's): not empty and without control characters (a
 * newline splits a table's row, an escape sequence rewrites the terminal). false: err says "WHAT holds ...". */
bool sb_name_check(const char *what, const char *name, sb_err *err);
/* "shadowbench: TEXT" and a newline on f, every control character of TEXT written as \xNN (a file name with an
 * escape sequence or a newline in a refusal neither rewrites the terminal nor splits the line). */
void sb_say_line(FILE *f, const char *text);
/* Text from a file or a user (a note, a name) written where a terminal or a line-based reader sees it: each
 * control character (a newline, an escape) as \xNN, so it can neither break a line nor drive the terminal. */
void sb_put_controls_escaped(FILE *f, const char *text);
/* The same into out (len bytes; cut short where it does not fit); returns out. */
const char *sb_controls_escaped(const char *text, char *out, size_t len);
/* Whether path (which need not exist yet: its nearest existing folder decides) is the folder dir or lies under
 * it, by any spelling. A folder a command writes that is, or is in, one of its input folders is refused with it. */
bool sb_path_within(const char *path, const char *dir);
/* Copies a file, written atomically (sb_write_file_atomic). */
bool sb_copy_file(const char *from, const char *to, sb_err *err);
bool sb_mkdir_p(const char *path, sb_err *err);
/* Makes BASE/<UTC time> (or <UTC time>-2, -3, ... when taken) into out. */
bool sb_make_stamped_dir(const char *base, char *out, size_t len, sb_err *err);

uint64_t sb_fnv1a(uint64_t h, const void *data, size_t n);
/* A fast 64-bit hash of large data (scene files): chained like sb_fnv1a (h: the hash so far). Not cryptographic. */
uint64_t sb_hash_bytes(uint64_t h, const void *data, size_t n);
/* splitmix64's finalizer: every bit of z spread over the result (inline: hash tables call it per element). */
static inline uint64_t sb_mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}
/* splitmix64: the next number of the sequence x (shuffles: the same seed, the same order everywhere). */
uint64_t sb_splitmix64(uint64_t *x);
/* A hash of n 64-bit words (hash-table keys). */
static inline uint64_t sb_hash_words(const uint64_t *w, int n) {
    uint64_t h = 0;
    for (int i = 0; i < n; i++) h = sb_mix64(h ^ w[i]);
    return h;
}
#define SB_FNV_SEED 1469598103934665603ull

double sb_now_ms(void);          /* CLOCK_MONOTONIC in milliseconds */
double sb_process_start_ms(void);   /* sb_now_ms() when the process started */
/* The time now in UTC as "YYYY-MM-DDTHH:MM:SSZ". */
void sb_utc_now(char *out, size_t len);

/* Allocation that cannot return NULL: out of memory prints one line
 * ("shadowbench: out of memory (N bytes)") and exits with status 1. */
void *sb_xmalloc(size_t n);
void *sb_xcalloc(size_t count, size_t size);
void *sb_xrealloc(void *p, size_t n);
char *sb_strdup(const char *s);
/* A copy of s that lives as long as the process, the same pointer for equal strings (an option's text read
 * from a line that is freed afterwards). */
const char *sb_intern(const char *s);
/* strtod/strtol wrappers that accept only a whole, finite number. */
bool sb_parse_double(const char *s, double *out);
bool sb_parse_int(const char *s, long *out);
