/* Small shared helpers: allocation that cannot return NULL. */
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

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_out_of_memory_is_one_line_and_exit_1)};
    return cmocka_run_group_tests_name("util", tests, NULL, NULL);
}
