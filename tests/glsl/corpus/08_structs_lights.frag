#version 330 core
struct Material {
    vec3 albedo;
    float roughness;
};

struct Light {
    vec3 position;
    vec3 color;
    float intensity;
};

struct Scene {
    Light lights[2];
    Material material;
};

uniform Light u_lights[2];
uniform Material u_material;
in vec3 v_normal;
in vec4 v_position;
out vec4 fragColor;

vec3 shade(Light light, Material m, vec3 n, vec3 p) {
    vec3 l = normalize(light.position - p);
    return m.albedo * light.color * light.intensity * max(dot(n, l), 0.0);
}

void main() {
    Scene scene = Scene(u_lights, u_material);
    vec3 n = normalize(v_normal);
    vec3 total = vec3(0.0);
    for (int i = 0; i < scene.lights.length(); ++i) {
        total += shade(scene.lights[i], scene.material, n, v_position.xyz);
    }
    Light extra = Light(vec3(0.0, 10.0, 0.0), vec3(1.0), 0.25);
    total += shade(extra, scene.material, n, v_position.xyz);
    fragColor = vec4(total, 1.0);
}
