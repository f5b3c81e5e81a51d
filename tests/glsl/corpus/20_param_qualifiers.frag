#version 330 core
out vec4 fragColor;
in vec2 v_texcoord;

void split(const in vec3 c, out float r, out float g, inout float b) {
    r = c.r;
    g = c.g;
    b += c.b;
}

void swap(inout vec2 a, inout vec2 b) {
    vec2 t = a;
    a = b;
    b = t;
}

void main() {
    float r, g, b = 0.5;
    split(vec3(v_texcoord, 0.25), r, g, b);
    vec2 x = vec2(r, g), y = vec2(b);
    swap(x, y);
    fragColor = vec4(x, y);
}
