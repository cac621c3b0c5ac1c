// virtual_common.glsl - the virtual shadow map's clipmap (virtual.c) as its page marking and its lookup both see
// it, so that a pixel looks up the page the marking asked for. Level l is a virtual map of SB_PAGES x SB_PAGES
// pages of SB_PAGE texels whose texel is u_vtexel0 * 2^l; its window (u_vwin[l], the light-space corner) is
// centred on the camera and snapped to whole pages. A point uses the finest level whose texel is no larger than
// its pixel's footprint (times 2^lod).
uniform mat4 u_vlight;              // origin-relative world -> light view (x, y across the light)
uniform vec3 u_veye;                // the frame's camera, origin-relative
uniform vec3 u_vfwd;                // ... and its forward axis
uniform float u_vfoot;              // world size of a pixel per unit of view depth, times 2^lod
uniform float u_vtexel0;            // level 0's texel, world units
uniform vec2 u_vwin[SB_LEVELS];     // each level's window corner in light space

int sb_vlevel(vec3 p) {
    float z = max(dot(p - u_veye, u_vfwd), 1e-6);
    return clamp(int(floor(log2(z * u_vfoot / u_vtexel0))), 0, SB_LEVELS - 1);
}
float sb_vtexel(int l) { return u_vtexel0 * exp2(float(l)); }
// texel coordinates of light-space point lp in level l's window
vec2 sb_vtexcoord(int l, vec2 lp) { return (lp - u_vwin[l]) / sb_vtexel(l); }
