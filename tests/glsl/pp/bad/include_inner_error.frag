// ERROR inc/inc_error.glsl:2:1 #error inside the include
#include "inc/inc_error.glsl"
