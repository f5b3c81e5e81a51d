// expect: 6:13 array size must be a constant integer expression
#version 330
uniform int n;
out vec4 color;
void main() {
    float a[n];
    color = vec4(1.0);
}
