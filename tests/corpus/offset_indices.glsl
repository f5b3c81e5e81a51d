// Loops whose array index is offset from the loop variable, neighbours guarded by the index,
// and a small 3x3 kernel over an array of vec2.
#version 330
in vec3 v_objectPosition;
in vec2 v_texcoord;
in vec3 v_normal;
out vec4 fragColor;

void main() {
    vec2 taps[9];
    for (int i = 0; i < 9; i++) {
        taps[i] = sin(v_objectPosition.xy * float(i + 1) * 1.7);
    }
    vec2 sum = vec2(0.0);
    for (int i = 0; i < 9; i++) sum += taps[i - 1 + 1];
    for (int i = 1; i < 9; i++) sum += 0.5 * taps[i - 1];
    for (int i = 0; i < 8; i++) sum -= 0.25 * taps[i + 1];
    vec2 edges = vec2(0.0);
    for (int i = 0; i < 9; i++) {
        if (i > 0) edges += taps[i - 1];
        if (i < 8) edges -= taps[i + 1];
        edges += i > 0 ? taps[i - 1] * 0.1 : taps[0];
    }
    float k[3] = float[3](0.25, 0.5, 0.25);
    float blur = 0.0;
    for (int j = -1; j <= 1; j++) blur += k[j + 1] * cos(dot(v_normal, vec3(float(j))));
    fragColor = vec4(0.5 + 0.05 * sum, 0.5 + 0.02 * edges.x + 0.1 * blur, 1.0);
}
