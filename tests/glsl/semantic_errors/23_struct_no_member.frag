// expect: 7:18 'Light' has no member named 'colour'
#version 330
struct Light { vec3 position; vec3 color; };
uniform Light light;
out vec4 color;
void main() {
    color = vec4(light.colour, 1.0);
}
