// expect: 6:26 argument 2 of 'modf' is an 'out' parameter
#version 330
uniform float u;
out vec4 color;
void main() {
    color = vec4(modf(u, 1.0 + u));
}
