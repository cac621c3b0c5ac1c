// virtual_mark.comp - the pages the frame's visible pixels need: each pixel of the camera's depth (sky excluded),
// put back in the world, marks the page of its level holding it, and the neighbouring page where it lies within
// u_margin texels of the page's edge (the lookup's point is the marking's up to rounding). A point outside its
// level's window marks the next coarser level that holds it. One bit a page; a bit already set costs no atomic.
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 2) buffer SbPageRequests { uint sb_req[]; };   // level, row, column: a bit each
uniform sampler2D u_depth;
uniform mat4 u_inv_view_proj;
uniform float u_margin;

void sb_mark(int l, int x, int y) {
    uint i = uint((l * SB_PAGES + y) * SB_PAGES + x);
    uint bit = 1u << (i & 31u);
    if ((sb_req[i >> 5] & bit) == 0u) atomicOr(sb_req[i >> 5], bit);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = textureSize(u_depth, 0);
    if (px.x >= size.x || px.y >= size.y) return;
    float d = texelFetch(u_depth, px, 0).r;
    if (d >= 1.0) return;
    vec4 h = u_inv_view_proj * vec4((vec2(px) + 0.5) / vec2(size) * 2.0 - 1.0, d * 2.0 - 1.0, 1.0);
    vec3 p = h.xyz / h.w;
    vec2 lp = (u_vlight * vec4(p, 1.0)).xy;
    for (int l = sb_vlevel(p); l < SB_LEVELS; l++) {
        vec2 q = sb_vtexcoord(l, lp);
        ivec2 lo = ivec2(floor((q - u_margin) / float(SB_PAGE))), hi = ivec2(floor((q + u_margin) / float(SB_PAGE)));
        if (lo.x < 0 || lo.y < 0 || hi.x >= SB_PAGES || hi.y >= SB_PAGES) continue;
        for (int y = lo.y; y <= hi.y; y++)
            for (int x = lo.x; x <= hi.x; x++) sb_mark(l, x, y);
        return;
    }
}
