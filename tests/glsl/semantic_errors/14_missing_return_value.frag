// expect: 5:5 function 'f' must return a value of type 'float'
#version 330
out vec4 color;
float f() {
    return;
}
void main() { color = vec4(f()); }
