// Locals and parameters named like the globals and built-in functions a helper uses: after
// inlining, the helper's `pos.y`, `vec3(uv, h)` and `step(...)` must still mean the globals and
// the built-in, not the caller's locals (raymarchers often name a variable `step`).
#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
in vec2 v_texcoord;
uniform vec3 u_light;
out vec4 fragColor;

vec3 pos = vec3(0.25, 0.5, 0.75);
vec2 uv = vec2(0.3, 0.6);

float height() { return pos.y * 2.0 + sin(v_objectPosition.y * 4.0); }

vec3 tint(float h) { return vec3(uv, h); }

float bands(float x) { return step(0.5, fract(x * 3.0)) * 0.2 + 0.8; }

float shade(vec3 uv) { return max(dot(normalize(v_normal), normalize(u_light - uv)), 0.0); }

void main() {
    float pos = v_objectPosition.x;          // shadows the global vec3 pos
    vec3 uv = v_objectPosition * 0.5 + 0.5;  // shadows the global vec2 uv
    float step = 0.05;                       // shadows the built-in step()
    vec3 c = tint(height()) * shade(uv) * bands(uv.z) + pos * step;
    fragColor = vec4(c, 1.0);
}
