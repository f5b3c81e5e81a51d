#version 330
// Image-based lighting written the way glTF viewers write it: a base-colour texture, a
// tangent-space normal map, a Lambertian environment looked up along the normal
// (u_LambertianEnvSampler, with the environment's rotation), a GGX environment looked up along
// the reflection at a mip level chosen by the roughness (u_GGXEnvSampler), the split-sum BRDF
// (here its analytic fit instead of a lookup texture), single- and multiple-scattering energy
// terms, then an exposure, the ACES filmic tone curve and the sRGB transfer function.
//
// Texture fetches dominate it: two cube-map look-ups (one with an implicit level of detail)
// and two 2D fetches per pixel; the tone-map chain after them is a long run of cheap steps.

in vec4 v_position;
in vec3 v_normal;
in vec2 v_texcoord;

uniform vec3 u_camera;
uniform sampler2D u_BaseColorSampler;
uniform sampler2D u_NormalSampler;
uniform samplerCube u_LambertianEnvSampler;
uniform samplerCube u_GGXEnvSampler;
uniform mat3 u_EnvRotation;
uniform float u_EnvIntensity;
uniform float u_MipCount;
uniform float u_MetallicFactor;
uniform float u_RoughnessFactor;
uniform float u_NormalScale;
uniform vec2 u_UVScale;
uniform float u_Exposure;

out vec4 fragColor;

const float M_PI = 3.141592653589793;

struct MaterialInfo {
    vec3 baseColor;
    float metallic;
    float perceptualRoughness;
    vec3 f0;
    vec3 c_diff;
};

vec3 sRGBToLinear(vec3 srgb) {
    return pow(srgb, vec3(2.2));
}

// the surface normal from the normal map; a surface of revolution about +Y has its tangent
// running around the axis
vec3 getNormal(vec2 uv) {
    vec3 ng = normalize(v_normal);
    vec3 axis = abs(ng.y) > 0.999 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    vec3 t = normalize(cross(axis, ng));
    vec3 b = cross(ng, t);
    vec3 ntex = texture(u_NormalSampler, uv).rgb * 2.0 - 1.0;
    ntex.xy *= u_NormalScale;
    return normalize(mat3(t, b, ng) * ntex);
}

MaterialInfo getMaterial(vec2 uv) {
    MaterialInfo m;
    vec4 base = texture(u_BaseColorSampler, uv);
    m.baseColor = sRGBToLinear(base.rgb);
    m.metallic = u_MetallicFactor * base.a;
    m.perceptualRoughness = clamp(u_RoughnessFactor * (0.6 + 0.4 * base.g), 0.04, 1.0);
    m.f0 = mix(vec3(0.04), m.baseColor, m.metallic);
    m.c_diff = mix(m.baseColor, vec3(0.0), m.metallic);
    return m;
}

// the split-sum scale and bias (the fit of Karis 2014 in place of the 2D lookup texture)
vec2 getBRDF(float NdotV, float roughness) {
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 r = roughness * c0 + c1;
    float a004 = min(r.x * r.x, exp2(-9.28 * NdotV)) * r.x + r.y;
    return vec2(-1.04, 1.04) * a004 + r.zw;
}

vec3 getIBLRadianceGGX(vec3 n, vec3 v, float roughness, vec3 F0) {
    float NdotV = clamp(dot(n, v), 0.0, 1.0);
    float lod = roughness * (u_MipCount - 1.0);
    vec3 reflection = normalize(reflect(-v, n));
    vec2 brdf = getBRDF(NdotV, roughness);
    vec3 specularLight = textureLod(u_GGXEnvSampler, u_EnvRotation * reflection, lod).rgb;
    vec3 Fr = max(vec3(1.0 - roughness), F0) - F0;
    vec3 k_S = F0 + Fr * pow(1.0 - NdotV, 5.0);
    vec3 FssEss = k_S * brdf.x + brdf.y;
    return specularLight * FssEss;
}

vec3 getIBLRadianceLambertian(vec3 n, vec3 v, float roughness, vec3 diffuseColor, vec3 F0) {
    float NdotV = clamp(dot(n, v), 0.0, 1.0);
    vec2 brdf = getBRDF(NdotV, roughness);
    vec3 irradiance = texture(u_LambertianEnvSampler, u_EnvRotation * n).rgb;
    // multiple scattering (Fdez-Agüera 2019)
    vec3 Fr = max(vec3(1.0 - roughness), F0) - F0;
    vec3 k_S = F0 + Fr * pow(1.0 - NdotV, 5.0);
    vec3 FssEss = k_S * brdf.x + brdf.y;
    float Ems = 1.0 - (brdf.x + brdf.y);
    vec3 F_avg = F0 + (1.0 - F0) / 21.0;
    vec3 FmsEms = Ems * FssEss * F_avg / (1.0 - F_avg * Ems);
    vec3 k_D = diffuseColor * (1.0 - FssEss + FmsEms);
    return (FmsEms + k_D) * irradiance;
}

// ACES filmic (Hill's fit of the RRT and ODT)
vec3 RRTAndODTFit(vec3 color) {
    vec3 a = color * (color + 0.0245786) - 0.000090537;
    vec3 b = color * (0.983729 * color + 0.4329510) + 0.238081;
    return a / b;
}

vec3 toneMapACES(vec3 color) {
    const mat3 ACESInput = mat3(0.59719, 0.07600, 0.02840,
                                0.35458, 0.90834, 0.13383,
                                0.04823, 0.01566, 0.83777);
    const mat3 ACESOutput = mat3(1.60475, -0.10208, -0.00327,
                                 -0.53108, 1.10813, -0.07276,
                                 -0.07367, -0.00605, 1.07602);
    color = ACESInput * color;
    color = RRTAndODTFit(color);
    color = ACESOutput * color;
    return clamp(color, 0.0, 1.0);
}

vec3 linearTosRGB(vec3 color) {
    return pow(color, vec3(1.0 / 2.2));
}

vec3 toneMap(vec3 color) {
    color *= u_Exposure;
    color /= 0.6;
    color = toneMapACES(color);
    return linearTosRGB(color);
}

void main() {
    vec2 uv = v_texcoord * u_UVScale;
    MaterialInfo m = getMaterial(uv);
    vec3 n = getNormal(uv);
    vec3 v = normalize(u_camera - v_position.xyz);
    float roughness = m.perceptualRoughness;
    vec3 f_specular = getIBLRadianceGGX(n, v, roughness, m.f0);
    vec3 f_diffuse = getIBLRadianceLambertian(n, v, roughness, m.c_diff, m.f0);
    vec3 color = (f_diffuse + f_specular) * u_EnvIntensity;
    fragColor = vec4(toneMap(color), 1.0);
}
