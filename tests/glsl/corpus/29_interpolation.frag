#version 450 core
smooth in vec3 v_normal;
noperspective in vec2 v_screen;
flat in int v_objectId;
centroid in vec2 v_texcoord;
sample in vec4 v_color;
layout(location = 0) out vec4 fragColor;

void main() {
    precise float w = v_color.a * 0.5 + 0.5;
    vec3 n = normalize(v_normal);
    float checker = mod(floor(v_texcoord.x * 8.0) + floor(v_texcoord.y * 8.0), 2.0);
    fragColor = vec4(n * 0.5 + 0.5, 1.0) * w * (0.5 + 0.5 * checker)
              + vec4(v_screen, float(v_objectId), 0.0) * 0.001;
}
