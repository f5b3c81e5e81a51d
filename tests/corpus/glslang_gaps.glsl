#version 330
// A construct of glslang's OpenGL tests the front-end once rejected (tools/glsl_conformance.py):
// GL_ARB_texture_query_lod's own spelling textureQueryLOD (GLSL 4.00 renamed it textureQueryLod),
// enabled only where the extension macro is defined. The level it returns depends on screen-space
// derivatives, like the implicit-LOD lookup beside it.
#ifdef GL_ARB_texture_query_lod
#extension GL_ARB_texture_query_lod : enable
#endif
in vec3 v_normal;
in vec4 v_position;
in vec2 v_texcoord;
uniform vec3 u_light;
uniform sampler2D u_checker;
out vec4 fragColor;

void main() {
    vec3 N = normalize(v_normal);
    vec3 L = normalize(u_light - v_position.xyz);
    float diff = max(dot(N, L), 0.0) * (0.8 + 0.2 * sin(v_position.x * 5.0));
    vec2 uv = v_texcoord * vec2(6.0, 3.0);
    vec3 albedo = texture(u_checker, uv).rgb;
#ifdef GL_ARB_texture_query_lod
    vec2 lod = textureQueryLOD(u_checker, uv);
#else
    vec2 lod = vec2(-1.0);
#endif
    vec3 tint = albedo * (0.2 + diff) * (1.0 + 0.1 * clamp(lod.y, 0.0, 4.0));
    fragColor = vec4(tint, 1.0);
}
