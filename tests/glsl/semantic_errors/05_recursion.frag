// expect: 6:27 recursion is not allowed: f -> g -> f
#version 330
out vec4 color;
float g(float x);
float f(float x) { return g(x) + 1.0; }
float g(float x) { return f(x * 0.5); }
void main() { color = vec4(f(1.0)); }
