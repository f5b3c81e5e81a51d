// Integer hashing with unsigned wrap-around: a negative unsigned constant, loops over uint and
// int counters, and constants folded while unrolling.
#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
out vec4 fragColor;

const uint ALL_ONES = -1u;
const uint MINUS_ONE = 0u - 1u;

uint hash(uint x) {
    for (uint i = 0u; i < 3u; i++) {
        x ^= x >> 16u;
        x *= 0x7feb352du;
        x += i * MINUS_ONE;
    }
    return x;
}

void main() {
    uint mask = -1u;
    uvec3 cell = uvec3(ivec3(floor(v_objectPosition * 6.0)) + 16);
    uint h = hash(cell.x + hash(cell.y + hash(cell.z))) & (ALL_ONES >> 8u) & mask;
    uint countdown = 0u;
    for (uint k = 5u; k != ALL_ONES; k--) countdown += k;
    float r = float(h & 255u) / 255.0;
    float g = float((h >> 8u) & 255u) / 255.0;
    float lit = 0.3 + 0.7 * max(dot(normalize(v_normal), vec3(0.0, 0.8, 0.6)), 0.0);
    fragColor = vec4(vec3(r, g, float(countdown) / 15.0) * lit, 1.0);
}
