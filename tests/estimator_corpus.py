"""Small shaders with loops, for the estimator analysis and the amortized variants.

``ESTIMATORS`` hold at least one estimator (name → (source, samples of each estimator));
``NOT_ESTIMATORS`` hold loops that are not, with a word of the reason the analysis must give.
Every shader renders with the harness on a session with normals and texture coordinates.
"""
from __future__ import annotations

HEAD = """#version 330
in vec3 v_normal;
in vec2 v_texcoord;
in vec4 v_position;
uniform float u_time;
out vec4 fragColor;
"""

ESTIMATORS = {
    # a plain sum of samples, through an inlined helper
    "blur": (HEAD + """
float bump(vec2 p) { return 0.5 + 0.5 * sin(40.0 * p.x) * cos(33.0 * p.y); }
void main() {
    float s = 0.0;
    for (int i = 0; i < 8; i++) {
        vec2 o = vec2(cos(float(i) * 0.785), sin(float(i) * 0.785)) * 0.02;
        s += bump(v_texcoord + o);
    }
    fragColor = vec4(vec3(s / 8.0), 1.0);
}
""", [8]),
    # a weighted sum: colour and weight, two accumulators in one payload (vec3 + float)
    "weighted": (HEAD + """
void main() {
    vec3 n = normalize(v_normal);
    vec3 acc = vec3(0.0);
    float wsum = 0.0;
    for (int i = 1; i <= 12; i += 1) {
        float a = float(i) * 0.523;
        vec3 d = normalize(n + 0.4 * vec3(cos(a), sin(a), cos(2.0 * a)));
        float w = exp(-0.1 * float(i));
        acc += w * (0.5 + 0.5 * d);
        wsum = wsum + w;
    }
    fragColor = vec4(acc / wsum, 1.0);
}
""", [12]),
    # a non-zero start value, a downward loop, a conditional term and a continue
    "conditional": (HEAD + """
void main() {
    float hits = 0.25;
    for (int k = 15; k >= 0; k--) {
        float x = fract(sin(float(k) * 12.9898 + v_texcoord.x * 78.233) * 43758.5453);
        if (x > v_texcoord.y) continue;
        hits += 1.0 / 16.0;
    }
    fragColor = vec4(vec3(hits), 1.0);
}
""", [16]),
}

# the loop is marked by the pragma: its term reads the accumulator, which the analysis refuses
PRAGMA = (HEAD + """
void main() {
    float s = 0.0;
    #pragma rrcache estimator
    for (int i = 0; i < 6; i++) {
        s += 0.1 * sin(float(i) + v_texcoord.x * 9.0) + 0.0 * s;
    }
    fragColor = vec4(vec3(0.5 + s), 1.0);
}
""")

NOT_ESTIMATORS = {
    "carried": (HEAD + """
void main() {
    float s = 0.0; float amp = 1.0;
    for (int i = 0; i < 5; i++) { s += amp * sin(v_texcoord.x * float(i)); amp *= 0.5; }
    fragColor = vec4(s);
}
""", "carried"),
    "reads": (HEAD + """
void main() {
    float s = 0.1;
    for (int i = 0; i < 5; i++) { s += s * v_texcoord.x; }
    fragColor = vec4(s);
}
""", "reads an accumulator"),
    "bound": (HEAD + """
uniform int u_count;
void main() {
    float s = 0.0;
    for (int i = 0; i < u_count; i++) { s += v_texcoord.x; }
    fragColor = vec4(s);
}
""", "not constant"),
    "break": (HEAD + """
void main() {
    float s = 0.0;
    for (int i = 0; i < 5; i++) { if (v_texcoord.x > 0.5) break; s += 1.0; }
    fragColor = vec4(s);
}
""", "break"),
    "wide": (HEAD + """
void main() {
    vec4 a = vec4(0.0); float b = 0.0;
    for (int i = 0; i < 5; i++) { a += vec4(v_texcoord.x); b += 1.0; }
    fragColor = a * b;
}
""", "4 components"),
}
