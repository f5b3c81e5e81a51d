// expect: 6:9 if condition must be a scalar bool, not 'float'
#version 330
uniform float u;
out vec4 color;
void main() {
    if (u) {
        color = vec4(1.0);
    }
}
