#version 330 core
layout(std140) uniform Transforms {
    mat4 view;
    mat4 projection;
    vec4 eye;
} transforms;

layout(std140, row_major) uniform LightBlock {
    vec4 position;
    vec4 color;
};

uniform Material {
    vec4 albedo;
    float roughness;
} materials[2];

in vec3 v_normal;
out vec4 fragColor;

void main() {
    vec3 n = normalize(v_normal);
    vec3 l = normalize(position.xyz - transforms.eye.xyz);
    float d = max(dot(n, l), 0.0);
    fragColor = vec4(materials[0].albedo.rgb * color.rgb * d + materials[1].albedo.rgb * 0.1, 1.0);
}
