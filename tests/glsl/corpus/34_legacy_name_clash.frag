#version 120
// Old shaders often name a sampler "texture" and use words that later became keywords.
uniform sampler2D texture;
uniform float sample;
varying vec2 v_texcoord;

vec4 texture2DBlur(sampler2D tex, vec2 uv) {
    vec4 sum = vec4(0.0);
    for (int i = -2; i <= 2; i++) {
        sum += texture2D(tex, uv + vec2(float(i) * 0.004, 0.0));
    }
    return sum / 5.0;
}

void main() {
    float flat = sample * 2.0;
    gl_FragColor = texture2DBlur(texture, v_texcoord) * flat + texture2D(texture, v_texcoord);
}
