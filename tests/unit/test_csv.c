/* CSV writer: quoting, empty fields for NaN, and atomic files. */
#include <ctype.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "csv.h"
#include "report.h"

static void test_quoting(void **st) {
    (void)st;
    sb_csv c = {0};
    sb_csv_str(&c, "plain");
    sb_csv_str(&c, "a,b");
    sb_csv_str(&c, "say \"hi\"");
    sb_csv_num(&c, NAN);
    sb_csv_num(&c, 1.5);
    sb_csv_int(&c, -7);
    sb_csv_empty(&c);
    sb_csv_end_row(&c);
    assert_string_equal(c.buf, "plain,\"a,b\",\"say \"\"hi\"\"\",,1.5,-7,\n");
    sb_csv_free(&c);
}

static void test_atomic_file(void **st) {
    (void)st;
    char dir[] = "/tmp/sbcsvXXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256], tmp[300];
    snprintf(path, sizeof path, "%s/run.csv", dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    sb_csv_file f;
    sb_err err;
    assert_true(sb_csv_file_open(&f, path, &err));
    sb_csv rows = {0};
    sb_csv_str(&rows, "frame");
    sb_csv_end_row(&rows);
    assert_true(sb_csv_file_write(&f, &rows, &err));
    /* while the run is going, only the temporary name exists */
    assert_int_equal(access(path, F_OK), -1);
    assert_int_equal(access(tmp, F_OK), 0);
    assert_true(sb_csv_file_commit(&f, &err));
    assert_int_equal(access(path, F_OK), 0);
    assert_int_equal(access(tmp, F_OK), -1);
    /* an aborted file leaves nothing */
    snprintf(path, sizeof path, "%s/aborted.csv", dir);
    assert_true(sb_csv_file_open(&f, path, &err));
    sb_csv_file_abort(&f);
    assert_int_equal(access(path, F_OK), -1);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_int_equal(access(tmp, F_OK), -1);
    /* whole-file atomic write */
    snprintf(path, sizeof path, "%s/summary.csv", dir);
    assert_true(sb_write_file_atomic(path, "a,b\n", 4, &err));
    size_t n;
    char *back = sb_read_file(path, &n, &err);
    assert_string_equal(back, "a,b\n");
    free(back);
    sb_csv_free(&rows);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

/* Every column of the table is documented in the README's CSV section. */
static void test_columns_documented(void **st) {
    (void)st;
    char path[4096];
    const char *root = getenv("SB_SOURCE_ROOT");
    snprintf(path, sizeof path, "%s/README.md", root ? root : ".");
    sb_err err;
    char *text = sb_read_file(path, NULL, &err);
    assert_non_null(text);
    char *sec = strstr(text, "\n## CSV");
    assert_non_null(sec);
    char *end = strstr(sec + 1, "\n## ");
    if (end) *end = 0;
    int missing = 0;
    for (int pass = 0; pass < 2; pass++) {
        int n = pass ? sb_run_col_count : sb_frame_col_count;
        for (int k = 0; k < n; k++) {
            const char *name = pass ? sb_run_cols[k].name : sb_frame_cols[k].name;
            if (!strncmp(name, "split_", 6) && strstr(sec, "split_1 … split_8")) continue;
            bool found = false;
            size_t len = strlen(name);
            for (const char *p = strstr(sec, name); p && !found; p = strstr(p + 1, name)) {
                char before = p == sec ? ' ' : p[-1], after = p[len];
                found = !(isalnum((unsigned char)before) || before == '_') && !(isalnum((unsigned char)after) || after == '_');
            }
            if (!found) {
                print_message("README's CSV section does not name the %s column %s\n", pass ? "per-run" : "per-frame", name);
                missing++;
            }
        }
    }
    free(text);
    assert_int_equal(missing, 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_columns_documented),cmocka_unit_test(test_quoting), cmocka_unit_test(test_atomic_file)};
    return cmocka_run_group_tests_name("csv", tests, NULL, NULL);
}
