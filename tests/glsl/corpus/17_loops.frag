#version 330 core
uniform float u_time;
uniform vec2 u_resolution;
out vec4 fragColor;

float march(vec3 ro, vec3 rd) {
    float t = 0.0;
    int i = 0;
    while (i < 64) {
        vec3 p = ro + rd * t;
        float d = length(p) - 1.0;
        if (d < 0.001) break;
        t += d;
        i++;
        if (t > 20.0) {
            t = -1.0;
            break;
        }
    }
    return t;
}

void main() {
    vec2 uv = (gl_FragCoord.xy * 2.0 - u_resolution) / u_resolution.y;
    float t = march(vec3(0.0, 0.0, 3.0), normalize(vec3(uv, -1.5)));
    float glow = 0.0;
    int k = 0;
    do {
        glow += 0.05 / float(k + 1);
        k++;
    } while (k < 8);
    for (;;) {
        glow *= 0.9;
        if (glow < 0.5) break;
    }
    for (int j = 0, m = 4; j < m; j++, m--) {
        if (j == 1) continue;
        glow += 0.01;
    }
    fragColor = t > 0.0 ? vec4(vec3(1.0 - t * 0.2), 1.0) : vec4(vec3(glow), 1.0);
}
