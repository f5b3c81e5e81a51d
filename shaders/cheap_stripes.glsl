#version 330
// A cheap material: a procedural pattern (sine stripes and a checker
// in object space) lit with Blinn-Phong. About 50-100 ns per covered pixel on a two-core
// llvmpipe machine at 320x240: cheaper than the reverse reprojection cache's own passes, so
// `rrcache profile` answers "the original" from the measured ceiling without training.
//
// glslViewer conventions: v_position (world), v_normal (world), v_objectPosition (object space),
// u_camera (eye), u_light (light position), u_lightColor.

in vec4 v_position;
in vec3 v_normal;
in vec3 v_objectPosition;

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform vec3 u_colorA;
uniform vec3 u_colorB;
uniform float u_scale;

out vec4 fragColor;

float pattern(vec3 p) {
    float a = 0.5 + 0.5 * sin(p.x * 7.0 + 2.0 * p.y);
    vec3 cell = floor(p * 2.0);
    float checker = mod(cell.x + cell.y + cell.z, 2.0);
    return mix(a, 1.0 - a, 0.35 * checker);
}

void main() {
    vec3 p = v_objectPosition * u_scale;
    vec3 albedo = mix(u_colorA, u_colorB, pattern(p));
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    vec3 v = normalize(u_camera - v_position.xyz);
    vec3 h = normalize(l + v);
    float diffuse = max(dot(n, l), 0.0);
    float specular = pow(max(dot(n, h), 0.0), 40.0);
    vec3 color = albedo * (0.15 + 0.85 * diffuse) * u_lightColor + 0.3 * specular * u_lightColor;
    fragColor = vec4(color, 1.0);
}
