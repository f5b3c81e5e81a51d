float a;
#line 100
float b;
#line 7 3
int f = __FILE__; int l = __LINE__;
#include "line_inc.glsl"
float after;
