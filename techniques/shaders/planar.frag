// planar.frag - only what lies above the plane casts onto it.
in float v_side;
uniform float u_eps;
void main() {
    SB_ALPHA_TEST();
    if (v_side < u_eps) discard;
}
