// vis_atlas.glsl - lamps' shadows from one depth atlas (atlas.c): each lamp six
// perspective tiles (a cube's faces) or two paraboloids (dpsm's), each a square
// of the atlas, its record in the texture buffer u_lights, SB_LREC texels a
// lamp: the lamp and its range; near, far, tile texels (0: no tiles, lit) and
// kind (0 cube, 1 dpsm, 2 a spot's one tile); the tiles' corners and sizes in
// atlas UV; the perspective tiles' matrices; at 32, a spot's cone. The lookups are cube's and dpsm's (bias and normal offset in
// texels of the tile at the point's distance), clamped half a texel inside the
// tile. SB_FILTER: 0 none, 1 hw (bilinear compare).
uniform sampler2DShadow u_atlas;
uniform samplerBuffer u_lights;
uniform int u_count;
uniform float u_bias, u_normal;
#define SB_LREC 36

int sb_light_count() { return u_count; }
vec4 sb_light_at(int i) { return texelFetch(u_lights, SB_LREC * i); }
#if SB_ATLAS_SPOTS
vec4 sb_light_cone(int i) { return texelFetch(u_lights, SB_LREC * i + 32); }
#else
vec4 sb_light_cone(int i) { return vec4(0.0); }   // no spot among the run's lamps
#endif

#if SB_ATLAS_DPSM
// dpsm's lookup in the lamp's two tiles: its frame x = +X, y = +Z, z = -Y (the front hemisphere looks down)
const mat3 sb_lamp_frame = mat3(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0);
float sb_paraboloid_at(int b, vec3 lamp, vec4 a, vec3 p, vec3 n) {
    vec3 dw = p - lamp;
    float dist = length(dw);
    float texel = 2.0 * dist / a.z;
    float cosl = clamp(dot(n, -dw / max(dist, 1e-20)), -1.0, 1.0);
    vec3 v = sb_lamp_frame * (dw + n * (u_normal * texel * sqrt(1.0 - cosl * cosl)));
    int face = v.z >= 0.0 ? 0 : 1;
    v.z = abs(v.z);
    float len = length(v);
    vec3 d = v / max(len, 1e-20);
    vec2 uv = clamp(d.xy / (1.0 + d.z) * 0.5 + 0.5, 0.5 / a.z, 1.0 - 0.5 / a.z);
    float ref = (len - u_bias * texel - a.x) / (a.y - a.x);
    if (ref >= 1.0) return 1.0;
    vec4 r = texelFetch(u_lights, b + 2 + face);
    return texture(u_atlas, vec3(r.xy + uv * r.z, ref));
}

#endif
#if SB_ATLAS_SPOTS
// a spot's one perspective tile down its cone: the reference depth is the point's depth along the cone's axis
float sb_spot_at(int b, int i, vec3 lamp, vec4 a, vec3 p, vec3 n) {
    vec4 cone = sb_light_cone(i);
    vec3 d = p - lamp;
    float depth = dot(d, cone.xyz);
    if (depth <= 0.0) return 1.0;
    float half_w = depth * sqrt(max(1.0 - (1.0 - cone.w) * (1.0 - cone.w), 0.0)) / max(1.0 - cone.w, 1e-6);
    float texel = 2.0 * half_w / a.z;   // the tile's texel at that depth
    float dist = length(d);
    float cosl = clamp(dot(n, -d / max(dist, 1e-20)), -1.0, 1.0);
    vec3 dq = d + n * (u_normal * texel * sqrt(1.0 - cosl * cosl));
    float axis = dot(dq, cone.xyz) - u_bias * texel;
    if (axis >= a.y) return 1.0;
    float z = (a.y + a.x) / (a.y - a.x) - 2.0 * a.y * a.x / ((a.y - a.x) * max(axis, a.x));
    int m = b + 8;
    vec4 c = mat4(texelFetch(u_lights, m), texelFetch(u_lights, m + 1), texelFetch(u_lights, m + 2),
                  texelFetch(u_lights, m + 3)) * vec4(lamp + dq, 1.0);
    vec2 uv = clamp(c.xy / c.w * 0.5 + 0.5, 0.5 / a.z, 1.0 - 0.5 / a.z);
    vec4 r = texelFetch(u_lights, b + 2);
    return texture(u_atlas, vec3(r.xy + uv * r.z, 0.5 * z + 0.5));
}
#endif

float sb_visibility_at(int i, vec3 p, vec3 n) {
    int b = SB_LREC * i;
    vec4 lamp = texelFetch(u_lights, b), a = texelFetch(u_lights, b + 1);   // a: near, far, tile texels, kind
    if (a.z <= 0.0) return 1.0;
    // the lookups the run needs, chosen when the program is built (a branch a lamp doubled llvmpipe's pass)
#if SB_ATLAS_SPOTS
    if (a.w > 1.5) return sb_spot_at(b, i, lamp.xyz, a, p, n);
#endif
#if SB_ATLAS_DPSM
    return sb_paraboloid_at(b, lamp.xyz, a, p, n);
#else
    vec3 d = p - lamp.xyz;
    float dist = length(d);
    float texel = 2.0 * max(abs(d.x), max(abs(d.y), abs(d.z))) / a.z;
    float cosl = clamp(dot(n, -d / max(dist, 1e-20)), -1.0, 1.0);
    vec3 dq = d + n * (u_normal * texel * sqrt(1.0 - cosl * cosl));
    vec3 ad = abs(dq);
    int face = ad.x >= ad.y && ad.x >= ad.z ? (dq.x > 0.0 ? 0 : 1) : ad.y >= ad.z ? (dq.y > 0.0 ? 2 : 3) : (dq.z > 0.0 ? 4 : 5);
    float axis = max(ad.x, max(ad.y, ad.z));
    axis -= u_bias * 2.0 * axis / a.z;
    if (axis >= a.y) return 1.0;
    float z = (a.y + a.x) / (a.y - a.x) - 2.0 * a.y * a.x / ((a.y - a.x) * max(axis, a.x));
    int m = b + 8 + 4 * face;
    vec4 c = mat4(texelFetch(u_lights, m), texelFetch(u_lights, m + 1), texelFetch(u_lights, m + 2),
                  texelFetch(u_lights, m + 3)) * vec4(lamp.xyz + dq, 1.0);
    vec2 uv = clamp(c.xy / c.w * 0.5 + 0.5, 0.5 / a.z, 1.0 - 0.5 / a.z);
    vec4 r = texelFetch(u_lights, b + 2 + face);
    return texture(u_atlas, vec3(r.xy + uv * r.z, 0.5 * z + 0.5));
#endif
}
