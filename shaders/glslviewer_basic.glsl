// A basic glslViewer-style fragment shader, written the old way: no #version, `varying`,
// `gl_FragColor`, a precision statement for GLSL ES, and the MODEL_VERTEX_* defines that say
// which attributes the mesh has. It shades with a diffuse term, a Blinn-Phong highlight and a
// little procedural stripe pattern, so it has something worth caching.

#ifdef GL_ES
precision mediump float;
#endif

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform float u_time;

varying vec4 v_position;

#ifdef MODEL_VERTEX_NORMAL
varying vec3 v_normal;
#endif

#ifdef MODEL_VERTEX_COLOR
varying vec4 v_color;
#endif

const float STRIPES = 12.0;
const float SHININESS = 48.0;

// Soft stripes along world-space height, drifting slowly with time.
float stripes(vec3 p) {
    return 0.5 + 0.5 * sin((p.y + 0.05 * u_time) * STRIPES);
}

void main(void) {
    vec3 color = vec3(0.85, 0.55, 0.35);
#ifdef MODEL_VERTEX_COLOR
    color *= v_color.rgb;
#endif
    color = mix(color, color * 0.6, stripes(v_position.xyz));

#ifdef MODEL_VERTEX_NORMAL
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    vec3 v = normalize(u_camera - v_position.xyz);
    vec3 h = normalize(l + v);
    float diffuse = max(dot(n, l), 0.0);
    float specular = pow(max(dot(n, h), 0.0), SHININESS);
    color = color * (0.2 + 0.8 * diffuse * u_lightColor) + 0.4 * specular * u_lightColor;
#endif

    gl_FragColor = vec4(color, 1.0);
}
