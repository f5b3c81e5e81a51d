// main() first, helpers and the globals they read after it, reached through prototypes:
// the inlined bodies read globals declared after main.
#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
uniform vec3 u_light;
out vec4 fragColor;

float stripes(vec3 p);
vec3 palette(float t);

void main() {
    float s = stripes(v_objectPosition);
    vec3 n = normalize(v_normal);
    fragColor = vec4(palette(s) * (0.3 + 0.7 * max(dot(n, normalize(u_light)), 0.0)), 1.0);
}

const float FREQ = 9.0;
vec3 g_warm = vec3(0.9, 0.6, 0.3);
vec3 g_cold = vec3(0.2, 0.4, 0.8);

float stripes(vec3 p) { return 0.5 + 0.5 * sin(p.y * FREQ + cos(p.x * FREQ)); }

vec3 palette(float t) { return mix(g_cold, g_warm, smoothstep(0.2, 0.8, t)); }
