// expect: 6:5 repeated components
#version 330
out vec4 color;
void main() {
    vec3 a = vec3(0.0);
    a.xx = vec2(1.0);
    color = vec4(a, 1.0);
}
