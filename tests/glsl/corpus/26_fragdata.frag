#version 110
uniform vec4 u_color;
varying vec2 v_texcoord;

void main() {
    gl_FragData[0] = u_color * vec4(v_texcoord, 1.0, 1.0);
}
