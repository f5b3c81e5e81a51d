// expect: 6:5 cannot assign to uniform 'u_time'
#version 330
uniform float u_time;
out vec4 color;
void main() {
    u_time = 1.0;
    color = vec4(u_time);
}
