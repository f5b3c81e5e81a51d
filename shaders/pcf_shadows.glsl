// Percentage-closer filtering of a shadow map on a rotated Poisson disc (Reeves et al. 1987;
// Nehab et al. 2007 section 7.3): the fourth paper scene, a temple of columns (sessions/temple.json).
//
// Each pixel rotates the 16-tap Poisson disc by a random angle (a hash of its world position),
// so 16 taps give noise rather than banding. PCF_SAMPLES sets the number of taps: 16 by default;
// more taps go round the disc again at evenly spaced extra rotations, so -D PCF_SAMPLES=256 (16
// rotations of the disc) is the reference the 16-tap estimate is measured against.
//
// The shadow map comes from the harness, glslViewer's way: u_lightShadowMap (depth, read .r),
// u_lightMatrix and v_lightCoord, with LIGHT_SHADOWMAP_SIZE defined (sessions/temple.json's
// light has "shadow_map": {"size": 1024}).
#ifdef GL_ES
precision highp float;
#endif

#ifndef PCF_SAMPLES
#define PCF_SAMPLES 16
#endif
#ifndef LIGHT_SHADOWMAP_SIZE
#define LIGHT_SHADOWMAP_SIZE 1024.0
#endif

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform sampler2D u_lightShadowMap;
uniform float u_filterRadius;    // radius of the PCF disc, in shadow-map texels
uniform vec3 u_stoneColor;
uniform vec3 u_floorColor;

varying vec4 v_position;
varying vec3 v_normal;
varying vec4 v_lightCoord;

const float TWO_PI = 6.28318530718;

// The taps in an order whose every fourth tap (i = j*4 + k, k = 0..3) makes a disc of its own:
// the 16 taps' sum does not depend on the order, but amortized sampling (4 of the 16 per frame,
// the subset j*4 + k at phase k; rrcache.compiler.amortize) then evaluates four well-spread taps
// each frame rather than four that may cluster. The order was searched to minimise the error of
// the subsets' blended estimate (λ = 3/5) of step edges across the disc: 3.3x lower than the
// published order's (README, "Amortized sampling").
const vec2 POISSON[16] = vec2[16](
    vec2(-0.94201624, -0.39906216), vec2(0.53742981, -0.47373420),
    vec2(-0.81544232, -0.87912464), vec2(-0.91588581, 0.45771432),
    vec2(0.79197514, 0.19090188), vec2(-0.26496911, -0.41893023),
    vec2(-0.38277543, 0.27676845), vec2(0.97484398, 0.75648379),
    vec2(0.44323325, -0.97511554), vec2(0.34495938, 0.29387760),
    vec2(0.94558609, -0.76890725), vec2(0.14383161, -0.14100790),
    vec2(-0.24188840, 0.99706507), vec2(-0.81409955, 0.91437590),
    vec2(0.19984126, 0.78641367), vec2(-0.09418410, -0.92938870));

// A random angle per surface point (stable while the camera moves; a hash without sine).
float rotationAngle(vec3 p) {
    vec3 q = fract(floor(p * 211.0) * 0.1031);
    q += dot(q, q.yzx + 33.33);
    return fract((q.x + q.y) * q.z) * TWO_PI;
}

// How much of the light the shadow-map position uv sees at this depth: the comparisons with the
// four nearest texels, interpolated bilinearly (glslViewer/lygia's textureShadowLerp), so the
// filtered shadow has no texel steps.
float shadowTap(vec2 uv, float depth) {
    vec2 size = vec2(LIGHT_SHADOWMAP_SIZE);
    vec2 texel = uv * size - 0.5;
    vec2 f = fract(texel);
    vec2 base = (floor(texel) + 0.5) / size;
    float lb = depth > texture2D(u_lightShadowMap, base).r ? 0.0 : 1.0;
    float rb = depth > texture2D(u_lightShadowMap, base + vec2(1.0, 0.0) / size).r ? 0.0 : 1.0;
    float lt = depth > texture2D(u_lightShadowMap, base + vec2(0.0, 1.0) / size).r ? 0.0 : 1.0;
    float rt = depth > texture2D(u_lightShadowMap, base + vec2(1.0, 1.0) / size).r ? 0.0 : 1.0;
    return mix(mix(lb, rb, f.x), mix(lt, rt, f.x), f.y);
}

// The fraction of the disc around coord.xy that sees the light.
float pcf(vec3 coord, float angle, float bias) {
    float texel = 1.0 / LIGHT_SHADOWMAP_SIZE;
    float radius = u_filterRadius * texel;
    float depth = coord.z - bias;
    float lit = 0.0;
    for (int i = 0; i < PCF_SAMPLES; i++) {
        float a = angle + float(i / 16) * (TWO_PI / float((PCF_SAMPLES + 15) / 16));
        vec2 d = POISSON[i - 16 * (i / 16)];
        vec2 offset = vec2(d.x * cos(a) - d.y * sin(a), d.x * sin(a) + d.y * cos(a));
        lit += shadowTap(coord.xy + offset * radius, depth);
    }
    return lit / float(PCF_SAMPLES);
}

void main() {
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light - v_position.xyz);
    vec3 v = normalize(u_camera - v_position.xyz);
    float ndotl = max(dot(n, l), 0.0);
    vec3 coord = v_lightCoord.xyz / v_lightCoord.w;
    // receiver slope: the wider the disc and the more grazing the light, the larger the bias
    float slope = sqrt(1.0 - ndotl * ndotl) / max(ndotl, 0.3);
    float bias = (2.0 + 2.5 * u_filterRadius * slope) / LIGHT_SHADOWMAP_SIZE;
    float lit = pcf(coord, rotationAngle(v_position.xyz), bias);

    float floorness = step(0.9, n.y) * step(v_position.y, 0.01);
    vec3 albedo = mix(u_stoneColor, u_floorColor, floorness);
    vec3 h = normalize(l + v);
    float spec = pow(max(dot(n, h), 0.0), 40.0) * 0.25;
    vec3 color = albedo * (0.18 + 0.82 * ndotl * lit * u_lightColor) + spec * lit * u_lightColor;
    gl_FragColor = vec4(sqrt(color), 1.0);  // gamma 2
}
