// vis_csm.glsl - shadow lookup for every shadow-map technique (sm is one cascade).
// SB_FILTER: 0 none (1 nearest tap), 1 hw (bilinear 2x2 compare), 2 pcf3, 3 pcf5, 4 poisson16,
//           5 pcss (blocker search, then a Poisson PCF kernel as wide as the penumbra)
// SB_SELECT: 0 interval (by view depth), 1 map (first map that contains the point)
// SB_MAPS: the maps in the block; SB_WARP: 1 when a map may be perspective (LiSPSM, TSM,
// PSM), so the lookup measures its local texel size; SB_BLEND: 1 when u_blend > 0.
// Each is fixed when the program is made, so a frame pays only for what its
// technique uses: the loops over the maps unroll, and a plain orthographic
// lookup has neither the warp's three extra projections nor a second lookup.
uniform sampler2DArrayShadow u_shadow;
uniform float u_bias;       // constant bias, in shadow texels
uniform float u_normal;     // normal offset, in shadow texels
uniform float u_blend;      // blend band, fraction of a cascade's depth range
uniform vec3 u_light;       // toward the light
uniform vec2 u_texel;       // 1 / shadow map size
uniform sampler2DArray u_depth_raw;     // the same map without comparison (PCSS blocker search)
uniform float u_sun_tan;                // tan of the sun's angular diameter (PCSS)

const vec2 sb_disk[16] = vec2[](
    vec2(-0.942, -0.399), vec2(0.946, -0.769), vec2(-0.094, -0.929), vec2(0.345, 0.294),
    vec2(-0.916, 0.458), vec2(-0.815, -0.879), vec2(-0.383, 0.277), vec2(0.975, 0.756),
    vec2(0.443, -0.975), vec2(0.537, -0.474), vec2(-0.265, -0.419), vec2(0.792, 0.191),
    vec2(-0.242, 0.997), vec2(-0.814, 0.914), vec2(0.200, 0.786), vec2(0.144, -0.141));

// Receiver-plane depth (Isidoro 2006), from the geometric normal rather than screen derivatives: the
// receiver's depth change per unit of map uv. A tap `off` texels away compares against the receiver's
// plane there, not the centre's depth, so a kernel wider than a texel (pcf3, pcf5, poisson16, pcss) does
// not shadow a sloped receiver with itself. Zero for warped maps (their depth is not linear in uv).
vec2 sb_rp_grad = vec2(0.0);

float sb_tap(vec3 c, float layer, vec2 off) {
    vec2 duv = off * u_texel;
    return texture(u_shadow, vec4(c.xy + duv, layer, c.z + dot(sb_rp_grad, duv)));
}

// The plane's depth gradient in an orthographic map k: two tangents of the receiver carried by the map's
// linear part, solved for d(depth)/d(uv); bounded to a slope of 80 degrees (grazing receivers).
vec2 sb_receiver_grad(int k, vec3 n, float texel) {
    mat3 a = mat3(sb_shadow_mat[k]);
    vec3 t1 = normalize(cross(n, abs(n.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    vec3 j1 = a * t1, j2 = a * cross(n, t1);
    mat2 m = mat2(j1.xy, j2.xy);
    float det = determinant(m);
    float cap = 5.67 * texel / (sb_cascade[k].w * u_texel.x);
    if (abs(det) < 1e-20) return vec2(0.0);
    vec2 g = transpose(inverse(m)) * vec2(j1.z, j2.z);
    float len = length(g);
    return len > cap ? g * (cap / len) : g;
}

// Filtered formats (SB_MAP_FORMAT 1 vsm, 2 esm, 3 msm): visibility from the blurred moments.
uniform sampler2DArray u_moments;
uniform float u_bleed;      // light-bleeding reduction (vsm, msm)
uniform float u_exponent;   // esm

float sb_reduce_bleed(float p) { return clamp((p - u_bleed) / (1.0 - u_bleed), 0.0, 1.0); }

float sb_filtered(vec3 c, float layer) {
    vec4 m = texture(u_moments, vec3(c.xy, layer));
    float z = c.z;
#if SB_MAP_FORMAT == 1
    // Chebyshev's one-sided bound (Donnelly & Lauritzen 2006)
    if (z <= m.x) return 1.0;
    float var = max(m.y - m.x * m.x, 1e-7);
    float d = z - m.x;
    return sb_reduce_bleed(var / (var + d * d));
#elif SB_MAP_FORMAT == 2
    // exp(c (occluder - receiver)) (Annen et al. 2008)
    return clamp(m.x * exp(-u_exponent * z), 0.0, 1.0);
#else
    // four moments, Hamburger bound (Peters & Klein 2015): a Cholesky solve of the 3x3
    // Hankel system, the roots of the resulting quadratic, and the bound from them
    vec4 b = mix(m, vec4(0.5, 0.5, 0.5, 0.5), 3e-5);
    float l32d22 = -b.x * b.y + b.z;
    float d22 = -b.x * b.x + b.y;
    float var2 = -b.y * b.y + b.w;
    float d33d22 = var2 * d22 - l32d22 * l32d22;
    float inv_d22 = 1.0 / d22;
    float l32 = l32d22 * inv_d22;
    vec3 q = vec3(1.0, z, z * z);
    q.y -= b.x;
    q.z -= b.y + l32 * q.y;
    q.y *= inv_d22;
    q.z *= d22 / d33d22;
    q.y -= l32 * q.z;
    q.x -= dot(q.yz, b.xy);
    float pp = q.y / q.z, qq = q.x / q.z;
    float r = sqrt(max(pp * pp * 0.25 - qq, 0.0));
    float z2 = -pp * 0.5 - r, z3 = -pp * 0.5 + r;
    vec4 sw = z3 < z ? vec4(z2, z, 1.0, 1.0) : (z2 < z ? vec4(z, z2, 0.0, 1.0) : vec4(0.0));
    float quotient = (sw.x * z3 - b.x * (sw.x + z3) + b.y) / ((z3 - sw.y) * (z - z2));
    float shadow = clamp(sw.z + sw.w * quotient, 0.0, 1.0);
    return sb_reduce_bleed(1.0 - shadow);
#endif
}

vec2 sb_map_uv(int k, vec3 p) {
    vec4 h = sb_shadow_mat[k] * vec4(p, 1.0);
    return h.xy / h.w;
}

float sb_lookup(int k, vec3 p, vec3 n) {
    float texel = sb_cascade[k].z;
#if SB_WARP
    bool warped = sb_flags[k].y > 0.5;
    if (warped) {
        // a warped map's texels differ across it: measure the local texel size (world units)
        // across the light direction, so bias and normal offset scale with it (Novosibirsk fix (d))
        vec3 t1 = normalize(cross(u_light, abs(u_light.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
        vec3 t2 = cross(u_light, t1);
        vec2 uv0 = sb_map_uv(k, p);
        float d1 = length(sb_map_uv(k, p + t1 * texel) - uv0), d2 = length(sb_map_uv(k, p + t2 * texel) - uv0);
        float texels_per_unit = max(d1, d2) / u_texel.x / texel;
        texel = 1.0 / max(texels_per_unit, 1e-20);
    }
#else
    const bool warped = false;
#endif
    float cosl = clamp(dot(n, u_light), -1.0, 1.0);
    vec3 q = p + n * (u_normal * texel * sqrt(1.0 - cosl * cosl));
    // a warped map's depth is not linear in distance: bias in world space instead (toward the light)
    if (warped) q += u_light * (u_bias * texel);
    vec4 h = sb_shadow_mat[k] * vec4(q, 1.0);   // projective for warped (LiSPSM) maps
    vec3 c = h.xyz / h.w;
    if (c.x < 0.0 || c.x > 1.0 || c.y < 0.0 || c.y > 1.0 || c.z > 1.0) return 1.0;
    if (!warped) c.z -= u_bias * texel / sb_cascade[k].w;
    float layer = float(k);
#if SB_MAP_FORMAT == 0 && SB_FILTER >= 2
    sb_rp_grad = warped ? vec2(0.0) : sb_receiver_grad(k, n, texel);
#endif
#if SB_MAP_FORMAT != 0
    return sb_filtered(c, layer);
#elif SB_FILTER == 0 || SB_FILTER == 1
    return sb_tap(c, layer, vec2(0.0));
#elif SB_FILTER == 2 || SB_FILTER == 3
    const int r = SB_FILTER == 2 ? 1 : 2;
    float sum = 0.0;
    for (int y = -r; y <= r; y++)
        for (int x = -r; x <= r; x++) sum += sb_tap(c, layer, vec2(x, y));
    return sum / float((2 * r + 1) * (2 * r + 1));
#elif SB_FILTER == 4
    float sum = 0.0;
    for (int i = 0; i < 16; i++) sum += sb_tap(c, layer, sb_disk[i] * 1.5);
    return sum / 16.0;
#else
    // PCSS (Fernando 2005) for a directional light: the penumbra is
    // (receiver - blocker distance) x tan(sun diameter); depths are linear in
    // an orthographic map, so distances are depth differences x the depth range.
    float range = sb_cascade[k].w;
    float search = max(u_sun_tan * range * 0.25 / texel, 1.0);    // texels: blockers up to a quarter range away
    search = min(search, 32.0);
    float blockers = 0.0, depth_sum = 0.0;
    for (int i = 0; i < 16; i++) {
        float d = texture(u_depth_raw, vec3(c.xy + sb_disk[i] * search * u_texel, layer)).r;
        if (d < c.z) { blockers += 1.0; depth_sum += d; }
    }
    if (blockers == 0.0) return 1.0;
    float penumbra = (c.z - depth_sum / blockers) * range * u_sun_tan / texel;   // texels
    float radius = clamp(penumbra * 0.5, 0.5, 32.0);
    float sum = 0.0;
    for (int i = 0; i < 16; i++) sum += sb_tap(c, layer, sb_disk[i] * radius);
    return sum / 16.0;
#endif
}

// The first rendered map holding the point (-1: none), without a branch: the
// maps are tried from the last to the first and the last match kept.
int sb_select(vec3 p, float view_z) {
    int k = -1;
    for (int i = SB_MAPS - 1; i >= 0; i--) {
#if SB_SELECT == 0
        bool in_map = view_z <= sb_cascade[i].y;
#else
        vec4 h = sb_shadow_mat[i] * vec4(p, 1.0);
        vec3 c = h.xyz / h.w;
        vec2 m = 2.0 * u_texel;   // keep filter taps inside the map
        // h.w > 0: in front of a perspective map's centre (PSM's cube faces)
        bool in_map = h.w > 0.0 && all(greaterThanEqual(c.xy, m)) && all(lessThanEqual(c.xy, 1.0 - m)) &&
                      c.z <= 1.0 && c.z >= 0.0;
#endif
        if (in_map && sb_flags[i].x > 0.5) k = i;
    }
    return k;
}

float sb_visibility(vec3 p, vec3 n, float view_z) {
    int k = sb_select(p, view_z);
#ifdef SB_EVAL
    // resolution: texels of the selected map per screen pixel (outside any branch, so
    // the derivatives are in uniform control flow)
    // (the map's size from the texture: the evaluation variant reads no uniform the timed one lacks)
#if SB_MAP_FORMAT != 0
    vec2 size = vec2(textureSize(u_moments, 0).xy);
#else
    vec2 size = vec2(textureSize(u_shadow, 0).xy);
#endif
    vec4 h = sb_shadow_mat[max(k, 0)] * vec4(p, 1.0);
    vec2 uv = h.xy / h.w * size;
    SB_EVAL_OUT(k < 0 ? -1.0 : max(length(dFdx(uv)), length(dFdy(uv))), float(k));
#endif
    if (k < 0) return 1.0;
    float v = sb_lookup(k, p, n);
#if SB_BLEND
    if (k + 1 < SB_MAPS && sb_flags[min(k + 1, SB_MAPS - 1)].x > 0.5) {
        float band = u_blend * (sb_cascade[k].y - sb_cascade[k].x);
        float start = sb_cascade[k].y - band;
        if (view_z > start) v = mix(v, sb_lookup(k + 1, p, n), clamp((view_z - start) / band, 0.0, 1.0));
    }
#endif
    return v;
}
