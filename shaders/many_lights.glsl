#version 330
// Many lights: a GGX (Cook-Torrance) metal-and-paint material lit by a moving key light and 48
// static coloured point lights with inverse-square attenuation and a smooth range window.
//
// A costly shader that is not noise: every pixel loops over all 32 lights and evaluates the
// GGX distribution, Smith-Schlick visibility and Schlick Fresnel for each (about 40 operations a
// light). The diffuse sum of the static lights depends only on the surface point, so it is the
// kind of value a reverse reprojection cache can keep across frames while the camera moves; the
// specular sum and the key light change with the view and the moving light.
//
// The fill lights are placed on a golden-angle spiral around the object (no texture, no array
// uniform), so the session needs nothing but the mesh. glslViewer conventions: v_position
// (world), v_normal (world), v_objectPosition (object space), u_camera (eye), u_light (key light
// position), u_lightColor.

in vec4 v_position;
in vec3 v_normal;
in vec3 v_objectPosition;

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;

uniform vec3 u_paintColor;      // the albedo of the painted bands
uniform vec3 u_metalColor;      // F0 of the bare metal bands
uniform float u_roughness;      // GGX roughness of the paint (the metal is smoother)
uniform float u_lightRadius;    // distance of the fill lights from the origin
uniform float u_lightRange;     // a fill light's influence fades to zero at this distance

out vec4 fragColor;

const int NUM_LIGHTS = 32;
const float PI = 3.14159265;
const float GOLDEN_ANGLE = 2.39996323;
const float FILL_INTENSITY = 1.6;
const float KEY_INTENSITY = 14.0;
const float AMBIENT = 0.03;
// Object-space frequency of the paint/metal bands.
const float BAND_FREQUENCY = 3.0;

// Fill light i: a point on a golden-angle spiral over a sphere, squashed in y.
vec3 fillPosition(int i) {
    float t = (float(i) + 0.5) / float(NUM_LIGHTS);
    float y = 1.0 - 2.0 * t;
    float r = sqrt(max(1.0 - y * y, 0.0));
    float a = GOLDEN_ANGLE * float(i);
    return u_lightRadius * vec3(r * cos(a), 0.6 * y, r * sin(a));
}

// Fill light i's colour: a hue on the colour wheel, slightly desaturated.
vec3 fillColor(int i) {
    float h = fract(float(i) * 0.618034);
    vec3 rgb = clamp(abs(mod(h * 6.0 + vec3(0.0, 4.0, 2.0), 6.0) - 3.0) - 1.0, 0.0, 1.0);
    return mix(vec3(1.0), rgb, 0.6);
}

// Inverse-square falloff windowed to zero at u_lightRange (Karis 2013).
float attenuation(float distance2) {
    float ratio = distance2 / (u_lightRange * u_lightRange);
    float window = clamp(1.0 - ratio * ratio, 0.0, 1.0);
    return window * window / (distance2 + 1.0);
}

float ggx(float NdotH, float alpha) {
    float a2 = alpha * alpha;
    float d = NdotH * NdotH * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float smithVisibility(float NdotL, float NdotV, float alpha) {
    float k = alpha * 0.5;
    float gl = NdotL / (NdotL * (1.0 - k) + k);
    float gv = NdotV / (NdotV * (1.0 - k) + k);
    return gl * gv / max(4.0 * NdotL * NdotV, 1e-4);
}

vec3 fresnel(float VdotH, vec3 f0) {
    return f0 + (1.0 - f0) * pow(1.0 - VdotH, 5.0);
}

// Diffuse (Lambert) light from the static fill lights: depends on the surface point only.
vec3 fillDiffuse(vec3 P, vec3 N) {
    vec3 sum = vec3(0.0);
    for (int i = 0; i < NUM_LIGHTS; i++) {
        vec3 toLight = fillPosition(i) - P;
        float d2 = dot(toLight, toLight);
        float NdotL = max(dot(N, toLight * inversesqrt(d2)), 0.0);
        sum += fillColor(i) * (NdotL * attenuation(d2));
    }
    return FILL_INTENSITY * sum;
}

// GGX specular from the static fill lights: depends on the view.
vec3 fillSpecular(vec3 P, vec3 N, vec3 V, vec3 f0, float alpha) {
    vec3 sum = vec3(0.0);
    float NdotV = max(dot(N, V), 1e-3);
    for (int i = 0; i < NUM_LIGHTS; i++) {
        vec3 toLight = fillPosition(i) - P;
        float d2 = dot(toLight, toLight);
        vec3 L = toLight * inversesqrt(d2);
        float NdotL = max(dot(N, L), 0.0);
        vec3 H = normalize(L + V);
        float NdotH = max(dot(N, H), 0.0);
        float VdotH = max(dot(V, H), 0.0);
        vec3 brdf = ggx(NdotH, alpha) * smithVisibility(NdotL, NdotV, alpha) * fresnel(VdotH, f0);
        sum += fillColor(i) * brdf * (NdotL * attenuation(d2));
    }
    return FILL_INTENSITY * sum;
}

void main() {
    vec3 P = v_position.xyz;
    vec3 N = normalize(v_normal);
    vec3 V = normalize(u_camera - P);

    // Paint and bare-metal bands in object space.
    float band = smoothstep(-0.15, 0.15, sin(v_objectPosition.x * BAND_FREQUENCY * PI
                                              + 2.0 * v_objectPosition.z));
    vec3 albedo = mix(u_paintColor, vec3(0.02), band);
    vec3 f0 = mix(vec3(0.04), u_metalColor, band);
    float alpha = mix(u_roughness, 0.5 * u_roughness, band);
    alpha = alpha * alpha;

    vec3 color = albedo * (AMBIENT + fillDiffuse(P, N) / PI);
    color += fillSpecular(P, N, V, f0, alpha);

    // The moving key light.
    vec3 toKey = u_light - P;
    float keyD2 = dot(toKey, toKey);
    vec3 L = toKey * inversesqrt(keyD2);
    vec3 H = normalize(L + V);
    float NdotL = max(dot(N, L), 0.0);
    float NdotV = max(dot(N, V), 1e-3);
    vec3 keySpec = ggx(max(dot(N, H), 0.0), alpha) * smithVisibility(NdotL, NdotV, alpha)
                 * fresnel(max(dot(V, H), 0.0), f0);
    color += (albedo / PI + keySpec) * u_lightColor * (KEY_INTENSITY * NdotL / (keyD2 + 1.0));

    // Reinhard tone mapping and gamma.
    color = color / (1.0 + color);
    fragColor = vec4(pow(color, vec3(1.0 / 2.2)), 1.0);
}
