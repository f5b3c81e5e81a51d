#version 330 core
uniform int u_iterations;
uniform vec2 u_resolution;
out vec4 fragColor;

int classify(vec2 p) {
    if (p.x < 0.0) {
        if (p.y < 0.0) return 0;
        else return 1;
    } else if (p.y < 0.0) {
        return 2;
    } else {
        return 3;
    }
}

void main() {
    vec2 p = gl_FragCoord.xy / u_resolution * 2.0 - 1.0;
    int quadrant = classify(p);
    float v = 0.0;
    for (int i = 0; i < 16; i++) {
        if (i >= u_iterations) break;
        for (int j = 0; j < 4; j++) {
            if (j == quadrant) continue;
            switch (j) {
                case 0: v += 0.01; break;
                case 1: v += 0.02; break;
                default: { v -= 0.005; }
            }
        }
    }
    if (v < 0.0) discard;
    fragColor = vec4(vec3(v), 1.0);
    return;
}
