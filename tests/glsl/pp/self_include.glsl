#ifndef SELF_INCLUDE
#define SELF_INCLUDE
#include "self_include.glsl"
float once;
#endif
