// csm_layer_gs.vert - layered shadow pass: positions go to the geometry shader.
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
layout(location = 5) in uint a_mask;   // cascades this caster's bounds intersect: per draw, at its baseInstance
out vec3 g_pos;
flat out uint g_mask;
void main() {
    vec3 a_pos = sb_world(a_vertex);
    g_pos = a_pos;
    g_mask = a_mask;
    SB_ALPHA_VS();
}
