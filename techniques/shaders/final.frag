// final.frag - shared camera pass. The technique's GLSL, linked before this,
// defines sb_visibility(): 1 lit ... 0 shadowed. Timed frames write the shaded
// colour alone, as an engine's pass would; the evaluation variant (SB_EVAL,
// untimed) also writes the visibility, unshaded, that error metrics and
// images read, the position and normal targets, and the base colour with the
// direct light's N.L factor (the shaded frame the perceptual error compares).
in vec3 v_pos;
in vec3 v_nrm;
in float v_view_z;
uniform vec4 u_shade_light;   // xyz toward the sun (w 0), or a point light's position (w 1)
uniform vec2 u_shade_more;    // x: the lamp's range (0: none); y: 1 in a pass adding a further light (no ambient)
uniform vec4 u_shade_spot;    // a spot light: xyz the way it shines, w 1 - cos of its cone (0: none)
flat in vec4 v_color;          // the draw's colour
layout(location = 0) out vec4 o_color;
#ifdef SB_EVAL
layout(location = 1) out float o_vis;
layout(location = 2) out vec4 o_pos;   // origin-relative position, shadow texels per pixel
layout(location = 3) out vec4 o_aux;   // geometric normal (facing the viewer), cascade index
layout(location = 4) out vec4 o_base;  // base colour, and N.L of the light scored (range and cone applied)
#endif
void main() {
    SB_ALPHA_TEST();
    vec3 n = normalize(v_nrm);
#ifdef SB_LIGHT_LOOP
    // every lamp in one pass (the atlas): the technique's GLSL gives sb_light_count(), sb_light_at(i) (xyz the
    // lamp, w its range, 0: none), sb_light_cone(i) and sb_visibility_at(i, p, n). An evaluation pass holds the one lamp it scores.
    float lit = 0.0, vis = 1.0, nl = 0.0;
#ifdef SB_LIGHT_GRID
    // the lamps of the pixel's cluster (lightgrid.glsl), in the records' order, not every lamp in view
    uvec2 cell = sb_grid_cell(v_pos);
    for (uint j = 0u; j < cell.y; j++) {
        int i = sb_grid_light(cell.x + j);
#else
    for (int i = 0; i < sb_light_count(); i++) {
#endif
        vec4 l = sb_light_at(i);
        vec3 d = l.xyz - v_pos;
        float dist = length(d), ndl = dot(n, d / max(dist, 1e-20));
        vec4 cone = sb_light_cone(i);   // a spot: the way it shines, 1 - cos of its cone (w 0: none)
        if ((l.w > 0.0 && dist > l.w) || ndl <= 0.0 || (cone.w > 0.0 && dot(-d / dist, cone.xyz) < 1.0 - cone.w)) continue;
        vis = sb_visibility_at(i, v_pos, n);
        nl = ndl;
        lit += SB_DIRECT * ndl * vis;
    }
    o_color = vec4(v_color.rgb * (SB_AMBIENT + lit), 1.0);
#else
    vec3 L = u_shade_light.w > 0.5 ? normalize(u_shade_light.xyz - v_pos) : u_shade_light.xyz;
    float ndl = dot(n, L);
    if (u_shade_light.w > 0.5 && u_shade_more.x > 0.0 && length(u_shade_light.xyz - v_pos) > u_shade_more.x) ndl = 0.0;
    if (u_shade_light.w > 0.5 && u_shade_spot.w > 0.0 &&
        dot(normalize(v_pos - u_shade_light.xyz), u_shade_spot.xyz) < 1.0 - u_shade_spot.w) ndl = 0.0;
    float vis = sb_visibility(v_pos, n, v_view_z);
    float nl = max(ndl, 0.0);
    o_color = vec4(v_color.rgb * ((1.0 - u_shade_more.y) * SB_AMBIENT + SB_DIRECT * nl * vis), 1.0);
#endif
#ifdef SB_EVAL
    o_vis = vis;
    vec3 ng = normalize(cross(dFdx(v_pos), dFdy(v_pos)));
    if (dot(ng, n) < 0.0) ng = -ng;
    o_pos = vec4(v_pos, sb_out_texel_px);
    o_aux = vec4(ng, sb_out_cascade);
    o_base = vec4(v_color.rgb, nl);
#endif
}
