// A glossy filter the way shader authors write one: a 3x3 kernel of texture samples around a
// perturbed coordinate, weighted by a const table (a binomial kernel, centre heaviest), through a
// helper that takes the sampler. The kernel's partial sums are reordered by weight (the corners
// first, the centre last), so "all but the centre" is a node.
#version 330
in vec2 v_texcoord;
in vec3 v_normal;
in vec4 v_position;
uniform sampler2D u_checker;
uniform vec3 u_camera;
out vec4 fragColor;

const int TAPS = 3;
const float KERNEL[9] = float[](1.0, 2.0, 1.0,
                                2.0, 4.0, 2.0,
                                1.0, 2.0, 1.0);
const float SPREAD = 0.02;

vec3 tap(sampler2D tex, vec2 uv, vec2 offset) {
    return textureLod(tex, uv + offset * SPREAD, 0.0).rgb;
}

void main() {
    vec3 V = normalize(u_camera - v_position.xyz);
    vec2 uv = v_texcoord * 3.0 + 0.1 * V.xy;
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (int y = 0; y < TAPS; ++y) {
        for (int x = 0; x < TAPS; ++x) {
            float w = KERNEL[y * TAPS + x];
            sum += w * tap(u_checker, uv, vec2(x - 1, y - 1));
            total += w;
        }
    }
    float shade = 0.3 + 0.7 * max(dot(normalize(v_normal), vec3(0.0, 0.0, 1.0)), 0.0);
    fragColor = vec4(sum / total * shade, 1.0);
}
