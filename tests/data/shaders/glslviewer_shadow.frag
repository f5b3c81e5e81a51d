// glslViewer's shadow-map interface, as its examples use it (texture2D on the depth map, .r)
#ifdef GL_ES
precision mediump float;
#endif

uniform vec3 u_light;

#ifdef LIGHT_SHADOWMAP
uniform sampler2D u_lightShadowMap;
uniform mat4 u_lightMatrix;
varying vec4 v_lightCoord;
#endif

varying vec4 v_position;
varying vec3 v_normal;

void main() {
    float shadow = 1.0;
#if defined(LIGHT_SHADOWMAP) && defined(LIGHT_SHADOWMAP_SIZE)
    vec3 coord = v_lightCoord.xyz / v_lightCoord.w;
    float texel = 1.0 / LIGHT_SHADOWMAP_SIZE;
    float depth = texture2D(LIGHT_SHADOWMAP, coord.xy).r;
    shadow = coord.z - 2.0 * texel > depth ? 0.0 : 1.0;
#endif
    float diffuse = max(dot(normalize(v_normal), normalize(u_light - v_position.xyz)), 0.0);
    gl_FragColor = vec4(vec3(0.1 + 0.9 * diffuse * shadow), 1.0);
}
