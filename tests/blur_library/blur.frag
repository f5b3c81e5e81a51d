// A glslViewer / WebGL 1 style sketch that blurs its texture through a blur library whose
// function takes the sampler as a parameter (lib/fast-gaussian-blur.glsl; tests/test_blur_library.py).
#ifdef GL_ES
precision mediump float;
#endif

#include "lib/fast-gaussian-blur.glsl"

uniform sampler2D u_image;
uniform float u_time;

varying vec2 v_texcoord;
varying vec3 v_normal;

void main() {
    vec2 direction = vec2(cos(u_time), sin(u_time));
    vec4 blurred = blur13(u_image, v_texcoord * 2.0, vec2(256.0), direction);
    float light = 0.3 + 0.7 * max(dot(normalize(v_normal), normalize(vec3(0.5, 0.8, 0.6))), 0.0);
    gl_FragColor = vec4(blurred.rgb * light, 1.0);
}
