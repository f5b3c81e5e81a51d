// The demo scene of rrcache's notebooks and report tests: a sphere with a marbled albedo made of
// eight octaves of a trigonometric noise (costly per pixel, smooth in time: worth caching), lit by
// a moving light (cheap, changes every frame: not worth caching).
#version 330
in vec4 v_position;
in vec3 v_normal;
in vec3 v_objectPosition;
uniform vec3 u_light;
uniform float u_scale;
out vec4 fragColor;

float wave(vec3 p, float f) {
    vec3 q = p * f;
    float a = sin(q.x + 1.3 * cos(q.y * 1.7 + sin(q.z * 0.9)));
    float b = cos(q.z * 0.7 + sin(q.x * 1.9 + cos(q.y * 2.3)));
    float c = sin(q.y * 1.1 + cos(q.z * 1.3 + sin(q.x * 0.6)));
    float d = cos(q.x * 0.8 - sin(q.y * 1.4 + cos(q.z * 2.1)));
    return a * b + 0.5 * c * sin(a + b) + 0.25 * d * cos(b - c);
}

float turbulence(vec3 p) {
    float sum = 0.0;
    float amplitude = 0.5;
    float frequency = 1.0;
    for (int i = 0; i < 8; i++) {
        sum += amplitude * abs(wave(p, frequency));
        amplitude *= 0.5;
        frequency *= 2.03;
    }
    return sum;
}

void main() {
    vec3 p = v_objectPosition * u_scale;
    float veins = 0.5 + 0.5 * sin(p.x * 2.0 + 6.0 * turbulence(p));
    vec3 albedo = mix(vec3(0.93, 0.9, 0.85), vec3(0.25, 0.22, 0.3), veins);
    vec3 nrm = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    float diffuse = max(dot(nrm, l), 0.0);
    fragColor = vec4(albedo * (0.15 + 0.85 * diffuse), 1.0);
}
