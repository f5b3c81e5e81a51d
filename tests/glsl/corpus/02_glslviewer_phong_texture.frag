#version 120
uniform sampler2D u_tex0;
uniform vec3 u_light;
uniform vec3 u_camera;
uniform float u_shininess;

varying vec4 v_position;
varying vec3 v_normal;
varying vec2 v_texcoord;

vec3 phong(vec3 n, vec3 l, vec3 v, vec3 albedo) {
    vec3 h = normalize(l + v);
    float d = max(dot(n, l), 0.0);
    float s = pow(max(dot(n, h), 0.0), u_shininess);
    return albedo * d + vec3(s);
}

void main(void) {
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    vec3 v = normalize(u_camera - v_position.xyz);
    vec3 albedo = texture2D(u_tex0, v_texcoord).rgb;
    gl_FragColor = vec4(phong(n, l, v, albedo), 1.0);
}
