#version 330 core
uniform vec3 u_camera;
uniform float u_time;
uniform vec2 u_resolution;
out vec4 fragColor;

#define MAX_STEPS 100
#define SURF_DIST 0.001

float sdTorus(vec3 p, vec2 t) {
    vec2 q = vec2(length(p.xz) - t.x, p.y);
    return length(q) - t.y;
}

float opSmoothUnion(float d1, float d2, float k) {
    float h = clamp(0.5 + 0.5 * (d2 - d1) / k, 0.0, 1.0);
    return mix(d2, d1, h) - k * h * (1.0 - h);
}

float scene(vec3 p) {
    float plane = p.y + 1.0;
    float torus = sdTorus(p - vec3(0.0, sin(u_time) * 0.2, 0.0), vec2(1.0, 0.25));
    return opSmoothUnion(plane, torus, 0.3);
}

vec3 normalAt(vec3 p) {
    vec2 e = vec2(0.001, 0.0);
    return normalize(vec3(scene(p + e.xyy) - scene(p - e.xyy),
                          scene(p + e.yxy) - scene(p - e.yxy),
                          scene(p + e.yyx) - scene(p - e.yyx)));
}

void main() {
    vec2 uv = (gl_FragCoord.xy - 0.5 * u_resolution) / u_resolution.y;
    vec3 ro = u_camera;
    vec3 fw = normalize(-ro), rt = normalize(cross(vec3(0, 1, 0), fw)), up = cross(fw, rt);
    vec3 rd = normalize(uv.x * rt + uv.y * up + 1.5 * fw);
    float t = 0.0;
    for (int i = 0; i < MAX_STEPS; i++) {
        float d = scene(ro + rd * t);
        t += d;
        if (d < SURF_DIST || t > 50.0) break;
    }
    vec3 col = vec3(0.0);
    if (t < 50.0) {
        vec3 n = normalAt(ro + rd * t);
        col = vec3(0.8, 0.6, 0.4) * max(dot(n, normalize(vec3(1, 2, 3))), 0.05);
    }
    fragColor = vec4(pow(col, vec3(1.0 / 2.2)), 1.0);
}
