#version 300 es
precision highp float;
precision highp int;

uniform uint u_seed;
flat in uint v_id;
in vec2 v_texcoord;
layout(location = 0) out vec4 fragColor;

uint pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

void main() {
    uvec2 p = uvec2(gl_FragCoord.xy);
    uint h = pcg(p.x + pcg(p.y + u_seed + v_id));
    fragColor = vec4(vec3(float(h) / 4294967295.0), 1.0);
}
