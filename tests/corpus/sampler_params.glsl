#version 330
// Functions with sampler parameters (lib/taps.glsl): the inliner must substitute the sampler
// argument into the inlined body (GLSL has no local variables of sampler type), including a
// sampler passed on from one helper to the next and a cube map.
#include "lib/taps.glsl"

in vec2 v_texcoord;
in vec3 v_normal;
in vec4 v_position;
in vec3 v_objectPosition;
uniform vec3 u_light;
uniform vec3 u_camera;
uniform sampler2D u_checker;
uniform samplerCube u_env;
out vec4 fragColor;

void main() {
    vec3 N = normalize(v_normal);
    vec3 L = normalize(u_light - v_position.xyz);
    vec3 V = normalize(u_camera - v_position.xyz);
    vec2 texel = vec2(1.0 / 256.0);
    vec4 base = softTap(u_checker, v_texcoord * vec2(3.0, 1.5), texel);
    vec3 detail = triplanar(u_checker, v_objectPosition, N, 0.7);
    vec3 albedo = mix(base.rgb, detail, 0.35);
    float diff = max(dot(N, L), 0.0);
    vec3 env = envLight(u_env, reflect(-V, N), 1.5);
    vec3 color = albedo * (0.15 + 0.85 * diff) + 0.25 * env * pow(1.0 - max(dot(N, V), 0.0), 2.0);
    fragColor = vec4(color, 1.0);
}
