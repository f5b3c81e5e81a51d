// expect: 5:5 'break' outside a loop or switch
#version 330
out vec4 color;
void main() {
    break;
    color = vec4(1.0);
}
