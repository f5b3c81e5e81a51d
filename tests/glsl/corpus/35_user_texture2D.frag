#version 130
// A user function named like a legacy built-in is left alone.
uniform sampler2D u_tex0;
in vec2 v_texcoord;

vec4 texture2D(sampler2D s, vec2 uv, float bias) {
    return texture(s, uv, bias) * 0.5;
}

void main() {
    gl_FragColor = texture2D(u_tex0, v_texcoord, 1.0);
}
