#version 330 core
out vec4 fragColor;
in vec2 v_texcoord;

struct Hit { float t; vec3 n; };

Hit miss() { return Hit(-1.0, vec3(0.0)); }

void main() {
    struct Sphere { vec3 c; float r; };
    Sphere s = Sphere(vec3(0.0), 0.5);
    Hit h = miss();
    {
        struct Local { int id; };
        Local l;
        l.id = 3;
        h.t = float(l.id);
    }
    vec2 p = v_texcoord - 0.5;
    if (length(p) < s.r) {
        h.t = 1.0;
        h.n = normalize(vec3(p, sqrt(max(s.r * s.r - dot(p, p), 0.0))));
    }
    fragColor = h.t > 0.0 ? vec4(h.n * 0.5 + 0.5, 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
