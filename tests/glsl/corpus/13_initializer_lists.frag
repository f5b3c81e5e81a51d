#version 450 core
layout(location = 0) out vec4 fragColor;

struct Sample {
    vec2 offset;
    float weight;
};

const Sample taps[3] = {
    { vec2(-1.0, 0.0), 0.25 },
    { vec2(0.0, 0.0), 0.5 },
    { vec2(1.0, 0.0), 0.25 },
};

const mat2 rot = { { 0.0, 1.0 }, { -1.0, 0.0 } };
const vec3 base = { 0.2, 0.3, 0.4 };

void main() {
    vec2 p = gl_FragCoord.xy * 0.01;
    float acc = 0.0;
    for (int i = 0; i < 3; ++i) {
        vec2 q = rot * (p + taps[i].offset);
        acc += taps[i].weight * sin(q.x) * cos(q.y);
    }
    float arr[2] = { acc, 1.0 - acc };
    fragColor = vec4(base + vec3(arr[0]), arr[1]);
}
