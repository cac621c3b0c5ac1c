// common.glsl - prepended to every shadowbench shader after #version and defines.
#define SB_PI 3.14159265358979
