#version 400 core
uniform dvec2 u_center;
uniform double u_zoom;
uniform vec2 u_resolution;
out vec4 fragColor;

void main() {
    dvec2 c = u_center + dvec2(gl_FragCoord.xy / u_resolution - 0.5) * u_zoom;
    dvec2 z = dvec2(0.0LF);
    int i;
    for (i = 0; i < 128; i++) {
        z = dvec2(z.x * z.x - z.y * z.y, 2.0lf * z.x * z.y) + c;
        if (dot(z, z) > 4.0lf) break;
    }
    dmat2 m = dmat2(1.0);
    float t = float(i) / 128.0;
    fragColor = vec4(t, t * t, sqrt(t), float(m[0][0]));
}
