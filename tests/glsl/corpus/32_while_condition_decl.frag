#version 330 core
out vec4 fragColor;
uniform int u_steps;

void main() {
    int i = 0;
    float acc = 0.0;
    while (bool more = i < u_steps) {
        acc += 0.1;
        i++;
        if (!more) break;
    }
    for (int j = 0; bool go = j < 3; j++) {
        acc *= go ? 0.9 : 1.0;
    }
    fragColor = vec4(vec3(acc), 1.0);
}
