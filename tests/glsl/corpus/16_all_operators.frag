#version 330 core
uniform int u_frame;
uniform uint u_seed;
out vec4 fragColor;

uint hash(uint x) {
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846CA68Bu;
    x ^= x >> 16u;
    return x;
}

void main() {
    int a = u_frame, b = 3, c = 017;
    a += b; a -= 1; a *= 2; a /= 3; a %= 7;
    a <<= 2; a >>= 1; a &= 0xff; a |= 1; a ^= c;
    int d = a << 1 >> 2;
    int e = ~a & b | c ^ d;
    bool p = a < b || b > c && !(c <= d) ^^ d >= a;
    bool q = a == b != (c == d);
    int f = -a + +b - -c;
    int g = a++ + ++b - c-- - --d;
    int h = (a, b, c);
    int t = p ? q ? 1 : 2 : 3;
    uint bits = hash(u_seed + uint(u_frame));
    float x = float(bits & 0xFFFFu) / 65535.0;
    x = x > 0.5 ? x : 1.0 - x;
    fragColor = vec4(x, float(e + f + g + h + t) * 0.001, float(p), 1.0);
}
