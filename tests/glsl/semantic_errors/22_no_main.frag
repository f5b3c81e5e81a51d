// expect: 3:1 no 'main' function
#version 330
out vec4 color;
void helper() { color = vec4(1.0); }
