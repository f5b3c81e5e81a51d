// expect: 6:11 redefinition of 'x'
#version 330
out vec4 color;
void main() {
    float x = 1.0;
    float x = 2.0;
    color = vec4(x);
}
