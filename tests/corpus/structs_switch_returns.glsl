// Struct parameters and an out struct, a switch inside an unrolled loop, a helper with a
// switch of returns, and a void helper with early returns writing a global.
#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
uniform vec3 u_light;
out vec4 fragColor;

struct Light { vec3 dir; vec3 color; float k; };
struct Surface { vec3 n; vec3 albedo; };

vec3 g_col;

vec3 shade(Light l, Surface s) { return s.albedo * l.color * max(dot(s.n, l.dir), 0.0) * l.k; }

void makeLight(out Light l, vec3 d) { l.dir = normalize(d); l.color = vec3(1.0, 0.9, 0.8); l.k = 1.2; }

vec3 palette(int k) {
    switch (k) {
        case 0: return vec3(0.9, 0.3, 0.2);
        case 1: return vec3(0.2, 0.8, 0.3);
        default: return vec3(0.2, 0.3, 0.9);
    }
}

void tint(vec3 p) {
    if (p.y > 0.6) { g_col = vec3(1.0); return; }
    if (p.x < -0.6) return;
    g_col *= 0.5 + 0.5 * p;
}

void main() {
    Light l;
    makeLight(l, u_light - v_objectPosition);
    Surface s = Surface(normalize(v_normal), vec3(0.5) + 0.5 * sin(v_objectPosition * 4.0));
    vec3 bands = vec3(0.0);
    for (int i = 0; i < 3; i++) {
        switch (i) {
            case 0: bands += sin(v_objectPosition * 3.0); break;
            case 1: bands *= 0.5; break;
            default: bands += 0.2 * palette(i - 2);
        }
    }
    g_col = vec3(1.0);
    tint(v_objectPosition);
    fragColor = vec4(shade(l, s) * g_col + 0.1 * bands, 1.0);
}
