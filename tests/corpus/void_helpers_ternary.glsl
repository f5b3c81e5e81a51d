// Void helpers chosen by ?: as a statement, a helper returning nothing, and helpers with out
// parameters, as GLSL sketches write them.
#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
out vec4 fragColor;

vec3 g_color;

void warm(float k) { g_color = vec3(0.9, 0.5, 0.2) * (0.5 + 0.5 * sin(k * 7.0)); }
void cold(float k) { g_color = vec3(0.2, 0.4, 0.9) * (0.5 + 0.5 * cos(k * 5.0)); }
void nothing() { }
void both(vec3 p, out float a, out float b) { a = fract(p.x * 3.0); b = fract(p.z * 3.0); }

void main() {
    g_color = vec3(0.0);
    nothing();
    v_objectPosition.y > 0.0 ? warm(v_objectPosition.x) : cold(v_objectPosition.z);
    float a, b;
    both(v_objectPosition, a, b);
    float lit = max(dot(normalize(v_normal), normalize(vec3(1.0, 2.0, 3.0))), 0.0);
    fragColor = vec4(g_color * (0.4 + 0.6 * lit) + vec3(a, b, 0.0) * 0.1, 1.0);
}
