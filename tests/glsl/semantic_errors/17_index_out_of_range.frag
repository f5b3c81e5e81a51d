// expect: 7:26 index 4 is out of range for 'float[4]'
#version 330
const int N = 4;
uniform float weights[N];
out vec4 color;
void main() {
    color = vec4(weights[N]);
}
