// expect: 6:5 cannot assign to input 'v_normal'
#version 330
in vec3 v_normal;
out vec4 color;
void main() {
    v_normal = normalize(v_normal);
    color = vec4(v_normal, 1.0);
}
