#version 120
invariant gl_FragColor;
uniform float u_time;
centroid varying vec2 v_texcoord;

void main() {
    gl_FragColor = vec4(fract(v_texcoord * 4.0 + u_time), 0.0, 1.0);
}
