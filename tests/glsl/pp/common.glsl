// Shared helpers, guarded.
#ifndef COMMON_GLSL
#define COMMON_GLSL
#define PI 3.14159265
float saturate(float x) { return clamp(x, 0.0, 1.0); }
#endif
