// expect: 5:25 undeclared identifier 'foo'
#version 330
out vec4 color;
void main() {
    color = vec4(1.0) * foo;
}
