// csm_depth.vert - per-cascade shadow pass: one cascade per draw.
layout(location = 0) in vec3 a_pos;
uniform int u_cascade;
void main() { gl_Position = sb_light_vp[u_cascade] * vec4(a_pos, 1.0); }
