/* Lamps found by cluster (techniques/lightgrid.c), on numbers alone: every point a lamp's range holds, seen by the
 * camera, lies in the lamp's footprint and in a cluster that lists the lamp; a lamp out of view has no footprint;
 * and the lists are short: a cluster holds the lamps near it, not every lamp. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lightgrid.h"

enum { W = 640, H = 360, LAMPS = 200 };

static uint64_t g_rng = 0x9e3779b97f4a7c15ull;
static double uniform(void) {   /* [0, 1) */
    g_rng = g_rng * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(g_rng >> 11) / 9007199254740992.0;
}

/* A camera at (0, 3, 0) looking down +z over a street of lamps (the frame's fields the grid reads). */
static void camera(sb_frame *f, sb_gpu *gpu, double jitter) {
    memset(gpu, 0, sizeof *gpu);
    gpu->width = W, gpu->height = H;
    memset(f, 0, sizeof *f);
    f->gpu = gpu;
    f->view = sb_m4_look_at(sb_v3_make(0, 3, 0), sb_v3_make(0.3, 2.5, 10), sb_v3_make(0, 1, 0));
    f->proj = sb_m4_perspective(60 * SB_PI / 180, (double)W / H, 0.1, 400);
    f->proj.m[8] += jitter / W, f->proj.m[9] += jitter / H;   /* a TAA frame's subpixel shift */
}

static void test_every_lit_point_finds_its_lamp(void **st) {
    (void)st;
    for (int pass = 0; pass < 2; pass++) {
        sb_gpu gpu;
        sb_frame f;
        camera(&f, &gpu, pass ? 0.8 : 0);
        sb_v3 pos[LAMPS];
        double range[LAMPS];
        for (int i = 0; i < LAMPS; i++) {   /* down the street and beside it, some behind the camera */
            pos[i] = sb_v3_make(uniform() * 20 - 10, uniform() * 6, uniform() * 200 - 20);
            range[i] = i == 7 ? 0 : 0.5 + uniform() * 9;   /* lamp 7 has no range: it lights everything */
        }
        sb_lightgrid g;
        sb_lightgrid_init(&g, W, H);
        uint32_t items = sb_lightgrid_fill(&g, &f, pos, range, LAMPS);
        int checked = 0, edge = 0;
        for (int k = 0; k < 200000; k++) {
            int i = (int)(uniform() * LAMPS);
            double r = (i == 7 ? 50 : range[i]) * cbrt(uniform());
            sb_v3 d = sb_v3_norm(sb_v3_make(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5));
            sb_v3 p = sb_v3_add(pos[i], sb_v3_scale(d, r));
            sb_v3 v = sb_m4_point(f.view, p);
            double depth = -v.z;
            if (depth < 0.1 || depth > 400) continue;
            sb_v3 n = sb_m4_point(f.proj, v);
            if (fabs(n.x) >= 1 || fabs(n.y) >= 1) continue;
            double px = (n.x * 0.5 + 0.5) * W, py = (n.y * 0.5 + 0.5) * H;
            sb_lamp_footprint fp;
            assert_true(sb_lamp_footprint_of(&f, pos[i], range[i], &fp));
            assert_true(px >= fp.x0 && px < fp.x1 && py >= fp.y0 && py < fp.y1);
            assert_true(depth >= fp.z0 && depth <= fp.z1);
            const uint32_t *cell = sb_lightgrid_cell(&g, px, py, depth);
            bool listed = false;
            for (uint32_t j = 0; j < cell[1] && !listed; j++) listed = g.items[cell[0] + j] == (uint32_t)i;
            if (!listed)
                fail_msg("lamp %d (range %g) lights the point at pixel (%.1f, %.1f), depth %g, but its cluster "
                         "(%u lamps) does not list it", i, range[i], px, py, depth, cell[1]);
            checked++;
            edge += r > 0.95 * range[i];
        }
        /* a lamp whose range lies behind the camera is in no cluster */
        sb_lamp_footprint fp;
        assert_false(sb_lamp_footprint_of(&f, sb_v3_make(0, 3, -20), 5, &fp));
        double cells = (double)g.tx * g.ty * g.slices;
        print_message("%d points checked (%d near their lamp's range); %u lamp-cluster pairs, %.2f lamps a cluster "
                      "of %d lamps\n", checked, edge, items, items / cells, LAMPS);
        assert_true(checked > 20000 && edge > 2000);
        assert_true(items / cells < LAMPS / 20.0);   /* short lists: lamp 7 everywhere, the others where they reach */
        assert_true(items >= cells);                 /* and lamp 7 in every one */
        sb_lightgrid_free(&g);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_every_lit_point_finds_its_lamp)};
    return cmocka_run_group_tests_name("lightgrid", tests, NULL, NULL);
}
