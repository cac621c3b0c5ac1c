/* conformance.h - the conformance set: one small scene per glTF feature,
 * written by scenegen (scenes/conformance.c) with scenes/glb.c, each with an
 * answer that follows from its geometry. Every scene stands on a 40 x 40 slab
 * (top at y = 0) under the sun SB_CONF_SUN_AZ/EL; what casts floats at height
 * SB_CONF_H, so a floor point p is shadowed when p + t * sun (at y = SB_CONF_H,
 * for flat casters) falls inside an opaque part. The tests
 * (tests/integration/test_conformance.c) check the reference's rays against
 * these answers and the rasterized techniques against the reference.
 *
 *   conf-double-sided  sheet A (doubleSided) and sheet B (single-sided), both
 *                      facing down: A casts and is seen from above, B neither
 *   conf-blend         BLEND panes of alpha 0.3 (A) and 0.8 (B), facing up:
 *                      --blend-casters mask: B casts; opaque: both; none: neither
 *   conf-alpha-card    a MASK card with a 4x4 checker alpha texture repeated
 *                      twice by KHR_texture_transform: 1-unit opaque cells where
 *                      floor(x + 4) + floor(z + 4) is even; a lamp above it
 *                      for the point-light techniques
 *   conf-skin          an arm of two segments skinned to two joints; the second
 *                      joint's own rotation (90 degrees about z) stands segment
 *                      two up; --pose 0 (its animation) lays it flat again
 *   conf-instanced     one box drawn five times by EXT_mesh_gpu_instancing
 *   conf-quantized     a box with KHR_mesh_quantization int16 positions, and a
 *                      box whose positions come only from a sparse accessor
 *   towers-draco       the towers scene with every mesh Draco-compressed */
#pragma once

#define SB_CONF_SUN_AZ 30.0
#define SB_CONF_SUN_EL 60.0
#define SB_CONF_H 3.0

/* conf-double-sided / conf-blend: two rectangles at height SB_CONF_H (x0, x1, z0, z1) */
#define SB_CONF_RECT_A {-6.0, -2.0, -2.0, 2.0}
#define SB_CONF_RECT_B {2.0, 6.0, -2.0, 2.0}
#define SB_CONF_BLEND_ALPHA_A 0.3
#define SB_CONF_BLEND_ALPHA_B 0.8

/* conf-alpha-card: the card's half size (it spans -4..4 in x and z), and a lamp above it (the
 * lamp techniques' shadows of the checker: cells twice as large on the floor, from y = 6) */
#define SB_CONF_CARD 4.0
#define SB_CONF_CARD_LAMP_X 0.3
#define SB_CONF_CARD_LAMP_Y 6.0
#define SB_CONF_CARD_LAMP_Z 0.2

/* conf-skin: segment one x 0..4 and segment two x 4..8, cross-section 1 x 1 around (y 3, z 0);
 * the second joint sits at (4, 3, 0) */
#define SB_CONF_ARM_LEN 4.0

/* conf-instanced: box (x, z) footprint 1 x 1 centred on x = -8, -4, 0, 4, 8 at z = 0, height 1 + k / 2 */
#define SB_CONF_INSTANCES 5

/* conf-lamp-wall: a single-sided wall in the plane x = 0 (y 0.5..3.5, z -2..2) facing -x, away
 * from the sun (which is toward +x), and a lamp on its front side at (-2, 2, 0): the wall
 * casts the lamp's shadow onto the floor at x > 0 and no shadow of the sun. */
#define SB_CONF_LAMP_X (-2.0)
#define SB_CONF_LAMP_Y 2.0

/* conf-quantized: box 1 spans x -6..-2, y 0..2, z -2..2; box 2 (sparse) x 2..6, y 0..2, z -2..2 */

/* Writes the conformance scenes and their paths into dir (0 on success). */
int sb_conformance_write(const char *dir);
