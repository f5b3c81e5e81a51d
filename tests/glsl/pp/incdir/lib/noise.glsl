#include "hash.glsl"
float noise(vec2 p) { return HASH(p); }
