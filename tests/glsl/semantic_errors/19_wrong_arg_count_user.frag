// expect: 5:28 no matching overload for 'f(float, float)'
#version 330
out vec4 color;
float f(float x) { return x; }
void main() { color = vec4(f(1.0, 2.0)); }
