#version 330 core
out vec4 fragColor;

void main() {
    int h = 0x1F + 0XaB;
    int o = 0755 + 00;
    uint u = 42u + 0x10U + 07u;
    float f1 = 1.5f + 2.F + .25 + 3.;
    float f2 = 1e3 + 2.5E-2 + 6.02e+23f * 0.0 + 1.e2;
    bool yes = true, no = false;
    float total = float(h + o) + float(u) + f1 + f2;
    fragColor = vec4(fract(total * 1e-3), float(yes), float(no), 1.0);
}
