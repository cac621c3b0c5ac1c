// vis_none.glsl - no shadows: everything is lit.
float sb_visibility(vec3 p, vec3 n, float view_z) { return 1.0; }
