#version 330
// Marble: a solid-texture marble albedo built from five octaves of 3D Perlin gradient noise,
// lit with Blinn-Phong and a white specular highlight.
//
// The scene of Sitthi-amorn et al. 2008, section 5.1 ("Marble"): noise-based albedo on a detailed
// model, camera and light orbiting. The noise is Perlin's improved noise as GPUs of the paper's
// time ran it (GPU Gems 2 ch. 26): permutation and gradient tables in textures, about 400
// operations per pixel in all, close to the paper's 419 instructions. The noise is evaluated in object space (v_objectPosition) so
// the veins stick to the model when it moves.
//
// glslViewer conventions: v_position (world), v_normal (world), v_objectPosition (object space),
// u_camera (eye, world), u_light (light position, world), u_lightColor.

in vec4 v_position;
in vec3 v_normal;
in vec3 v_objectPosition;

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;

// Look of the marble, bound from the session.
uniform vec3 u_veinColor;       // dark veins
uniform vec3 u_baseColor;       // pale stone
uniform float u_noiseScale;     // object-space units -> noise lattice cells
uniform float u_shininess;      // Blinn-Phong exponent

out vec4 fragColor;

// Vein pattern: sin(x * VEIN_FREQUENCY + VEIN_TURBULENCE * turbulence(p)).
const float VEIN_FREQUENCY = 7.0;
const float VEIN_TURBULENCE = 5.0;
// Sharpens the zero crossings of the sine into thin veins.
const float VEIN_SHARPNESS = 3.0;
// Cloudy variation of the stone between the veins.
const float CLOUD_STRENGTH = 0.5;
// Octave step of the turbulence.
const float LACUNARITY = 2.0;
const float GAIN = 0.5;
// Lighting.
const vec3 SPECULAR_COLOR = vec3(1.0);
const float SPECULAR_STRENGTH = 0.6;
const float AMBIENT = 0.18;

// Perlin's improved noise (Perlin 2002) as GPU Gems 2 ch. 26 implements it on the GPU: the
// permutation table and the 16 gradient directions live in small textures (fetched exactly with
// texelFetch), eight hashed lattice corners per evaluation.
uniform sampler2D u_permutation;   // 256 x 1, R: a permutation of 0..255
uniform sampler2D u_gradients;     // 16 x 1, RGB: Perlin's 12 edge directions (+4 repeats)

float perm(float i) {
    return texelFetch(u_permutation, ivec2(int(mod(i, 256.0)), 0), 0).r;
}

float grad(float hash, vec3 offset) {
    return dot(texelFetch(u_gradients, ivec2(int(mod(hash, 16.0)), 0), 0).rgb, offset);
}

// Perlin's quintic fade curve 6t^5 - 15t^4 + 10t^3.
vec3 fade(vec3 t) {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// 3D Perlin gradient noise, roughly in [-1, 1].
float noise(vec3 p) {
    vec3 cell = mod(floor(p), 256.0);
    vec3 f = p - floor(p);
    vec3 w = fade(f);

    // Hash the eight lattice corners through the permutation table.
    float a = perm(cell.x) + cell.y;
    float aa = perm(a) + cell.z;
    float ab = perm(a + 1.0) + cell.z;
    float b = perm(cell.x + 1.0) + cell.y;
    float ba = perm(b) + cell.z;
    float bb = perm(b + 1.0) + cell.z;

    // Gradient dot offset at each corner, blended with the fade curve.
    float n000 = grad(perm(aa), f);
    float n100 = grad(perm(ba), f - vec3(1.0, 0.0, 0.0));
    float n010 = grad(perm(ab), f - vec3(0.0, 1.0, 0.0));
    float n110 = grad(perm(bb), f - vec3(1.0, 1.0, 0.0));
    float n001 = grad(perm(aa + 1.0), f - vec3(0.0, 0.0, 1.0));
    float n101 = grad(perm(ba + 1.0), f - vec3(1.0, 0.0, 1.0));
    float n011 = grad(perm(ab + 1.0), f - vec3(0.0, 1.0, 1.0));
    float n111 = grad(perm(bb + 1.0), f - vec3(1.0, 1.0, 1.0));
    float nx00 = mix(n000, n100, w.x);
    float nx10 = mix(n010, n110, w.x);
    float nx01 = mix(n001, n101, w.x);
    float nx11 = mix(n011, n111, w.x);
    float nxy0 = mix(nx00, nx10, w.y);
    float nxy1 = mix(nx01, nx11, w.y);
    return mix(nxy0, nxy1, w.z);
}

// Perlin's turbulence: five octaves of |noise|, each at twice the frequency and half the weight.
float turbulence(vec3 p) {
    float sum = 0.0;
    float frequency = 1.0;
    float amplitude = 1.0;
    for (int i = 0; i < 5; i++) {
        sum += amplitude * abs(noise(p * frequency));
        frequency *= LACUNARITY;
        amplitude *= GAIN;
    }
    return sum;
}

// Marble albedo: sine bands along x, displaced by turbulence; the zero crossings of the sine
// become thin dark veins in a pale stone clouded by the same turbulence.
vec3 marbleAlbedo(vec3 objectPosition) {
    vec3 p = objectPosition * u_noiseScale;
    float turb = turbulence(p);
    float bands = sin(p.x * VEIN_FREQUENCY + VEIN_TURBULENCE * turb);
    float vein = pow(1.0 - abs(bands), VEIN_SHARPNESS);
    vec3 stone = u_baseColor * (1.0 - CLOUD_STRENGTH * turb * (0.5 + 0.5 * bands));
    return mix(stone, u_veinColor, vein);
}

void main() {
    vec3 albedo = marbleAlbedo(v_objectPosition);

    vec3 N = normalize(v_normal);
    vec3 L = normalize(u_light - v_position.xyz);
    vec3 V = normalize(u_camera - v_position.xyz);
    vec3 H = normalize(L + V);

    float diffuse = max(dot(N, L), 0.0);
    float specular = pow(max(dot(N, H), 0.0), u_shininess);

    vec3 color = albedo * (AMBIENT + diffuse * u_lightColor)
               + SPECULAR_COLOR * SPECULAR_STRENGTH * specular * u_lightColor;
    fragColor = vec4(color, 1.0);
}
