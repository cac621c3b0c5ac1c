/* Small shared helpers: allocation that cannot return NULL; the tests' own
 * command runner, which must not hang on a command that prints a lot. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "support.h"
#include "json.h"
#include "util.h"

/* Runs fn in a child with stderr in a pipe; returns its exit status and output. */
static int in_child(void (*fn)(void), char *out, size_t len) {
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        dup2(fd[1], 2);
        close(fd[0]);
        fn();
        _exit(0);
    }
    close(fd[1]);
    ssize_t n = read(fd[0], out, len - 1);
    out[n > 0 ? n : 0] = 0;
    close(fd[0]);
    int st = 0;
    waitpid(pid, &st, 0);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void huge_malloc(void) { (void)sb_xmalloc(SIZE_MAX / 2); }
static void huge_calloc(void) { (void)sb_xcalloc(SIZE_MAX / 8, 16); } /* the product overflows */
static void huge_realloc(void) { (void)sb_xrealloc(NULL, SIZE_MAX / 2); }

static void test_out_of_memory_is_one_line_and_exit_1(void **st) {
    (void)st;
    void (*fns[])(void) = {huge_malloc, huge_calloc, huge_realloc};
    for (size_t i = 0; i < sizeof fns / sizeof fns[0]; i++) {
        char out[512];
        int rc = in_child(fns[i], out, sizeof out);
        print_message("exit %d: %s", rc, out);
        assert_int_equal(rc, 1);
        assert_non_null(strstr(out, "shadowbench: out of memory ("));
        assert_int_equal(strchr(out, '\n') - out, (long)strlen(out) - 1);
    }
    /* and an ordinary request succeeds, zeroed for calloc */
    unsigned char *p = sb_xcalloc(64, 4);
    for (int i = 0; i < 256; i++) assert_int_equal(p[i], 0);
    free(p);
}

/* A command whose output is larger than the buffer and the pipe together: read to the end (a
 * runner that stopped reading would wait on the child for ever), its exit status kept, and the
 * tail kept, where a results folder is printed. */
static void test_run_capture_reads_everything(void **st) {
    (void)st;
    static char out[65536];
    int rc = run_capture("head -c 300000 /dev/zero | tr '\\0' x; echo; echo the-last-line; exit 3", out, sizeof out);
    assert_int_equal(rc, 3);
    assert_int_equal(strlen(out), sizeof out - 1);
    size_t n = strlen(out);
    assert_string_equal(out + n - strlen("\nthe-last-line\n"), "\nthe-last-line\n");
    char small[64];
    assert_int_equal(run_capture("echo short", small, sizeof small), 0);
    assert_string_equal(small, "short\n");
    /* a buffer smaller than one read */
    assert_int_equal(run_capture("seq 1 5000", small, sizeof small), 0);
    assert_int_equal(strlen(small), sizeof small - 1);
    assert_string_equal(small + strlen(small) - 5, "5000\n");
}

/* Names as data (issue 65): the JSON writer writes UTF-8 as it is and a byte that is none of it as U+FFFD (a scene
 * file named with byte 0xff made the cameras' export no JSON), control characters as escapes; the name check
 * refuses control characters and an empty name; a refusal's line shows a control character as \\xNN. */
static void test_names_as_data(void **st) {
    (void)st;
    sb_jw j = {0};
    sb_jw_str(&j, "a\xff\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\xed\xa0\x80\xc0\xaf\xe2\x82\x1b<\n\"");
    assert_string_equal(j.buf, "\"a\\ufffd\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd"
                               "\\ufffd\\u001b\\u003c\\n\\\"\"");
    sb_jw_free(&j);
    sb_err err;
    assert_true(sb_name_check("the name", "towers \xc3\xa9", &err));
    assert_false(sb_name_check("the name", "", &err));
    assert_false(sb_name_check("the name", "a\x1b[31mb", &err));
    assert_string_equal(err.msg, "the name holds a control character (byte 27 at 1): a name is one line of text");
    assert_false(sb_name_check("the name", "a\x7f", &err));
    char buf[256] = "";
    FILE *f = fmemopen(buf, sizeof buf, "w");
    assert_non_null(f);
    sb_say_line(f, "x\x1b[2Jy\nz");
    fclose(f);
    assert_string_equal(buf, "shadowbench: x\\x1b[2Jy\\x0az\n");
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_out_of_memory_is_one_line_and_exit_1),
                                       cmocka_unit_test(test_run_capture_reads_everything),
                                       cmocka_unit_test(test_names_as_data)};
    return cmocka_run_group_tests_name("util", tests, NULL, NULL);
}
