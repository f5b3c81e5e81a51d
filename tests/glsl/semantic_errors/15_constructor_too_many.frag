// expect: 5:34 too many arguments to the 'vec3' constructor
#version 330
out vec4 color;
void main() {
    vec3 a = vec3(1.0, 2.0, 3.0, 4.0);
    color = vec4(a, 1.0);
}
