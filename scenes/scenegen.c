/* scenegen.c - writes the bundled scenes (.glb with a KHR_lights_punctual sun)
 * and their fly-through paths, deterministically (no randomness beyond a
 * fixed-seed LCG). Run by the build: scenegen OUTDIR.
 *
 *   plane-box  a 2x2x2 box on a 40x40 slab: analytic shadows for tests
 *   desert     wide flat terrain, ~6000 low boxy buildings (>200k triangles)
 *   towers     a dense block of skyscrapers with setbacks and narrow streets
 *   overhangs  cantilevered buildings and bridges over open ground, far views
 *   movers     plane-box's slab with a sliding box and a turning bar (node animation)
 * and the conformance set (conformance.h). */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "conformance.h"
#include "glb.h"
#include "sbmath.h"

static uint32_t g_seed = 12345u;
static double rnd(void) { /* deterministic LCG in [0,1) */
    g_seed = g_seed * 1664525u + 1013904223u;
    return (g_seed >> 8) / 16777216.0;
}

static double terrain_h(double x, double z) {
    return 1.2 * sin(x / 37.0) * cos(z / 53.0) + 0.6 * sin(x / 13.0 + z / 17.0);
}

/* A terrain tile of cells x cells quads with smooth normals, as a closed slab skirt-less surface. */
static void terrain_tile(sb_glb_mesh *m, double x0, double z0, double size, int cells) {
    uint32_t base = m->nv;
    double d = size / cells, e = 0.01;
    for (int j = 0; j <= cells; j++)
        for (int i = 0; i <= cells; i++) {
            double x = x0 + i * d, z = z0 + j * d;
            double hx = (terrain_h(x + e, z) - terrain_h(x - e, z)) / (2 * e);
            double hz = (terrain_h(x, z + e) - terrain_h(x, z - e)) / (2 * e);
            sb_v3 n = sb_v3_norm(sb_v3_make(-hx, 1, -hz));
            sb_glb_vert(m, x, terrain_h(x, z), z, n.x, n.y, n.z);
        }
    for (int j = 0; j < cells; j++)
        for (int i = 0; i < cells; i++) {
            uint32_t a = base + j * (cells + 1) + i, b = a + 1, c = a + cells + 1, dd = c + 1;
            sb_glb_tri(m, a, c, b);
            sb_glb_tri(m, b, c, dd);
        }
}

static int write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fputs(text, f);
    return fclose(f) == 0 ? 0 : 1;
}

/* A generated scene: DIR/NAME.glb and its camera path DIR/NAME.path. */
static int write_scene(sb_glb_scene *s, const char *dir, const char *name, const char *path_text) {
    char p[4096];
    snprintf(p, sizeof p, "%s/%s.glb", dir, name);
    int rc = sb_glb_write(s, p);
    snprintf(p, sizeof p, "%s/%s.path", dir, name);
    return rc | write_text(p, path_text);
}

/* ---- the scenes ---- */

static int gen_plane_box(const char *dir) {
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(30, 50);
    sb_glb_box(sb_glb_new_mesh(&s, 0), -20, -0.5, -20, 20, 0, 20);
    sb_glb_box(sb_glb_new_mesh(&s, 1), -1, 0, -1, 1, 2, 1);
    return write_scene(&s, dir, "plane-box",
                       "# plane-box: a slow half orbit around the box\n"
                       "fov 60\n"
                       "look 0   0 6 12     0 0.5 0\n"
                       "look 4   10 6 6     0 0.5 0\n"
                       "look 8   12 7 -4    0 0.5 0\n"
                       "look 12  4 9 -11    0 0.5 0\n");
}

/* plane-box with a lamp (a point light) beside the box, and the sun */
static int gen_plane_box_lamp(const char *dir) {
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(30, 50);
    sb_glb_box(sb_glb_new_mesh(&s, 0), -20, -0.5, -20, 20, 0, 20);
    sb_glb_box(sb_glb_new_mesh(&s, 1), -1, 0, -1, 1, 2, 1);
    s.lamps[s.nlamps++] = sb_v3_make(2.5, 3.5, 1.5);
    return write_scene(&s, dir, "plane-box-lamp",
                       "# plane-box-lamp: around the box, lit by the lamp\n"
                       "fov 60\n"
                       "look 0   -7 6 -6    0 0.5 0\n"
                       "look 4   -8 5 3     0 0.5 0\n"
                       "look 8   -3 7 -9    0 0.5 0\n");
}

static int gen_desert(const char *dir) {
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(120, 35);
    g_seed = 1;
    const int tiles = 16, cells = 16;
    const double size = 400, tile = size / tiles, x0 = -size / 2;
    for (int tj = 0; tj < tiles; tj++)
        for (int ti = 0; ti < tiles; ti++) {
            double tx = x0 + ti * tile, tz = x0 + tj * tile;
            terrain_tile(sb_glb_new_mesh(&s, 2), tx, tz, tile, cells);
            sb_glb_mesh *b = sb_glb_new_mesh(&s, 4);
            /* streets on the tile borders: buildings keep 3 units away */
            for (int k = 0; k < 23; k++) {
                double w = 2 + 3 * rnd(), d = 2 + 3 * rnd(), h = 3 + 7 * rnd();
                double bx = tx + 3 + rnd() * (tile - 6 - w), bz = tz + 3 + rnd() * (tile - 6 - d);
                double ground = fmin(fmin(terrain_h(bx, bz), terrain_h(bx + w, bz)),
                                     fmin(terrain_h(bx, bz + d), terrain_h(bx + w, bz + d))) - 0.3;
                sb_glb_box(b, bx, ground, bz, bx + w, ground + 0.3 + h, bz + d);
            }
        }
    return write_scene(&s, dir, "desert",
                       "# desert: low along a street between blocks, then up to a wide view (50 s); the keys spaced so that\n"
                       "# the spline neither dips under the terrain nor cuts a corner (shadowbench path desert desert)\n"
                       "fov 60\n"
                       "look 0    -175 5 -150    -175 5 -100\n"
                       "look 10   -175 5 -50     -175 5 0\n"
                       "look 18   -175 6 10      -175 6 60\n"
                       "look 24   -175 14 30     -120 5 40\n"
                       "look 32   -150 40 40     -60 3 30\n"
                       "look 40   -40 40 60      50 0 0\n"
                       "look 50   0 120 190      0 0 0\n");
}

/* the towers' ground and skyscrapers (with setbacks), shared by the day and night scenes */
static void towers_buildings(sb_glb_scene *s) {
    g_seed = 2;
    sb_glb_box(sb_glb_new_mesh(s, 0), -160, -1, -160, 160, 0, 160);
    const int blocks = 8;
    const double pitch = 26, street = 6, half = blocks * pitch / 2;
    for (int bj = 0; bj < blocks; bj++)
        for (int bi = 0; bi < blocks; bi++) {
            sb_glb_mesh *m = sb_glb_new_mesh(s, 3);
            double bx = -half + bi * pitch + street / 2, bz = -half + bj * pitch + street / 2;
            double lot = (pitch - street) / 2;
            for (int k = 0; k < 4; k++) {
                double lx = bx + (k & 1) * lot + 0.5, lz = bz + (k >> 1) * lot + 0.5, w = lot - 1;
                double h = 40 + 110 * rnd() * rnd();
                /* three setbacks */
                sb_glb_box(m, lx, 0, lz, lx + w, h * 0.5, lz + w);
                sb_glb_box(m, lx + 1, h * 0.5, lz + 1, lx + w - 1, h * 0.8, lz + w - 1);
                sb_glb_box(m, lx + 2.5, h * 0.8, lz + 2.5, lx + w - 2.5, h, lz + w - 2.5);
            }
        }
}

/* towers' camera path (towers-draco has the same); streets run along x = -104 + 26k and z = -104 + 26k */
static const char towers_path[] =
    "# towers: down a narrow street between skyscrapers, then up it above the roofs (25 s)\n"
    "fov 60\n"
    "look 0    0 4 -120    0 4 -60\n"
    "look 5    0 4 -60     0 5 0\n"
    "look 10   0 5 0       0 8 60\n"
    "look 14   0 30 50     0 15 90\n"
    "look 19   0 170 90    0 20 0\n"
    "look 25   120 200 200 0 0 0\n";

static int gen_towers(const char *dir) {
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(200, 55);
    towers_buildings(&s);
    return write_scene(&s, dir, "towers", towers_path);
}

/* towers at night: no sun, street lamps along the path's street */
static int gen_towers_night(const char *dir) {
    sb_glb_scene s = {0};
    s.no_sun = true;
    towers_buildings(&s);
    /* lamps on posts along the street at x = 0, and their posts */
    sb_glb_mesh *posts = sb_glb_new_mesh(&s, 4);
    for (int i = 0; i < 6; i++) {
        double z = -90 + 36 * i;
        sb_glb_box(posts, 1.6, 0, z - 0.1, 1.8, 5.5, z + 0.1);
        s.lamps[s.nlamps++] = sb_v3_make(1.2, 6, z);
    }
    return write_scene(&s, dir, "towers-night",
                       "# towers-night: down the lamp-lit street\n"
                       "fov 60\n"
                       "look 0    -1.5 3 -120   0 3 -60\n"
                       "look 8    -1.5 3 -60    0 2 0\n"
                       "look 16   -1.5 4 0      1 2 60\n");
}

/* a street lit by 64 lamps of range 7 in two rows, a post and a crate under each: the camera looks down the
 * street, so near lamps light much of the screen and far ones a few pixels (--lights, atlas policies) */
static int gen_street_lamps(const char *dir) {
    sb_glb_scene s = {0};
    s.no_sun = true;
    sb_glb_box(sb_glb_new_mesh(&s, 0), -12, -0.5, -8, 12, 0, 200);
    sb_glb_mesh *posts = sb_glb_new_mesh(&s, 4), *crates = sb_glb_new_mesh(&s, 1);
    for (int i = 0; i < 64; i++) {
        double x = i % 2 ? 4 : -4, z = 6 * (i / 2), side = i % 2 ? 1 : -1;
        sb_glb_box(posts, fmin(x + side * 0.6, x + side * 0.8), 0, z - 0.1, fmax(x + side * 0.6, x + side * 0.8), 3.8,
                   z + 0.1);   /* a box's corners low, then high: its faces wind outward */
        sb_glb_box(crates, x - side * 1.5 - 0.5, 0, z + 1, x - side * 1.5 + 0.5, 1, z + 2);
        s.lamp_range[s.nlamps] = 7;
        s.lamps[s.nlamps++] = sb_v3_make(x, 4, z);
    }
    return write_scene(&s, dir, "street-lamps",
                       "# street-lamps: down the street between the two rows of lamps\n"
                       "fov 60\n"
                       "near 0.5\n"
                       "far 220\n"
                       "look 0   0 3 -6     0 1 40\n"
                       "look 8   0 3 30     0 1 80\n");
}

static int gen_overhangs(const char *dir) {
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(60, 30);
    g_seed = 3;
    sb_glb_box(sb_glb_new_mesh(&s, 0), -600, -1, -600, 600, 0, 600);
    const int n = 10;
    const double pitch = 40;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            sb_glb_mesh *m = sb_glb_new_mesh(&s, (i + j) % 2 ? 4 : 1);
            double cx = (i - n / 2 + 0.5) * pitch, cz = (j - n / 2 + 0.5) * pitch;
            double h = 15 + 30 * rnd();
            /* a slim core, a wide cantilevered slab (overhang) and a roof ring */
            sb_glb_box(m, cx - 4, 0, cz - 4, cx + 4, h, cz + 4);
            sb_glb_box(m, cx - 12, h * 0.6, cz - 9, cx + 12, h * 0.6 + 2, cz + 9);
            sb_glb_box(m, cx - 9, h, cz - 9, cx + 9, h + 1.5, cz + 9);
            for (int k = 0; k < 6; k++) { /* pillars and fins */
                double a = k * SB_PI / 3;
                double px = cx + 7 * cos(a), pz = cz + 7 * sin(a);
                sb_glb_box(m, px - 0.5, 0, pz - 0.5, px + 0.5, h * 0.6, pz + 0.5);
            }
            if (i + 1 < n && rnd() < 0.5) /* bridge to the east neighbour */
                sb_glb_box(m, cx + 12, h * 0.6 + 0.5, cz - 1.5, cx + pitch - 12, h * 0.6 + 1.5, cz + 1.5);
            if (j + 1 < n && rnd() < 0.4) /* bridge to the north neighbour */
                sb_glb_box(m, cx - 1.5, h * 0.4, cz + 9, cx + 1.5, h * 0.4 + 1, cz + pitch - 9);
        }
    return write_scene(&s, dir, "overhangs",
                       "# overhangs: under the slabs and bridges, between the cores, then out to a far view (25 s)\n"
                       "fov 60\n"
                       "look 0    -220 3 0       -100 4 0\n"
                       "look 6    -100 3 0       -40 6 20\n"
                       "look 12   -40 4 20       20 8 60\n"
                       "look 15   -40 10 40      0 10 80\n"
                       "look 19   -30 70 60      0 10 0\n"
                       "look 25   300 120 400    0 0 0\n");
}

/* towers with every mesh Draco-compressed (conformance set; a build with Draco only) */
static int gen_towers_draco(const char *dir) {
    if (!SB_HAVE_DRACO) return 0;
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(200, 55);
    towers_buildings(&s);
    for (int i = 0; i < s.n; i++) s.meshes[i].draco = true;
    sb_glb_extension(&s, "KHR_draco_mesh_compression", true);
    return write_scene(&s, dir, "towers-draco", towers_path);
}

/* movers: plane-box's slab with casters that move by node animation, as a file would carry them: a 2x2x2 box
 * sliding along x from -8 to 8 and back over 8 s (clip "slide", LINEAR translation), a 6 m bar at 3 m turning
 * about the vertical once in 8 s (clip "turn", rotation), and a box that stays. Its path holds the camera still
 * for 8 s above the slider's track, so that all that changes is what moves (tests, the nightly's dynamic
 * section). */
static int gen_movers(const char *dir) {
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(30, 50);
    sb_glb_box(sb_glb_new_mesh(&s, 0), -20, -0.5, -20, 20, 0, 20);
    sb_glb_box(sb_glb_new_mesh(&s, 1), 6, 0, 6, 8, 2, 8);
    sb_glb_mesh *m = sb_glb_new_mesh(&s, 2);
    sb_glb_box(m, -1, 0, -1, 1, 2, 1);
    m->no_node = true;
    int slider = sb_glb_node(&s, true, "{\"name\":\"slider\",\"mesh\":%d,\"translation\":[-8,0,-4]}", s.n - 1);
    sb_glb_mesh *b = sb_glb_new_mesh(&s, 3);
    sb_glb_box(b, -3, 2.7, -0.3, 3, 3.3, 0.3);
    b->no_node = true;
    int turner = sb_glb_node(&s, true, "{\"name\":\"turner\",\"mesh\":%d,\"translation\":[0,0,6]}", s.n - 1);
    const float st[3] = {0, 4, 8}, sv[9] = {-8, 0, -4, 8, 0, -4, -8, 0, -4};
    float tt[5], tv[20];
    for (int k = 0; k < 5; k++) {   /* a quarter turn a key: slerp between them turns the short way */
        double a = k * SB_PI / 2;
        tt[k] = (float)(2 * k);
        tv[4 * k] = 0, tv[4 * k + 1] = (float)sin(a / 2), tv[4 * k + 2] = 0, tv[4 * k + 3] = (float)cos(a / 2);
    }
    int ast = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":3,\"type\":\"SCALAR\","
                                  "\"min\":[0],\"max\":[8]}", sb_glb_view(&s, st, sizeof st));
    int asv = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}",
                              sb_glb_view(&s, sv, sizeof sv));
    int att = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":5,\"type\":\"SCALAR\","
                                  "\"min\":[0],\"max\":[8]}", sb_glb_view(&s, tt, sizeof tt));
    int atv = sb_glb_accessor(&s, "{\"bufferView\":%d,\"componentType\":5126,\"count\":5,\"type\":\"VEC4\"}",
                              sb_glb_view(&s, tv, sizeof tv));
    sb_glb_top(&s, "\"animations\":[{\"name\":\"slide\",\"channels\":[{\"sampler\":0,\"target\":{\"node\":%d,"
                   "\"path\":\"translation\"}}],\"samplers\":[{\"input\":%d,\"output\":%d}]},{\"name\":\"turn\","
                   "\"channels\":[{\"sampler\":0,\"target\":{\"node\":%d,\"path\":\"rotation\"}}],\"samplers\":"
                   "[{\"input\":%d,\"output\":%d}]}]", slider, ast, asv, turner, att, atv);
    return write_scene(&s, dir, "movers",
                       "# movers: a still camera above the slider's track for the clips' 8 s\n"
                       "fov 60\n"
                       "look 0   0 16 -16    0 0 -3\n"
                       "look 8   0 16 -16    0 0 -3\n");
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: scenegen OUTDIR\n");
        return 2;
    }
    return gen_plane_box(argv[1]) | gen_plane_box_lamp(argv[1]) | gen_desert(argv[1]) | gen_towers(argv[1]) |
           gen_towers_night(argv[1]) | gen_street_lamps(argv[1]) | gen_overhangs(argv[1]) | gen_towers_draco(argv[1]) | gen_movers(argv[1]) |
           sb_conformance_write(argv[1]);
}
