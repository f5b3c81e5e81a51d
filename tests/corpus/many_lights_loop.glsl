// Many lights in a loop: eight point lights on a ring, each with its own colour, evaluated by a
// helper with an early-out ternary; the third light follows u_light (it moves with the session's
// light), the others are fixed. The static lights' sum comes first once reordered: its partial
// sum "every light but the moving one" is the static part of the lighting.
#version 330
in vec4 v_position;
in vec3 v_normal;
uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform vec3 u_camera;
out vec4 fragColor;

#define NUM_LIGHTS 8
const float RING = 3.0;

struct Light { vec3 position; vec3 color; };

Light ringLight(int i) {
    float a = 6.2831853 * float(i) / float(NUM_LIGHTS);
    Light l;
    l.position = vec3(RING * cos(a), 1.5 + 0.25 * float(i % 3), RING * sin(a));
    l.color = 0.5 + 0.5 * cos(vec3(0.0, 2.0, 4.0) + a);
    return l;
}

vec3 shadeLight(Light l, vec3 p, vec3 n, vec3 v) {
    vec3 d = l.position - p;
    float dist2 = dot(d, d);
    vec3 L = d * inversesqrt(dist2);
    float ndl = max(dot(n, L), 0.0);
    float spec = ndl > 0.0 ? pow(max(dot(n, normalize(L + v)), 0.0), 24.0) : 0.0;
    return l.color * (ndl + 0.3 * spec) / (1.0 + 0.2 * dist2);
}

void main() {
    vec3 p = v_position.xyz;
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_camera - p);
    vec3 lit = vec3(0.02);
    for (int i = 0; i < NUM_LIGHTS; i++) {
        Light l = ringLight(i);
        if (i == 2) {
            l.position = u_light;
            l.color = u_lightColor;
        }
        lit += shadeLight(l, p, n, v);
    }
    fragColor = vec4(lit / (1.0 + lit), 1.0);
}
