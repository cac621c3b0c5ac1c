// moments.frag - filtered shadow-map formats: what the map stores per texel.
// SB_MAP_FORMAT 1 vsm: (z, z^2); 2 esm: exp(c z); 3 msm: (z, z^2, z^3, z^4) (4 moments).
uniform float u_exponent;
layout(location = 0) out vec4 o_moments;
void main() {
    SB_ALPHA_TEST();
    float z = gl_FragCoord.z;
#if SB_MAP_FORMAT == 1
    float dx = dFdx(z), dy = dFdy(z);
    o_moments = vec4(z, z * z + 0.25 * (dx * dx + dy * dy), 0.0, 0.0);
#elif SB_MAP_FORMAT == 2
    o_moments = vec4(exp(u_exponent * z), 0.0, 0.0, 0.0);
#else
    float z2 = z * z;
    o_moments = vec4(z, z2, z2 * z, z2 * z2);
#endif
}
