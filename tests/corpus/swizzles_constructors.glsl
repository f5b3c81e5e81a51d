// Swizzles of scalars (x.xxx), constructors from mixed vec2/float arguments, and an int argument
// to a float parameter: conversions the inliner must keep (scalar swizzles need GLSL 4.20).
#version 420
in vec3 v_objectPosition;
in vec3 v_normal;
in vec2 v_texcoord;
uniform float u_time;
out vec4 fragColor;

float sq(float x) { return x * x; }

vec3 grey(float x) { return x.xxx * 0.8 + 0.1; }

vec3 tint(vec2 p, float h) { return vec3(p, h) * 0.5 + vec3(h, p.yx) * 0.25; }

vec4 pack(float a, vec2 b, float c) { return vec4(a, b, c); }

float halve(float x) { return x / 2.0; }

void main() {
    float s = sin(v_objectPosition.x * 5.0 + u_time);
    vec3 c = grey(s) + tint(v_objectPosition.yz, sq(s)) + vec3(sq(s).x, s.xx);
    vec4 p = pack(s, v_normal.xy, halve(3));
    fragColor = vec4(c * 0.5 + p.xyz * 0.25 + s.xxx * 0.1, 1.0);
}
