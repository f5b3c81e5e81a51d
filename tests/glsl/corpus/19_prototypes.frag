#version 330 core
out vec4 fragColor;
uniform vec2 u_resolution;

float sdSphere(vec3 p, float r);
float sdBox(vec3 p, vec3 b);
float map(vec3);
vec3 calcNormal(in vec3 p);

void main() {
    vec3 p = vec3(gl_FragCoord.xy / u_resolution - 0.5, 0.0);
    vec3 n = calcNormal(p);
    fragColor = vec4(n * 0.5 + 0.5, 1.0);
}

float sdSphere(vec3 p, float r) { return length(p) - r; }

float sdBox(vec3 p, vec3 b) {
    vec3 q = abs(p) - b;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}

float map(vec3 p) {
    return min(sdSphere(p, 0.3), sdBox(p - vec3(0.4, 0.0, 0.0), vec3(0.1)));
}

vec3 calcNormal(in vec3 p) {
    const vec2 e = vec2(1e-4, 0.0);
    return normalize(vec3(map(p + e.xyy) - map(p - e.xyy),
                          map(p + e.yxy) - map(p - e.yxy),
                          map(p + e.yyx) - map(p - e.yyx)));
}
