#version 120
uniform sampler2D u_tex0;
uniform float u_cutoff;
varying vec2 v_texcoord;
varying vec4 v_color;

void main() {
    vec4 texel = texture2D(u_tex0, v_texcoord) * v_color;
    if (texel.a < u_cutoff)
        discard;
    else
        ;
    gl_FragColor = texel;
}
