// csm_layer_vs.vert - layered shadow pass without a geometry shader
// (ARB_shader_viewport_layer_array): instance k goes to the k-th cascade in the mask.
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
layout(location = 5) in uint a_mask;   // cascades this caster's bounds intersect: per draw, at its baseInstance
void main() {
    vec3 a_pos = sb_world(a_vertex);
    SB_ALPHA_VS();
    int k = gl_InstanceID, c = 0;
    for (; c < 8; c++) {
        if (((a_mask >> uint(c)) & 1u) != 0u) {
            if (k == 0) break;
            k--;
        }
    }
    gl_Layer = c;
    gl_Position = sb_flags[c].x < 0.5 ? vec4(2.0, 2.0, 2.0, 1.0) : sb_light_vp[c] * vec4(a_pos, 1.0);
}
