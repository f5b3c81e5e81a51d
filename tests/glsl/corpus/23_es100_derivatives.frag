#extension GL_OES_standard_derivatives : enable
precision mediump float;

uniform float u_time;
varying vec2 v_texcoord;

float grid(vec2 uv, float width) {
    vec2 d = fwidth(uv);
    vec2 g = abs(fract(uv - 0.5) - 0.5) / d;
    return 1.0 - min(min(g.x, g.y) / width, 1.0);
}

void main() {
    float g = grid(v_texcoord * 10.0, 1.5);
    gl_FragColor = vec4(vec3(g), 1.0);
}
