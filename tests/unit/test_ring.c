/* Query ring bookkeeping: frame f reads frame f-ring, nothing is lost or read twice. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>

#include "timing.h"

static void test_ring_order(void **st) {
    (void)st;
    for (int size = 1; size <= 4; size++) {
        sb_ring r;
        sb_ring_init(&r, size);
        int collected[64];
        memset(collected, 0, sizeof collected);
        for (int f = 0; f < 40; f++) {
            int slot;
            int prev = sb_ring_claim(&r, f, &slot);
            if (f < size) assert_int_equal(prev, -1);
            else assert_int_equal(prev, f - size);
            if (prev >= 0) collected[prev]++;
            assert_int_equal(sb_ring_slot_of(&r, f), slot);
            if (f >= 1 && size > 1) assert_int_equal(sb_ring_slot_of(&r, f - 1), (f - 1) % size);
        }
        /* drain: the last `size` frames are still in the ring */
        for (int s = 0; s < size; s++) {
            assert_true(r.slot_frame[s] >= 40 - size);
            collected[r.slot_frame[s]]++;
        }
        for (int f = 0; f < 40; f++) assert_int_equal(collected[f], 1);
        sb_ring_free(&r);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_ring_order)};
    return cmocka_run_group_tests_name("ring", tests, NULL, NULL);
}
