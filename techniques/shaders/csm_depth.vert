// csm_depth.vert - per-cascade shadow pass: one cascade per draw.
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
uniform int u_cascade;
void main() {
    vec3 a_pos = sb_world(a_vertex);
    SB_ALPHA_VS();
    // a cascade flagged empty (SDSM on the GPU) renders nothing
    gl_Position = sb_flags[u_cascade].x < 0.5 ? vec4(2.0, 2.0, 2.0, 1.0) : sb_light_vp[u_cascade] * vec4(a_pos, 1.0);
}
