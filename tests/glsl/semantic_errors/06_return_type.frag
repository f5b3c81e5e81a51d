// expect: 5:12 cannot return a value of type 'vec3' from function 'f' returning 'float'
#version 330
out vec4 color;
float f() {
    return vec3(1.0);
}
void main() { color = vec4(f()); }
