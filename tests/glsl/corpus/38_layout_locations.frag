#version 440 core
const int BASE = 1;
layout(location = BASE + 0) in vec3 v_normal;
layout(location = (BASE + 1) * 2) in vec2 v_texcoord;
layout(location = 0, index = 0) out vec4 fragColor;
layout(binding = 3) uniform sampler2D u_tex0;
layout(std140, binding = BASE) uniform Params {
    layout(offset = 0) vec4 tint;
    layout(offset = 16) float gain;
} params;

void main() {
    vec4 c = texture(u_tex0, v_texcoord);
    fragColor = vec4(c.rgb * params.tint.rgb * params.gain * (0.5 + 0.5 * normalize(v_normal).y), c.a);
}
