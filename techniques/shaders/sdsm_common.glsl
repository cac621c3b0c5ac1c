// sdsm_common.glsl - SDSM's depth statistics (binding 1) and helpers.
layout(std430, binding = 1) buffer SbDepthStats {
    uint sb_zmin;           // ordered float bits of the nearest visible view depth
    uint sb_zmax;           // ... and the farthest
    uint sb_samples;        // visible (non-sky) pixels
    uint sb_pad;
    uint sb_hist[64];       // log-depth histogram over the camera's [near, far]
    uint sb_part_count[8];  // samples per partition
    uint sb_bounds[8][4];   // per partition: light-space x min, y min, x max, y max (ordered bits)
};
uniform float u_near;
uniform float u_far;

// floats as uints whose unsigned order is the float order (negative values too)
uint sb_order(float f) {
    uint b = floatBitsToUint(f);
    return (b & 0x80000000u) != 0u ? ~b : (b | 0x80000000u);
}
float sb_unorder(uint u) { return uintBitsToFloat((u & 0x80000000u) != 0u ? (u & 0x7fffffffu) : ~u); }

float sb_linear_depth(float d) {
    float z = 2.0 * d - 1.0;
    return 2.0 * u_near * u_far / ((u_far + u_near) - z * (u_far - u_near));
}

int sb_hist_bin(float z) {
    return clamp(int(64.0 * log(z / u_near) / log(u_far / u_near)), 0, 63);
}
