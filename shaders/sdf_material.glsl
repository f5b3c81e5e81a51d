#version 330
// SDF material: a rasterized scene (ground, sphere, torus, box, cylinder) shaded with a
// ray-marched soft shadow and ambient occlusion of a signed distance field of the same scene.
//
// Per pixel, from the rasterized surface point: a soft shadow marched toward the light through
// the scene's SDF (up to 80 steps, Quilez's penumbra estimate with the improved nearest-approach
// term) and six-tap SDF ambient occlusion along the normal (Quilez, "Rendering worlds with two
// triangles", 2008), then a Blinn-Phong material. Up to 86 evaluations of the five-primitive
// distance field a pixel: a costly shader that is not noise. The occlusion depends only on the
// surface point and the shadow only on the point and the slowly orbiting light, so both are
// values a reverse reprojection cache can keep across frames while the camera moves.
//
// The primitives below must match the session's objects (sessions/sdf.json), all static, in
// world space. glslViewer conventions: v_position (world), v_normal (world), u_camera (eye),
// u_light (light position), u_lightColor.

in vec4 v_position;
in vec3 v_normal;

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;

uniform float u_penumbra;       // soft-shadow sharpness k (larger: harder shadows)
uniform float u_aoStrength;     // scales the occlusion sum
uniform vec3 u_groundColorA;    // the ground's checker squares
uniform vec3 u_groundColorB;
uniform vec3 u_objectColor;

out vec4 fragColor;

// The scene, as in sessions/sdf.json.
const vec3 SPHERE_CENTER = vec3(-1.1, 0.7, 0.3);
const float SPHERE_RADIUS = 0.7;
const vec3 TORUS_CENTER = vec3(1.0, 0.22, 0.7);
const vec2 TORUS_RADII = vec2(0.6, 0.22);
const vec3 BOX_CENTER = vec3(0.2, 0.6, -1.2);
const vec3 BOX_HALF = vec3(0.4, 0.6, 0.4);
const vec3 CYLINDER_CENTER = vec3(1.7, 0.8, -0.7);
const vec2 CYLINDER_SIZE = vec2(0.3, 0.8);   // radius, half height

const int SHADOW_STEPS = 80;
const float SHADOW_START = 0.02;
const float SHADOW_MAX = 8.0;
const float NORMAL_OFFSET = 0.01;
const int AO_TAPS = 6;
const float AMBIENT = 0.25;
const float SHININESS = 48.0;
const float SPECULAR_STRENGTH = 0.4;

float sdSphere(vec3 p, float r) { return length(p) - r; }

float sdTorus(vec3 p, vec2 t) {
    vec2 q = vec2(length(p.xz) - t.x, p.y);
    return length(q) - t.y;
}

float sdBox(vec3 p, vec3 b) {
    vec3 q = abs(p) - b;
    return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}

float sdCylinder(vec3 p, vec2 h) {
    vec2 d = abs(vec2(length(p.xz), p.y)) - h;
    return min(max(d.x, d.y), 0.0) + length(max(d, 0.0));
}

// Distance to the nearest surface of the scene (the ground is the plane y = 0).
float scene(vec3 p) {
    float d = p.y;
    d = min(d, sdSphere(p - SPHERE_CENTER, SPHERE_RADIUS));
    d = min(d, sdTorus(p - TORUS_CENTER, TORUS_RADII));
    d = min(d, sdBox(p - BOX_CENTER, BOX_HALF));
    d = min(d, sdCylinder(p - CYLINDER_CENTER, CYLINDER_SIZE));
    return d;
}

// Soft shadow toward the light: 0 in umbra, 1 unoccluded (Quilez's improved penumbra).
float softShadow(vec3 origin, vec3 dir, float maxT) {
    float result = 1.0;
    float t = SHADOW_START;
    float previous = 1e10;
    for (int i = 0; i < SHADOW_STEPS; i++) {
        float h = scene(origin + dir * t);
        float y = h * h / (2.0 * previous);
        float d = sqrt(max(h * h - y * y, 0.0));
        result = min(result, u_penumbra * d / max(t - y, 1e-4));
        previous = h;
        t += clamp(h, 0.02, 0.15);
        if (result < 0.001 || t > maxT) break;
    }
    result = clamp(result, 0.0, 1.0);
    return result * result * (3.0 - 2.0 * result);
}

// Ambient occlusion from AO_TAPS distance samples along the normal.
float ambientOcclusion(vec3 p, vec3 n) {
    float occlusion = 0.0;
    float weight = 1.0;
    for (int i = 1; i <= AO_TAPS; i++) {
        float h = 0.06 + 0.12 * float(i);
        occlusion += (h - scene(p + n * h)) * weight;
        weight *= 0.7;
    }
    return clamp(1.0 - u_aoStrength * occlusion, 0.0, 1.0);
}

vec3 albedo(vec3 p) {
    if (p.y < 0.005) {
        vec2 cell = floor(p.xz * 2.0);
        return mix(u_groundColorA, u_groundColorB, mod(cell.x + cell.y, 2.0));
    }
    return u_objectColor * (0.8 + 0.2 * sin(6.0 * p.y));
}

void main() {
    vec3 P = v_position.xyz;
    vec3 N = normalize(v_normal);
    vec3 toLight = u_light - P;
    float lightDistance = length(toLight);
    vec3 L = toLight / lightDistance;
    vec3 V = normalize(u_camera - P);
    vec3 H = normalize(L + V);

    vec3 origin = P + N * NORMAL_OFFSET;
    float shadow = softShadow(origin, L, min(lightDistance, SHADOW_MAX));
    float ao = ambientOcclusion(P, N);

    float diffuse = max(dot(N, L), 0.0) * shadow;
    float specular = pow(max(dot(N, H), 0.0), SHININESS) * shadow;
    vec3 color = albedo(P) * (AMBIENT * ao + diffuse * u_lightColor)
               + SPECULAR_STRENGTH * specular * u_lightColor;
    fragColor = vec4(pow(color, vec3(1.0 / 2.2)), 1.0);
}
