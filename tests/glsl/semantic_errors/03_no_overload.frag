// expect: 6:18 no matching overload for 'mix(vec3, float)'
#version 330
uniform vec3 a;
out vec4 color;
void main() {
    color = vec4(mix(a, 0.5), 1.0);
}
