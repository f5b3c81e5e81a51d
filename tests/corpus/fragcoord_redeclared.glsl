#version 330
// Built-in redeclaration: the fragment coordinate with its origin at the top left, as ports of
// D3D-style screen-space code write it. The cache's own snippets read gl_FragCoord too, so the
// redeclaration must come before them in every pass (GLSL 4.60 §7.1.2).
layout(origin_upper_left, pixel_center_integer) in vec4 gl_FragCoord;

uniform vec3 u_light;
in vec3 v_normal;
in vec3 v_position;
out vec4 fragColor;

float bands(vec3 n) {
    float s = 0.0;
    for (int i = 1; i <= 12; i++) {
        s += sin(float(i) * n.x * 2.7 + n.y * float(i) * 1.3) / float(i);
    }
    return s;
}

void main() {
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light - v_position);
    float diffuse = max(dot(n, l), 0.0);
    float b = bands(n) * 0.25 + 0.5;
    // a screen-space scanline, top-left origin: rows counted down from the top
    float scan = mod(gl_FragCoord.y, 4.0) < 1.0 ? 0.85 : 1.0;
    fragColor = vec4(vec3(b * (0.2 + 0.8 * diffuse)) * scan, 1.0);
}
