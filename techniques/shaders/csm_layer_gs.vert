// csm_layer_gs.vert - layered shadow pass: positions go to the geometry shader.
layout(location = 0) in vec3 a_pos;
out vec3 g_pos;
void main() {
    g_pos = a_pos;
    SB_ALPHA_VS();
}
