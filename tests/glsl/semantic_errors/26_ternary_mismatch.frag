// expect: 6:18 the branches of '?:' have different types: 'vec3' and 'vec2'
#version 330
uniform bool b;
out vec4 color;
void main() {
    color = vec4(b ? vec3(1.0) : vec2(0.0), 1.0);
}
