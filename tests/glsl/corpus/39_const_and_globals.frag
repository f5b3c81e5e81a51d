#version 150
const float PI = 3.141592653589793, TAU = 2.0 * PI;
const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);
const int N = 4;
uniform float u_weights[N];
uniform vec2 u_resolution;
in vec2 v_texcoord;
out vec4 outColor;
float g_accum;
vec3 g_color = vec3(0.0);

void accumulate(float w) {
    g_accum += w;
}

void main() {
    g_accum = 0.0;
    for (int i = 0; i < N; ++i) accumulate(u_weights[i]);
    float angle = atan(v_texcoord.y - 0.5, v_texcoord.x - 0.5) / TAU + 0.5;
    g_color = vec3(angle, g_accum, dot(LUMA, vec3(angle)));
    outColor = vec4(g_color, 1.0);
}
