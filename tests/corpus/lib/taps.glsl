// Texture helpers that take their sampler as a parameter, the way blur, bicubic, triplanar and
// material-getter libraries are written. Included by sampler_params.glsl.
#ifndef TAPS_GLSL
#define TAPS_GLSL

// two taps a hundredth apart
vec4 tap2(sampler2D image, vec2 uv) {
    return 0.5 * (texture(image, uv) + texture(image, uv + vec2(0.01, 0.0)));
}

// a 9-tap binomial blur along `dir` in five bilinear fetches (taps 1-2 and 3-4 merged)
vec4 blur5(sampler2D image, vec2 uv, vec2 texel, vec2 dir) {
    vec4 sum = texture(image, uv) * 0.2734375;
    vec2 o1 = dir * texel * 1.3333333;
    vec2 o2 = dir * texel * 3.1111111;
    sum += (texture(image, uv + o1) + texture(image, uv - o1)) * 0.328125;
    sum += (texture(image, uv + o2) + texture(image, uv - o2)) * 0.03515625;
    return sum;
}

// a texture projected along the three axes, blended by the normal
vec3 triplanar(sampler2D tex, vec3 p, vec3 n, float scale) {
    vec3 w = abs(n);
    w /= (w.x + w.y + w.z);
    vec3 x = texture(tex, p.yz * scale).rgb;
    vec3 y = texture(tex, p.zx * scale).rgb;
    vec3 z = texture(tex, p.xy * scale).rgb;
    return x * w.x + y * w.y + z * w.z;
}

// a blurred environment look-up at an explicit level
vec3 envLight(samplerCube env, vec3 dir, float level) {
    return textureLod(env, dir, level).rgb;
}

// a helper that passes its sampler on to others
vec4 softTap(sampler2D image, vec2 uv, vec2 texel) {
    return mix(tap2(image, uv), blur5(image, uv, texel, vec2(1.0, 0.0)), 0.5);
}

#endif
