// Value noise and fbm with helpers whose locals share names with the caller's (i, f, t), a
// rotation matrix indexed by two unrolled loop variables, and a loop counting down.
#version 330
in vec3 v_objectPosition;
in vec3 v_normal;
uniform float u_time;
out vec4 fragColor;

float hash(float t) { return fract(sin(t) * 43758.5453); }

float noise(float t) {
    float i = floor(t);
    float f = fract(t);
    return mix(hash(i), hash(i + 1.0), f * f * (3.0 - 2.0 * f));
}

float fbm(float t) {
    float v = 0.0;
    float a = 0.5;
    for (int i = 0; i < 4; i++) { v += a * noise(t); t *= 2.0; a *= 0.5; }
    return v;
}

mat3 rot(float a) { float c = cos(a), s = sin(a); return mat3(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0); }

void main() {
    float t = v_objectPosition.x * 4.0 + v_objectPosition.y;
    float i = fbm(t);
    float f = noise(i * 8.0);
    mat3 m = rot(0.3 * u_time + v_objectPosition.z);
    float acc = 0.0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) acc += m[r][c] * v_normal[c] * float(r + 1);
    for (int k = 2; k >= 0; k--) acc += 0.1 * m[k].x;
    fragColor = vec4(i, f, 0.5 + 0.25 * acc, 1.0);
}
