float a;
#include "cycle_b.glsl"
