// vis_lamps.glsl - the per-light techniques' lamps in one camera pass (lamp.c, grid=on with --lights): each
// lamp's record in the texture buffer u_lights, SB_LAMP_REC texels a lamp: the lamp and its range (0: none);
// near, far and the map's texels; a spot's way and 1 - cos of its cone (w 0: a point light). Lamp i's maps are
// layers of u_map from i times the kind's maps on, read by the kind's lookup (vis_cube.glsl, vis_dpsm.glsl, built
// with SB_LIGHT_LOOP), which gives sb_visibility_at(i, p, n).
uniform samplerBuffer u_lights;
#define SB_LAMP_REC 3
vec4 sb_light_at(int i) { return texelFetch(u_lights, SB_LAMP_REC * i); }
vec3 sb_lamp_clip(int i) { return texelFetch(u_lights, SB_LAMP_REC * i + 1).xyz; }
vec4 sb_light_cone(int i) { return texelFetch(u_lights, SB_LAMP_REC * i + 2); }
