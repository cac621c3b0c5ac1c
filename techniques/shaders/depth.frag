// depth.frag - depth only.
void main() {}
