// expect: 5:18 undeclared function 'nosie'
#version 330
out vec4 color;
void main() {
    color = vec4(nosie(vec3(1.0)));
}
