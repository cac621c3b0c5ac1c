// lightgrid.glsl - a pixel's lamps, found by cluster (lightgrid.c): the cluster of its tile of
// gl_FragCoord and its view-depth slice, and that cluster's lamps (indices into the technique's records).
uniform usamplerBuffer u_grid_heads;   // per cluster: first item, count
uniform usamplerBuffer u_grid_items;   // lamp indices
uniform vec4 u_grid;                   // tile pixels, tiles across, tiles down, slices per log unit past near
uniform vec4 u_grid_zrow;              // the pass view's third row: z of an origin-relative point
uniform vec2 u_grid_near;              // the near plane, slices
// the cluster holding the pixel at p (origin-relative): its first item and count
uvec2 sb_grid_cell(vec3 p) {
    float depth = -(dot(u_grid_zrow.xyz, p) + u_grid_zrow.w);
    int s = int(clamp(floor(log(max(depth, u_grid_near.x) / u_grid_near.x) * u_grid.w), 0.0, u_grid_near.y - 1.0));
    ivec2 t = clamp(ivec2(gl_FragCoord.xy / u_grid.x), ivec2(0), ivec2(u_grid.yz) - 1);
    return texelFetch(u_grid_heads, (s * int(u_grid.z) + t.y) * int(u_grid.y) + t.x).xy;
}
int sb_grid_light(uint item) { return int(texelFetch(u_grid_items, int(item)).x); }
