#version 330 core
uniform int u_mode;
uniform vec2 u_resolution;
out vec4 fragColor;

vec3 palette(int mode, float t) {
    vec3 c;
    switch (mode) {
        case 0:
            c = vec3(t);
            break;
        case 1:
        case 2: {
            c = vec3(t, 1.0 - t, 0.5);
            break;
        }
        case 3:
            c = vec3(0.0);
            // fall through
        default:
            c += vec3(0.25);
    }
    return c;
}

void main() {
    float t = gl_FragCoord.x / u_resolution.x;
    switch (u_mode & 3) {
    case 0: fragColor = vec4(palette(0, t), 1.0); break;
    default: fragColor = vec4(palette(u_mode, t), 1.0);
    }
}
