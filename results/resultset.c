/* resultset.c - a results set's manifest, written and verified (resultset.h). */
#include "resultset.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "columns.h"
#include "csv.h"
#include "table.h"
#include "runkey.h"

#define MANIFEST_HEAD "# shadowbench results set manifest 1: name, bytes, FNV-1a 64 of the bytes, CSV rows (-1: not a CSV)"

/* A file of the set: its name, its size and checksum, its CSV rows. */
typedef struct entry {
    char name[256];
    long long bytes, rows;
    unsigned long long hash;
} entry;

static bool is_csv(const char *name) {
    size_t l = strlen(name);
    return l > 4 && !strcmp(name + l - 4, ".csv");
}

/* Data rows of a CSV text (a header first), -1 when it does not parse. */
static long long csv_rows(const char *name, const char *text) {
    sb_table t;
    sb_err e;
    if (!sb_table_parse(&t, name, text, &e)) return -1;
    long long n = t.nrows;
    sb_table_free(&t);
    return n;
}

static bool describe(const char *dir, const char *name, entry *out, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    size_t size = 0;
    char *data = sb_read_file(path, &size, err);
    if (!data) return false;
    snprintf(out->name, sizeof out->name, "%s", name);
    out->bytes = (long long)size;
    out->hash = sb_fnv1a(SB_FNV_SEED, data, size);
    out->rows = is_csv(name) ? csv_rows(name, data) : -1;
    free(data);
    return true;
}

/* The folder's files that the manifest covers: not hidden, not a temporary, not the manifest. */
static bool covered(const char *dir, const char *name) {
    size_t l = strlen(name);
    if (name[0] == '.' || !strcmp(name, SB_MANIFEST_NAME) || (l > 4 && !strcmp(name + l - 4, ".tmp"))) return false;
    char path[4400];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

static int cmp_name(const void *a, const void *b) { return strcmp(((const entry *)a)->name, ((const entry *)b)->name); }

bool sb_resultset_seal(const char *dir, sb_err *err) {
    DIR *d = opendir(dir);
    if (!d) return sb_fail(err, "%s: cannot read the results folder: %s", dir, strerror(errno));
    entry *e = NULL;
    int n = 0;
    bool ok = true;
    for (struct dirent *de; ok && (de = readdir(d));) {
        if (!covered(dir, de->d_name) || strlen(de->d_name) >= sizeof e->name) continue;
        e = sb_xrealloc(e, sizeof *e * (size_t)(n + 1));
        ok = describe(dir, de->d_name, &e[n++], err);
    }
    closedir(d);
    if (!ok) {
        free(e);
        return false;
    }
    qsort(e, (size_t)n, sizeof *e, cmp_name);
    sb_csv text = {0};
    sb_csv_line(&text, MANIFEST_HEAD);
    for (int i = 0; i < n; i++) {
        char line[512];
        snprintf(line, sizeof line, "%s %lld %016llx %lld", e[i].name, e[i].bytes, e[i].hash, e[i].rows);
        sb_csv_line(&text, line);
    }
    char end[64];
    snprintf(end, sizeof end, "end %016llx", (unsigned long long)sb_fnv1a(SB_FNV_SEED, text.buf, text.len));
    sb_csv_line(&text, end);
    free(e);
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, SB_MANIFEST_NAME);
    ok = sb_write_file_atomic(path, text.buf, text.len, err);
    sb_csv_free(&text);
    return ok;
}

/* NAME.PID.tmp: the PID, or -1 for any other name. */
static long tmp_writer(const char *name) {
    size_t l = strlen(name);
    if (l < 6 || strcmp(name + l - 4, ".tmp")) return -1;
    const char *end = name + l - 4, *p = end;
    while (p > name && p[-1] >= '0' && p[-1] <= '9') p--;
    if (p == end || p == name || p[-1] != '.') return -1;
    return strtol(p, NULL, 10);
}

int sb_resultset_unseal(const char *dir) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, SB_MANIFEST_NAME);
    unlink(path);
    DIR *d = opendir(dir);
    int removed = 0;
    for (struct dirent *e; d && (e = readdir(d));) {
        long pid = tmp_writer(e->d_name);
        if (pid <= 0 || (kill((pid_t)pid, 0) == 0 || errno != ESRCH)) continue;   /* its writer may still be at it */
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        removed += unlink(path) == 0;
    }
    if (d) closedir(d);
    return removed;
}

/* One listed file against the folder. */
static bool check_entry(const char *dir, const entry *want, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, want->name);
    struct stat st;
    if (stat(path, &st) != 0) return sb_fail(err, "%s: missing (the set's manifest lists it): the set is damaged", path);
    if ((long long)st.st_size != want->bytes)
        return sb_fail(err, "%s: %lld bytes where the manifest says %lld: %s", path, (long long)st.st_size, want->bytes,
                       (long long)st.st_size < want->bytes ? "cut short" : "changed since it was written");
    entry got;
    if (!describe(dir, want->name, &got, err)) return false;
    if (got.hash != want->hash) return sb_fail(err, "%s: its bytes differ from the manifest's checksum: changed since it "
                                                    "was written", path);
    return true;
}

/* The per-frame CSVs against the summary: an ok run's file has frames x repeats rows. */
static bool check_frames(const char *dir, const entry *e, int n, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/summary.csv", dir);
    sb_table t;
    if (!sb_table_load(&t, path, err)) return false;
    bool ok = true;
    for (int r = 0; ok && r < t.nrows; r++) {
        long frames = 0, repeats = 1;
        const char *id = sb_run_key_id(&t, r);
        if (sb_status_of(sb_table_get(&t, r, "status")) != SB_STATUS_OK || !sb_parse_int(sb_table_get(&t, r, "frames"), &frames)) continue;
        if (!sb_parse_int(sb_table_get(&t, r, "repeats"), &repeats)) repeats = 1;
        char name[300];
        snprintf(name, sizeof name, "%s.csv", id);
        const entry *f = NULL;
        for (int i = 0; i < n && !f; i++)
            if (!strcmp(e[i].name, name)) f = &e[i];
        snprintf(path, sizeof path, "%s/%s", dir, name);
        if (!f) ok = sb_fail(err, "%s: missing: summary.csv has run %s ok, the manifest lists no such file", path, id);
        else if (f->rows < frames * repeats)
            ok = sb_fail(err, "%s: %lld rows, fewer than the summary's %ld frames x %ld repeats", path, f->rows, frames,
                         repeats);
    }
    sb_table_free(&t);
    return ok;
}

/* The manifest's lines into entries; false when it is not one or its own checksum does not hold. */
static bool parse_manifest(const char *path, char *text, size_t len, entry **out, int *n, sb_err *err) {
    char *end = NULL;
    for (char *p = text; p < text + len; p += strcspn(p, "\n") + (p[strcspn(p, "\n")] != 0))
        if (!strncmp(p, "end ", 4)) end = p;
    unsigned long long want = 0;
    if (strncmp(text, MANIFEST_HEAD, strlen(MANIFEST_HEAD)) || !end || sscanf(end, "end %llx", &want) != 1 ||
        sb_fnv1a(SB_FNV_SEED, text, (size_t)(end - text)) != want)
        return sb_fail(err, "%s: its checksum does not hold: the manifest was edited or damaged", path);
    *end = 0;
    *out = NULL;
    *n = 0;
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
        if (line[0] == '#') continue;
        entry x;
        if (sscanf(line, "%255s %lld %llx %lld", x.name, &x.bytes, &x.hash, &x.rows) != 4) {
            free(*out);
            return sb_fail(err, "%s: a line that is no file entry ('%.60s'): the manifest was edited", path, line);
        }
        *out = sb_xrealloc(*out, sizeof **out * (size_t)(*n + 1));
        (*out)[(*n)++] = x;
    }
    return true;
}

bool sb_resultset_verify(const char *dir, sb_err *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, SB_MANIFEST_NAME);
    struct stat st;
    if (stat(dir, &st) != 0) return sb_fail(err, "%s/summary.csv: no such results folder (%s)", dir, strerror(errno));
    if (!S_ISDIR(st.st_mode)) return sb_fail(err, "%s: not a folder (a results set is the folder a run printed)", dir);
    size_t len = 0;
    char *text = stat(path, &st) == 0 ? sb_read_file(path, &len, err) : NULL;
    if (!text) {
        if (access(path, F_OK) == 0) return false;
        /* noted only where the set reads: a summary that does not is the reader's one line to say */
        snprintf(path, sizeof path, "%s/summary.csv", dir);
        sb_table t;
        sb_err e;
        if (sb_table_load(&t, path, &e)) {
            sb_table_free(&t);
            sb_log("note: %s has no manifest (a set from before they were written): read as it is", dir);
        }
        return true;
    }
    entry *e = NULL;
    int n = 0;
    bool ok = parse_manifest(path, text, len, &e, &n, err);
    for (int i = 0; ok && i < n; i++) ok = check_entry(dir, &e[i], err);
    if (ok) ok = check_frames(dir, e, n, err);
    free(e);
    free(text);
    return ok;
}
