// Wood: growth rings around the object's y axis, bent by fractal noise, tinted by a gradient
// texture and lit with Blinn-Phong. glslViewer conventions (v_position, v_normal,
// v_objectPosition, u_light, u_camera).
#ifdef GL_ES
precision highp float;
#endif

#ifndef OCTAVES
#define OCTAVES 6
#endif
#include "lib/noise.glsl"

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform float u_ringScale;
uniform float u_varnish;       // animated: the gloss fades in over the session
uniform sampler2D u_tint;      // a 1D gradient across the rings

varying vec4 v_position;
varying vec3 v_normal;
varying vec3 v_objectPosition;

struct Material {
    vec3 albedo;
    float gloss;
};

Material wood(vec3 p) {
    float bend = fbm(p * 1.7);
    float rings = fract(length(p.xz) * u_ringScale + 3.0 * bend);
    float grain = fbm(vec3(p.x * 9.0, p.y * 0.6, p.z * 9.0));
    vec3 tint = texture2D(u_tint, vec2(rings, 0.5)).rgb;
    Material m;
    m.albedo = tint * (0.75 + 0.5 * grain);
    m.gloss = mix(8.0, 64.0, u_varnish);
    return m;
}

void main() {
    Material m = wood(v_objectPosition);
    vec3 N = normalize(v_normal);
    vec3 L = normalize(u_light - v_position.xyz);
    vec3 V = normalize(u_camera - v_position.xyz);
    vec3 H = normalize(L + V);
    float diffuse = max(dot(N, L), 0.0);
    float specular = pow(max(dot(N, H), 0.0), m.gloss) * u_varnish;
    vec3 color = m.albedo * (0.15 + diffuse * u_lightColor) + 0.4 * specular * u_lightColor;
    gl_FragColor = vec4(color, 1.0);
}
