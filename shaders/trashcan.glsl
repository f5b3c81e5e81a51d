#version 330
// Trashcan: a shiny, dented metal can lit by an environment map.
//
// After the Toyshop trashcan shader used in Sitthi-amorn et al. 2008, section 5.2: the surface
// normal comes from a high-resolution tangent-space normal map; around that normal a 5x5 grid
// of perturbed normals reflects the view direction into a cube environment map, and the 25
// samples are combined with Gaussian weights (a glossy reflection filter). A small key-light
// highlight follows u_light. The result is tone mapped and gamma corrected.
//
// Every texture fetch uses an explicit level of detail, so no value depends on screen-space
// derivatives.

in vec4 v_position;
in vec3 v_normal;
in vec2 v_texcoord;
#ifdef MODEL_VERTEX_TANGENT
in vec4 v_tangent;
#endif

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform vec2 u_resolution;
uniform mat4 u_projectionMatrix;

uniform sampler2D u_normalMap;    // tangent-space normals, RGB in [0,1]
uniform samplerCube u_envMap;     // linear HDR radiance
uniform vec2 u_normalTiling;      // texcoord -> normal-map repeats (around, along)
uniform float u_normalTexelsPerUnit; // normal-map texels per world unit (for the LOD)
uniform float u_bumpStrength;     // scales the tangent-space xy of the normal map
uniform vec3 u_metalColor;        // reflectance of the metal at normal incidence
uniform float u_exposure;

out vec4 fragColor;

// Glossy filter: 5x5 normals spaced GRID_SPACING apart (in tangent units), Gaussian weights.
const int GRID_SIZE = 5;
const float GRID_SPACING = 0.06;
const float GAUSSIAN_SIGMA = 1.2;       // in grid steps
const float ENV_LOD = 1.0;              // pre-blur of each environment sample
// Key-light highlight.
const float KEY_SHININESS = 180.0;
const float KEY_STRENGTH = 2.5;
const float GAMMA = 2.2;
const float MAX_NORMAL_LOD = 8.0;

// A unit vector perpendicular to n, used when the mesh has no tangents (surfaces of revolution
// about +Y: the tangent runs around the axis).
vec3 fallbackTangent(vec3 n) {
    vec3 axis = abs(n.y) > 0.999 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    return normalize(cross(axis, n));
}

// Level of detail for the normal map from the pixel footprint at this distance.
float normalMapLod(vec3 position) {
    float pixelAngle = 2.0 / (u_projectionMatrix[1][1] * u_resolution.y);
    float footprint = distance(u_camera, position) * pixelAngle * u_normalTexelsPerUnit;
    return clamp(log2(max(footprint, 1.0)), 0.0, MAX_NORMAL_LOD);
}

// The shading normal: the normal map in the tangent frame of the surface.
vec3 mappedNormal(vec3 N, vec3 T, float handedness, vec2 uv, float lod) {
    vec3 B = cross(N, T) * handedness;
    vec3 tn = textureLod(u_normalMap, uv * u_normalTiling, lod).xyz * 2.0 - 1.0;
    tn.xy *= u_bumpStrength;
    return normalize(T * tn.x + B * tn.y + N * tn.z);
}

// Gaussian weight of grid cell (i, j), centred on the middle cell.
float gridWeight(int i, int j) {
    vec2 d = vec2(float(i - GRID_SIZE / 2), float(j - GRID_SIZE / 2));
    return exp(-dot(d, d) / (2.0 * GAUSSIAN_SIGMA * GAUSSIAN_SIGMA));
}

// Schlick's Fresnel for a metal of reflectance f0.
vec3 fresnelSchlick(vec3 f0, float cosTheta) {
    return f0 + (1.0 - f0) * pow(1.0 - clamp(cosTheta, 0.0, 1.0), 5.0);
}

void main() {
    vec3 P = v_position.xyz;
    vec3 N = normalize(v_normal);
    vec3 V = normalize(u_camera - P);

#ifdef MODEL_VERTEX_TANGENT
    vec3 T = normalize(v_tangent.xyz - N * dot(N, v_tangent.xyz));
    float handedness = v_tangent.w < 0.0 ? -1.0 : 1.0;
#else
    vec3 T = fallbackTangent(N);
    float handedness = 1.0;
#endif

    vec3 Nm = mappedNormal(N, T, handedness, v_texcoord, normalMapLod(P));

    // An orthonormal frame around the mapped normal for the grid of perturbed normals.
    vec3 Tm = normalize(T - Nm * dot(Nm, T));
    vec3 Bm = cross(Nm, Tm);

    // 25 environment samples on a 5x5 grid of normals, Gaussian weighted.
    vec3 radiance = vec3(0.0);
    float weightSum = 0.0;
    for (int i = 0; i < GRID_SIZE; i++) {
        for (int j = 0; j < GRID_SIZE; j++) {
            vec2 offset = vec2(float(i - GRID_SIZE / 2), float(j - GRID_SIZE / 2)) * GRID_SPACING;
            vec3 n = normalize(Nm + Tm * offset.x + Bm * offset.y);
            vec3 R = reflect(-V, n);
            float w = gridWeight(i, j);
            radiance += w * textureLod(u_envMap, R, ENV_LOD).rgb;
            weightSum += w;
        }
    }
    radiance /= weightSum;

    // Metal: Fresnel-weighted reflection plus a sharp highlight of the key light.
    float cosView = max(dot(Nm, V), 0.0);
    vec3 reflectance = fresnelSchlick(u_metalColor, cosView);
    vec3 L = normalize(u_light - P);
    vec3 H = normalize(L + V);
    float key = pow(max(dot(Nm, H), 0.0), KEY_SHININESS) * KEY_STRENGTH;
    vec3 color = reflectance * (radiance + key * u_lightColor);

    // Exposure, a soft shoulder, then gamma.
    color = 1.0 - exp(-color * u_exposure);
    fragColor = vec4(pow(color, vec3(1.0 / GAMMA)), 1.0);
}
