#version 150 compatibility
uniform sampler2D u_tex0;
in vec2 v_texcoord;
uniform float u_time;

void main() {
    vec2 uv = v_texcoord;
    uv.x += sin(uv.y * 20.0 + u_time) * 0.01;
    gl_FragColor = texture2D(u_tex0, uv);
}
