#version 120
uniform sampler2D u_tex0;
uniform samplerCube u_env;
uniform sampler2DShadow u_shadowMap;
uniform sampler3D u_volume;
varying vec4 v_shadowCoord;
varying vec3 v_normal;
varying vec2 v_texcoord;

void main() {
    vec3 blurred = texture2DLod(u_tex0, v_texcoord, 3.0).rgb;
    vec3 env = textureCubeLod(u_env, normalize(v_normal), 2.0).rgb;
    float lit = shadow2D(u_shadowMap, v_shadowCoord.xyz).r;
    float lit2 = shadow2DProj(u_shadowMap, v_shadowCoord).r;
    float density = texture3D(u_volume, vec3(v_texcoord, 0.5)).r;
    gl_FragColor = vec4((blurred + env) * (lit + lit2) * 0.5 * density, 1.0);
}
