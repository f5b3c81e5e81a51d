#version 450 core
layout(early_fragment_tests) in;

layout(binding = 0, rgba32f) uniform readonly image2D u_input;
layout(binding = 1, r32ui) uniform coherent uimage2D u_counter;
layout(binding = 2) uniform writeonly restrict image2D u_output;
layout(location = 2 * 0) out vec4 fragColor;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 c = imageLoad(u_input, p);
    uint n = imageAtomicAdd(u_counter, ivec2(0), 1u);
    imageStore(u_output, p, c * 0.5);
    fragColor = vec4(c.rgb, float(n & 1u));
}
