// Helper functions as people write them: out and inout parameters, a void helper writing a
// global, an early return, and vec3/vec4 constructors from mixed vec2/float arguments.
#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
in vec4 v_position;
uniform vec3 u_light;
uniform float u_time;
out vec4 fragColor;

vec3 g_acc;

void addLight(vec3 n, vec3 l, vec3 color) {
    g_acc += max(dot(n, l), 0.0) * color;
}

void polar(in vec3 p, out float r, out vec2 angles) {
    r = length(p);
    angles = vec2(atan(p.y, p.x), acos(clamp(p.z / max(r, 1e-4), -1.0, 1.0)));
}

void fade(inout vec3 c, float t) {
    if (t > 0.8) return;
    c *= 0.5 + 0.5 * t;
}

vec3 bands(vec2 a, float r) {
    return vec3(sin(a * 6.0), cos(r * 9.0));
}

void main() {
    g_acc = vec3(0.05);
    vec3 n = normalize(v_normal);
    addLight(n, normalize(u_light - v_position.xyz), vec3(0.9, 0.85, 0.8));
    addLight(n, normalize(vec3(-1.0, 0.5, 0.2)), vec3(0.1, 0.15, 0.3));
    float r;
    vec2 angles;
    polar(v_objectPosition * 2.0, r, angles);
    vec3 albedo = 0.5 + 0.5 * bands(angles, r);
    fade(albedo, fract(v_objectPosition.y * 3.0 + 0.1 * u_time));
    fragColor = vec4(albedo * g_acc, 1.0);
}
