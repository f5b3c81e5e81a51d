// ERROR 3:10 cannot find include file 'nope/missing.glsl'
#version 330
#include "nope/missing.glsl"
