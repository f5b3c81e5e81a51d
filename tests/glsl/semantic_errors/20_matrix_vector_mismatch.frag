// expect: 6:18 cannot multiply 'mat3' by 'vec4'
#version 330
uniform mat3 m;
out vec4 color;
void main() {
    color = vec4(m * vec4(1.0));
}
