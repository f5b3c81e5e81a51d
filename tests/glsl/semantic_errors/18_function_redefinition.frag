// expect: 5:1 redefinition of function 'f(float)'
#version 330
out vec4 color;
float f(float x) { return x; }
float f(float x) { return 2.0 * x; }
void main() { color = vec4(f(1.0)); }
