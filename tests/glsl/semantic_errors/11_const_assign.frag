// expect: 6:5 cannot assign to constant 'K'
#version 330
out vec4 color;
const float K = 2.0;
void main() {
    K = 3.0;
    color = vec4(K);
}
