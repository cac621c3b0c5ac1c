// depth.frag - depth only.
void main() { SB_ALPHA_TEST(); }
