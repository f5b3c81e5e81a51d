#version 300 es
precision mediump float;

struct Wave {
    highp float amplitude;
    float frequency;
    vec2 direction;
};

uniform Wave u_waves[3];
uniform float u_time;
in vec2 v_texcoord;
out vec4 fragColor;

float height(vec2 p) {
    float h = 0.0;
    for (int i = 0; i < 3; i++) {
        Wave w = u_waves[i];
        h += w.amplitude * sin(dot(w.direction, p) * w.frequency + u_time);
    }
    return h;
}

void main() {
    float h = height(v_texcoord * 10.0);
    fragColor = vec4(vec3(0.1, 0.3, 0.6) + h * 0.2, 1.0);
}
