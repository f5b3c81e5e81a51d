#version 330 core
out vec4 fragColor;
uniform float u_weights[5];
uniform vec2 u_resolution;

const float kernel[5] = float[5](0.0625, 0.25, 0.375, 0.25, 0.0625);
const vec3 colors[] = vec3[](vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, 1.0));

float[3] triple(float x) {
    return float[3](x, x * 2.0, x * 3.0);
}

float sum(float values[3]) {
    float s = 0.0;
    for (int i = 0; i < values.length(); i++) s += values[i];
    return s;
}

void main() {
    float[3] t = triple(0.1);
    float acc = 0.0;
    for (int i = 0; i < 5; ++i)
        acc += kernel[i] * u_weights[i];
    int idx = int(gl_FragCoord.x) % colors.length();
    fragColor = vec4(colors[idx] * (acc + sum(t)), 1.0);
}
