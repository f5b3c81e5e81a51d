#ifdef GL_ES
precision highp float;
#endif

uniform float time;
uniform vec2 resolution;

const float PI = 3.14159265;

mediump float stripes(mediump float a, float t) {
    return step(0.5, fract(a * 8.0 / PI + t));
}

void main() {
    vec2 p = (2.0 * gl_FragCoord.xy - resolution) / min(resolution.x, resolution.y);
    float r = length(p);
    float a = atan(p.y, p.x);
    float d = 1.0 / max(r, 1e-3);
    float s = stripes(a, time * .25) * stripes(d, time);
    highp vec3 col = mix(vec3(0.1, 0.2, 0.4), vec3(1.0, 0.8, 0.3), s) * r;
    gl_FragColor = vec4(col, 1.);
}
