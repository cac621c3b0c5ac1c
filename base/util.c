#define _DEFAULT_SOURCE /* MAP_POPULATE */
#include "util.h"

#include <pthread.h>

#include <signal.h>

#include <errno.h>
#include <limits.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static bool g_quiet, g_verbose;

void sb_set_quiet(bool quiet) { g_quiet = quiet; }
void sb_set_verbose(bool verbose) { g_verbose = verbose; }
bool sb_is_verbose(void) { return g_verbose && !g_quiet; }

bool sb_fail(sb_err *e, const char *fmt, ...) {
    if (e) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(e->msg, sizeof e->msg, fmt, ap);
        va_end(ap);
        for (char *p = e->msg; *p; p++)
            if (*p == '\n' || *p == '\r') *p = ' ';
    }
    return false;
}

/* Lines logged while a capture is on (sb_log_capture), kept whether or not quiet. */
static char *g_capture;
static size_t g_capture_len, g_capture_cap;
static bool g_capturing;

void sb_log(const char *fmt, ...) {
    if (g_quiet && !g_capturing) return;
    char line[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (g_capturing) {
        size_t n = strlen(line) + 1;
        if (g_capture_len + n + 1 > g_capture_cap) {
            g_capture_cap = (g_capture_len + n + 1) * 2;
            g_capture = sb_xrealloc(g_capture, g_capture_cap);
        }
        memcpy(g_capture + g_capture_len, line, n - 1);
        g_capture[g_capture_len + n - 1] = '\n';
        g_capture_len += n;
        g_capture[g_capture_len] = 0;
    }
    if (!g_quiet) fprintf(stderr, "%s\n", line);
}

void sb_verbose(const char *fmt, ...) {
    if (!sb_is_verbose()) return;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

void sb_log_capture(bool on) {
    g_capturing = on;
    if (on) {
        g_capture_len = 0;
        if (g_capture) g_capture[0] = 0;
    }
}

const char *sb_log_captured(void) { return g_capture ? g_capture : ""; }

int sb_open_read(const char *path, size_t *size, sb_err *err) {
    if (!path || !*path) {
        sb_fail(err, "an empty file name: nothing to read");
        return -1;
    }
    /* O_NONBLOCK: opening a FIFO waits for a writer, a device may wait for ever; the descriptor is checked before
       anything is read, and made blocking again for a regular file (where the flag changes nothing anyway) */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) {
        sb_fail(err, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) sb_fail(err, "%s: cannot stat: %s", path, strerror(errno));
    else if (S_ISDIR(st.st_mode)) sb_fail(err, "%s: a folder, not a file", path);
    else if (!S_ISREG(st.st_mode))
        sb_fail(err, "%s: %s, not a regular file", path,
                S_ISFIFO(st.st_mode) ? "a FIFO" : S_ISSOCK(st.st_mode) ? "a socket" : "a device");
    else {
        int fl = fcntl(fd, F_GETFL);
        if (fl >= 0) fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
        if (size) *size = (size_t)st.st_size;
        return fd;
    }
    close(fd);
    return -1;
}

char *sb_read_file(const char *path, size_t *size, sb_err *err) {
    size_t n;
    int fd = sb_open_read(path, &n, err);
    if (fd < 0) return NULL;
    char *buf = malloc(n + 1);
    if (!buf) {
        close(fd);
        sb_fail(err, "%s: out of memory (%zu bytes)", path, n);
        return NULL;
    }
    size_t got = 0;
    while (got < n) {
        ssize_t k = read(fd, buf + got, n - got);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break;
        got += (size_t)k;
    }
    close(fd);
    if (got != n) {
        free(buf);
        sb_fail(err, "%s: short read", path);
        return NULL;
    }
    buf[n] = 0;
    if (size) *size = n;
    return buf;
}

uint64_t sb_binary_identity(void) {
    struct stat st;
    if (stat("/proc/self/exe", &st) != 0) return 0;
    int64_t id[4] = {(int64_t)st.st_size, (int64_t)st.st_mtim.tv_sec, (int64_t)st.st_mtim.tv_nsec, (int64_t)st.st_ino};
    return sb_fnv1a(SB_FNV_SEED, id, sizeof id);
}

void *sb_map_file(const char *path, size_t *size, bool writable) {
    size_t n = 0;
    int fd = sb_open_read(path, &n, NULL);
    if (fd < 0) return NULL;
    void *p = NULL;
    if (n > 0) {
        /* a writable private mapping is not populated: populating it would copy every page (the kernel breaks
           copy-on-write for each), where a reader writes a few (a moving scene's posed vertices) */
        p = mmap(NULL, n, PROT_READ | (writable ? PROT_WRITE : 0), MAP_PRIVATE | (writable ? 0 : MAP_POPULATE), fd, 0);
        if (p == MAP_FAILED) p = NULL;
        else *size = n;
        if (p && writable) madvise(p, n, MADV_WILLNEED);
    }
    close(fd);
    return p;
}

void sb_unmap_file(void *p, size_t size) {
    if (p) munmap(p, size);
}

static volatile sig_atomic_t g_interrupt;

static void on_interrupt(int sig) {
    if (g_interrupt) {   /* the second: at once, as the default action would */
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    g_interrupt = sig;
    static const char msg[] = "\nshadowbench: stopping after the frame in flight (again to stop at once)\n";
    ssize_t w = write(2, msg, sizeof msg - 1);
    (void)w;
}

void sb_interrupt_install(void) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sa.sa_flags = SA_RESTART;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

int sb_interrupted(void) { return g_interrupt; }

const char *sb_interrupt_name(void) { return g_interrupt == SIGTERM ? "SIGTERM" : "SIGINT"; }

static bool g_result_write_failed;

void sb_result_write_failed(void) { g_result_write_failed = true; }
bool sb_result_writes_failed(void) { return g_result_write_failed; }

/* PATH.PID.tmp, every byte written, fsync, close and rename checked. */
static bool write_atomic(const char *path, const void *data, size_t size, sb_err *err) {
    size_t len = strlen(path) + 32;
    char *tmp = sb_xmalloc(len);
    snprintf(tmp, len, "%s.%ld.tmp", path, (long)getpid());   /* its own: two writers never share one */
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        sb_fail(err, "%s: cannot create: %s", tmp, strerror(errno));
        free(tmp);
        return false;
    }
    const char *p = data;
    size_t left = size;
    const char *failed = NULL;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0) {
            if (errno == EINTR) continue;
            failed = "write";
            break;
        }
        p += w;
        left -= (size_t)w;
    }
    if (!failed && fsync(fd) != 0 && errno != EINVAL) failed = "fsync";
    int saved = errno;
    if (close(fd) != 0 && !failed) failed = "close", saved = errno;
    if (failed) {
        sb_fail(err, "%s: %s failed: %s", tmp, failed, strerror(saved));
        unlink(tmp);
        free(tmp);
        return false;
    }
    if (rename(tmp, path) != 0) {
        sb_fail(err, "%s: rename failed: %s", path, strerror(errno));
        unlink(tmp);
        free(tmp);
        return false;
    }
    free(tmp);
    return true;
}

bool sb_write_file_atomic(const char *path, const void *data, size_t size, sb_err *err) {
    if (write_atomic(path, data, size, err)) return true;
    sb_result_write_failed();
    return false;
}

void sb_cache_unkept(const char *what, const char *why) {
    static bool said;
    if (!said) sb_log("warning: %s not kept (%s); going on without it (said once)", what, why);
    said = true;
}

bool sb_write_cache_file_atomic(const char *path, const void *data, size_t size, const char *what) {
    sb_err e;
    if (write_atomic(path, data, size, &e)) return true;
    sb_cache_unkept(what, e.msg);
    return false;
}

bool sb_copy_file(const char *from, const char *to, sb_err *err) {
    size_t n;
    char *data = sb_read_file(from, &n, err);
    if (!data) return false;
    bool ok = sb_write_file_atomic(to, data, n, err);
    free(data);
    return ok;
}

bool sb_mkdir_p(const char *path, sb_err *err) {
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + 1; *p; p++) {
        if (*p != '/') continue;
        *p = 0;
        if (mkdir(buf, 0755) != 0 && errno != EEXIST)
            return sb_fail(err, "%s: cannot create directory: %s", buf, strerror(errno));
        *p = '/';
    }
    if (mkdir(buf, 0755) != 0 && errno != EEXIST)
        return sb_fail(err, "%s: cannot create directory: %s", buf, strerror(errno));
    return true;
}

uint64_t sb_splitmix64(uint64_t *x) { return sb_mix64(*x += 0x9e3779b97f4a7c15u); }

uint64_t sb_fnv1a(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static inline uint64_t rotl64(uint64_t x, int r) { return x << r | x >> (64 - r); }

/* Four lanes of 64-bit words (a multiply and a rotate each), folded and
 * mixed; the tail bytes FNV-style. Several GB/s where sb_fnv1a does one byte
 * per multiply. */
uint64_t sb_hash_bytes(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    /* four lanes in registers (the same sums as an array of four, kept out of memory) */
    uint64_t v0 = h ^ 0x9e3779b97f4a7c15u, v1 = h + 0xc2b2ae3d27d4eb4fu, v2 = h ^ 0x165667b19e3779f9u,
             v3 = h - 0x27d4eb2f165667c5u;
    size_t i = 0;
    for (; i + 32 <= n; i += 32) {
        uint64_t w[4];
        memcpy(w, p + i, 32);
        v0 = rotl64(v0 + w[0] * 0xc2b2ae3d27d4eb4fu, 31) * 0x9e3779b97f4a7c15u;
        v1 = rotl64(v1 + w[1] * 0xc2b2ae3d27d4eb4fu, 31) * 0x9e3779b97f4a7c15u;
        v2 = rotl64(v2 + w[2] * 0xc2b2ae3d27d4eb4fu, 31) * 0x9e3779b97f4a7c15u;
        v3 = rotl64(v3 + w[3] * 0xc2b2ae3d27d4eb4fu, 31) * 0x9e3779b97f4a7c15u;
    }
    uint64_t r = sb_mix64(v0) ^ rotl64(sb_mix64(v1), 17) ^ rotl64(sb_mix64(v2), 31) ^ rotl64(sb_mix64(v3), 47);
    for (; i < n; i++) r = (r ^ p[i]) * 1099511628211ull;
    return sb_mix64(r ^ (uint64_t)n);
}

double sb_now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

char *sb_strdup(const char *s) {
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    memcpy(d, s, n);
    return d;
}

const char *sb_intern(const char *s) {
    static char **pool;
    static size_t n;
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    pthread_mutex_lock(&lock);
    const char *found = NULL;
    for (size_t i = 0; i < n && !found; i++)
        if (!strcmp(pool[i], s)) found = pool[i];
    if (!found) {
        pool = sb_xrealloc(pool, (n + 1) * sizeof *pool);
        found = pool[n++] = sb_strdup(s);
    }
    pthread_mutex_unlock(&lock);
    return found;
}

bool sb_parse_double(const char *s, double *out) {
    if (!s || !*s) return false;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (*end || errno == ERANGE || !isfinite(v)) return false;
    *out = v;
    return true;
}

bool sb_parse_int(const char *s, long *out) {
    if (!s || !*s) return false;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (*end || errno == ERANGE) return false;
    *out = v;
    return true;
}

void sb_utc_now(char *out, size_t len) {
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    strftime(out, len, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

bool sb_make_stamped_dir(const char *base, char *out, size_t len, sb_err *err) {
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    char stamp[32];
    strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
    for (int k = 0; k < 100; k++) {
        if (k == 0) snprintf(out, len, "%s/%s", base, stamp);
        else snprintf(out, len, "%s/%s-%d", base, stamp, k + 1);
        if (access(out, F_OK) != 0) return sb_mkdir_p(out, err);
    }
    return sb_fail(err, "%s: cannot find a free results folder name", base);
}

static void *checked(void *p, size_t n) {
    if (!p && n) {
        fprintf(stderr, "shadowbench: out of memory (%zu bytes)\n", n);
        exit(1);
    }
    return p;
}

void *sb_xmalloc(size_t n) { return checked(malloc(n ? n : 1), n); }

void *sb_xcalloc(size_t count, size_t size) {
    if (size && count > SIZE_MAX / size) return checked(NULL, SIZE_MAX);
    return checked(calloc(count ? count : 1, size ? size : 1), count * size);
}

void *sb_xrealloc(void *p, size_t n) { return checked(realloc(p, n ? n : 1), n); }

static double g_start_ms;
__attribute__((constructor)) static void note_start(void) { g_start_ms = sb_now_ms(); }
double sb_process_start_ms(void) { return g_start_ms; }

const sb_exit_status sb_exit_statuses[] = {
    {SB_EXIT_OK, "ok",
     "every run succeeded or was skipped with a reason; compare, history regressions and history check: no "
     "regression; bisect: the first bad commit found"},
    {SB_EXIT_FAILED, "failed",
     "a run failed (recorded in the summary; the others still ran); compare: a regression; history regressions: a "
     "regression not accepted starts in the newest --recent nights; history check: a figure beyond the nights' band; "
     "bisect: GOOD and BAD do not differ beyond the noise"},
    {SB_EXIT_BAD_INPUT, "bad-input",
     "bad input of any kind, before anything renders: an unknown, misplaced, contradictory or out-of-range option; a "
     "missing, unreadable, damaged or invalid scene, path, batch, results set or history file; an --out or --resume "
     "folder that cannot be written (history add: the other sets are still added)"},
    {SB_EXIT_UNSTABLE, "unstable", "compare: no regression, but a compared timing is UNSTABLE (a run marked stable=no)"},
    {SB_EXIT_WRITE, "not-written",
     "a result file could not be written whole once writing had begun (a full disk, a failed fsync, close or rename; "
     "named on stderr); batch --resume into the same folder completes the set"},
    {SB_EXIT_SIGNAL + 2, "interrupted",
     "SIGINT stopped it in order (completed runs kept; --resume DIR goes on; a second signal ends it at once)"},
    {SB_EXIT_SIGNAL + 15, "terminated", "SIGTERM stopped it in order, as SIGINT"},
};
const int sb_exit_status_count = (int)SB_COUNT(sb_exit_statuses);

bool sb_same_file(const char *a, const char *b) {
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

void sb_put_controls_escaped(FILE *f, const char *text) {
    for (const unsigned char *q = (const unsigned char *)text; *q; q++)
        if (*q < 0x20 || *q == 0x7f) fprintf(f, "\\x%02x", *q);
        else fputc(*q, f);
}

const char *sb_controls_escaped(const char *text, char *out, size_t len) {
    size_t n = 0;
    for (const unsigned char *q = (const unsigned char *)text; *q && n + 5 < len; q++)
        if (*q < 0x20 || *q == 0x7f) n += (size_t)snprintf(out + n, len - n, "\\x%02x", *q);
        else out[n++] = (char)*q;
    if (len) out[n < len ? n : len - 1] = 0;
    return out;
}

void sb_say_line(FILE *f, const char *text) {
    fputs("shadowbench: ", f);
    sb_put_controls_escaped(f, text);
    fputc('\n', f);
}

bool sb_name_check(const char *what, const char *name, sb_err *err) {
    if (!*name) return sb_fail(err, "%s is empty: a name is one line of text", what);
    for (const unsigned char *q = (const unsigned char *)name; *q; q++)
        if (*q < 0x20 || *q == 0x7f)
            return sb_fail(err, "%s holds a control character (byte %u at %d): a name is one line of text", what, *q,
                           (int)(q - (const unsigned char *)name));
    return true;
}

bool sb_path_within(const char *path, const char *dir) {
    struct stat sd, sp;
    if (stat(dir, &sd) != 0 || !S_ISDIR(sd.st_mode)) return false;
    char cur[PATH_MAX];
    snprintf(cur, sizeof cur, "%s", path);
    /* up from path to the first folder that exists, then up from there to the root, looking for dir's inode */
    while (stat(cur, &sp) != 0) {
        char *slash = strrchr(cur, '/');
        if (!slash) snprintf(cur, sizeof cur, ".");
        else if (slash == cur) cur[1] = 0;
        else *slash = 0;
    }
    char real[PATH_MAX];
    if (!realpath(cur, real)) return false;
    for (;;) {
        if (stat(real, &sp) == 0 && sp.st_dev == sd.st_dev && sp.st_ino == sd.st_ino) return true;
        char *slash = strrchr(real, '/');
        if (!slash || (slash == real && !real[1])) return false;
        if (slash == real) real[1] = 0;
        else *slash = 0;
    }
}
