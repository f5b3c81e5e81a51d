#version 330
// Partial writes of every kind: a component (c.rgb += ...), a member by component
// (m.albedo.rg *= ...), array elements (a constant index after unrolling, and a per-pixel one),
// ++ on a float, and inout/out parameters written by component (inlined into assignments of
// the parameter's copy). The final colour reads all of them: it must be listed, not uniform,
// and cost everything that flowed into it.
in vec3 v_normal;
in vec4 v_position;
in vec2 v_texcoord;
uniform vec3 u_light;
out vec4 fragColor;

struct Material {
    vec3 albedo;
    float rough;
};

void shadeInto(inout vec4 c, vec3 n) {
    c.rgb += sin(n * 3.0) * cos(n * 5.0);
    c.a *= 0.5 + 0.5 * n.y;
}

void split(vec3 x, out vec3 lo, out vec2 hi) {
    lo.xy = exp(x.xy * 0.5) * 0.3;
    lo.z = log(2.0 + x.z);
    hi = x.yz * x.x;
}

void main() {
    vec3 n = normalize(v_normal);
    vec4 c = vec4(0.0, 0.0, 0.0, 1.0);
    c.rgb += sin(n) * cos(n);
    Material m;
    m.albedo = vec3(0.6, 0.5, 0.4);
    m.albedo.rg *= 0.5 + 0.5 * sin(v_position.xy * 4.0);
    m.rough = 0.3 + 0.2 * cos(v_position.z * 7.0);
    vec3 taps[3];
    for (int i = 0; i < 3; i++) {
        taps[i] = sin(v_position.xyz * float(i + 2));
    }
    int j = int(clamp(v_texcoord.x * 3.0, 0.0, 2.0));
    taps[j] += vec3(0.1) * exp(v_texcoord.y);
    float k = 0.0;
    k++;
    shadeInto(c, n);
    vec3 lo;
    vec2 hi;
    split(v_position.xyz, lo, hi);
    vec3 L = normalize(u_light - v_position.xyz);
    float diff = max(dot(n, L), 0.0);
    c.rgb = c.rgb * m.albedo * diff + (taps[0] + taps[1] * 0.5 + taps[2] * 0.25) * 0.1
          + lo * 0.05 + vec3(hi, k) * 0.02 * m.rough;
    fragColor = c;
}
