// csm_layer.geom - layered shadow pass: each caster is drawn once; every
// triangle is routed (gl_Layer) to each cascade whose map it touches.
layout(triangles) in;
layout(triangle_strip, max_vertices = 24) out;
in vec3 g_pos[];
flat in uint g_mask[];  // cascades this caster's bounds intersect (CPU culling)
void main() {
    int n = int(sb_info.x);
    for (int c = 0; c < n; c++) {
        if (((g_mask[0] >> uint(c)) & 1u) == 0u || sb_flags[c].x < 0.5) continue;
        vec4 p0 = sb_light_vp[c] * vec4(g_pos[0], 1.0);
        vec4 p1 = sb_light_vp[c] * vec4(g_pos[1], 1.0);
        vec4 p2 = sb_light_vp[c] * vec4(g_pos[2], 1.0);
        // skip triangles entirely outside one side of the map (w > 0: ortho, or a warp in front of its centre)
        if (p0.x > p0.w && p1.x > p1.w && p2.x > p2.w) continue;
        if (p0.x < -p0.w && p1.x < -p1.w && p2.x < -p2.w) continue;
        if (p0.y > p0.w && p1.y > p1.w && p2.y > p2.w) continue;
        if (p0.y < -p0.w && p1.y < -p1.w && p2.y < -p2.w) continue;
        gl_Layer = c; gl_Position = p0; SB_ALPHA_GS(0); EmitVertex();
        gl_Layer = c; gl_Position = p1; SB_ALPHA_GS(1); EmitVertex();
        gl_Layer = c; gl_Position = p2; SB_ALPHA_GS(2); EmitVertex();
        EndPrimitive();
    }
}
