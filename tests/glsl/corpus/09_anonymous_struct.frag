#version 420 core
out vec4 fragColor;
uniform float u_time;

struct Ray { vec3 origin; vec3 dir; } primary, secondary;

struct {
    float near;
    float far;
} clipRange = { 0.1, 100.0 };

void main() {
    primary = Ray(vec3(0.0), vec3(0.0, 0.0, -1.0));
    secondary = primary;
    secondary.origin.x += u_time;
    float depth = clamp(secondary.origin.x, clipRange.near, clipRange.far);
    fragColor = vec4(vec3(depth / clipRange.far), 1.0);
}
