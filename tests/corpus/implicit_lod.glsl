#version 330
// Implicit-LOD texture lookups: texture() of a mipmapped 2D texture seen minified (a fine
// checker repeated 6x3 times over a torus in a 64x64 frame), a cube map looked up with a bias,
// and fwidth(). Values computed after them are cacheable by three-pass and two-pass, whose
// passes draw whole primitives; one-pass, which computes the node in a per-pixel branch, must
// refuse them. Values flowing into a lookup's coordinate are never cached.
in vec3 v_normal;
in vec4 v_position;
in vec2 v_texcoord;
uniform vec3 u_camera;
uniform vec3 u_light;
uniform sampler2D u_checker;
uniform samplerCube u_env;
out vec4 fragColor;

void main() {
    vec3 N = normalize(v_normal);
    vec3 V = normalize(u_camera - v_position.xyz);
    vec3 L = normalize(u_light - v_position.xyz);
    float diff = max(dot(N, L), 0.0) * (0.8 + 0.2 * sin(v_position.x * 5.0));
    vec2 uv = v_texcoord * vec2(6.0, 3.0) + 0.05 * sin(v_position.yz * 3.0);
    vec3 albedo = texture(u_checker, uv).rgb;
    vec3 R = reflect(-V, N);
    vec3 env = texture(u_env, R, 0.5).rgb;
    float edge = fwidth(v_texcoord.x * 40.0);
    vec3 color = albedo * (0.2 + diff * exp(-edge))
               + env * pow(1.0 - max(dot(N, V), 0.0), 3.0) * (0.75 + 0.25 * sin(albedo * 3.0));
    fragColor = vec4(color, 1.0);
}
