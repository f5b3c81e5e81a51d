// glslViewer-style legacy Lambert shading.
#ifdef GL_ES
precision mediump float;
#endif

uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform vec3 u_camera;

varying vec4 v_position;
varying vec3 v_normal;
varying vec2 v_texcoord;

void main() {
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    float diffuse = max(dot(n, l), 0.0);
    vec3 color = vec3(0.1) + u_lightColor * diffuse;
    gl_FragColor = vec4(color, 1.0);
}
