#version 300 es
precision highp float;
precision mediump int;

uniform float u_time;
uniform vec2 u_resolution;
out vec4 fragColor;

void main() {
    vec2 uv = gl_FragCoord.xy / u_resolution;
    float v = sin(uv.x * 10.0 + u_time);
    v += sin((uv.y * 10.0 + u_time) / 2.0);
    v += sin((uv.x * 10.0 + uv.y * 10.0 + u_time) / 2.0);
    lowp vec3 col = vec3(sin(v * 3.14159), cos(v * 3.14159), 0.5);
    fragColor = vec4(col * 0.5 + 0.5, 1.0);
}
