// vis_volumes.glsl - stencil shadow volumes: the final pass is drawn twice,
// stencil 0 (lit) and stencil != 0 (in shadow), each with its own u_lit.
uniform float u_lit;
float sb_visibility(vec3 p, vec3 n, float view_z) { return u_lit; }
