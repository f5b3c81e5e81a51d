#version 330 core
out vec4 fragColor;
uniform float u_time;

void main() {
    float a = 1.0, b = 2.0, c = 3.0;
    a = b = c;
    a += b -= c *= 2.0;
    float t = u_time > 1.0 ? 0.1 : u_time > 0.5 ? 0.2 : 0.3;
    float s = (u_time > 1.0 ? a : b) * c;
    bool k = (a > b) == (b > c);
    float q = (a, b, c);
    float r = a - (b - c) - (a + b);
    float x = a / (b * c) / (a / b);
    float y = -(a + b) * -c;
    vec2 v = vec2(1.0, 2.0);
    float w = (v * 2.0).x + (-v).y + (v.xy++).x;
    fragColor = vec4(t, s, float(k) + q, r + x + y + w);
}
