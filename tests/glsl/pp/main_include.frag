#version 330 core
#include "common.glsl"
#include "common.glsl"
#include <lib/noise.glsl>
out vec4 color;
void main() { color = vec4(saturate(PI), noise(gl_FragCoord.xy), __FILE__, 1.0); }
