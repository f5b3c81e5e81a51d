#version 330
// Screen-space values: stripes of gl_FragCoord.xy / u_resolution over a lit surface. Values of
// the screen position stay on the screen while the surface moves, so they are excluded as
// 'screen' (and so is the final colour, which reads them); the surface's own lighting is listed.
in vec3 v_normal;
in vec4 v_position;
uniform vec3 u_light;
uniform vec2 u_resolution;
out vec4 fragColor;

void main() {
    vec3 n = normalize(v_normal);
    vec3 L = normalize(u_light - v_position.xyz);
    vec3 surf = vec3(0.8, 0.6, 0.4) * max(dot(n, L), 0.0) * (0.75 + 0.25 * sin(v_position.xyz * 9.0));
    vec2 st = gl_FragCoord.xy / u_resolution;
    float stripes = 0.5 + 0.5 * sin(st.x * 60.0) * cos(st.y * 30.0);
    fragColor = vec4(surf * (0.8 + 0.2 * stripes), 1.0);
}
