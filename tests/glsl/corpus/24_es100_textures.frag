#ifdef GL_ES
precision mediump float;
#endif

uniform sampler2D u_tex0;
uniform samplerCube u_cubeMap;
uniform float u_time;
varying mediump vec3 v_normal;
varying vec2 v_texcoord;
varying vec4 v_position;

void main() {
    vec3 n = normalize(v_normal);
    vec4 albedo = texture2D(u_tex0, v_texcoord + vec2(u_time * 0.01, 0.0));
    vec3 env = textureCube(u_cubeMap, reflect(normalize(v_position.xyz), n)).rgb;
    vec4 proj = texture2DProj(u_tex0, vec3(v_texcoord, 1.0));
    gl_FragColor = vec4(mix(albedo.rgb, env, 0.3) + proj.rgb * 0.1, albedo.a);
}
