"""A generator of large, realistic fragment shaders for the front-end benchmark.

Real shaders grow by libraries: hash and noise functions, fbm loops over them, material structs
filled member by member, lighting helpers with ``out``/``inout`` parameters, texture lookups with
implicit level of detail, small arrays. :func:`realistic_shader` writes ``modules`` such blocks
(each its own set of helper functions, as a shader assembled from several libraries has) and a
``main`` that calls every module and accumulates the colour by component, until the source has
about ``target_lines`` lines. The shader reads only the harness's varyings, so it renders too.

:func:`sketch_shader` writes the other common shape, a long ``main`` of straight-line code as
ES sketches are written (a folding, rotating point and a distance refined step after step, the
colour built by component): every value depends on all the steps before it, which is what made
the old cacheable-set closure quadratic in time and memory.

>>> src = realistic_shader(400)
>>> 300 < src.count("\\n") <= 400 and "texture(u_tex" in src
True
>>> 300 < sketch_shader(400).count("\\n") <= 400
True
"""
from __future__ import annotations

__all__ = ["realistic_shader", "sketch_shader"]

_HEADER = """#version 330
in vec4 v_position;
in vec3 v_normal;
in vec2 v_texcoord;
uniform float u_time;
uniform vec3 u_light;
uniform vec3 u_camera;
uniform sampler2D u_tex;
out vec4 fragColor;

struct Material {
    vec3 albedo;
    float roughness;
    vec3 emission;
};
"""

_MODULE = """
// ---- module {k} ----
float hash_{k}(vec3 p) {{
    p = fract(p * 0.3183099 + vec3(0.{k1}, 0.{k2}, 0.{k3}));
    p *= 17.0;
    return fract(p.x * p.y * p.z * (p.x + p.y + p.z));
}}

float noise_{k}(vec3 x) {{
    vec3 i = floor(x);
    vec3 f = fract(x);
    f = f * f * (3.0 - 2.0 * f);
    return mix(mix(mix(hash_{k}(i + vec3(0.0, 0.0, 0.0)), hash_{k}(i + vec3(1.0, 0.0, 0.0)), f.x),
                   mix(hash_{k}(i + vec3(0.0, 1.0, 0.0)), hash_{k}(i + vec3(1.0, 1.0, 0.0)), f.x), f.y),
               mix(mix(hash_{k}(i + vec3(0.0, 0.0, 1.0)), hash_{k}(i + vec3(1.0, 0.0, 1.0)), f.x),
                   mix(hash_{k}(i + vec3(0.0, 1.0, 1.0)), hash_{k}(i + vec3(1.0, 1.0, 1.0)), f.x), f.y), f.z);
}}

float fbm_{k}(vec3 p) {{
    float sum = 0.0;
    float amp = 0.5;
    for (int o = 0; o < {octaves}; o++) {{
        sum += amp * noise_{k}(p);
        p = p * 2.02 + vec3(0.13, 0.71, 0.37);
        amp *= 0.5;
    }}
    return sum;
}}

void material_{k}(vec3 p, inout Material m) {{
    float n = fbm_{k}(p * {scale});
    m.albedo.rg *= vec2(0.6 + 0.4 * n, 0.8);
    m.albedo.b += 0.1 * n;
    m.roughness = clamp(n * 1.5, 0.05, 1.0);
}}

void lighting_{k}(vec3 n, vec3 l, vec3 v, Material m, out vec3 diffuse, out vec3 specular) {{
    vec3 h = normalize(l + v);
    float ndl = max(dot(n, l), 0.0);
    diffuse = m.albedo * ndl;
    specular.rgb = vec3(pow(max(dot(n, h), 0.0), 2.0 / (m.roughness * m.roughness + 0.01)));
    specular.g *= 0.9;
}}

vec3 module_{k}(vec3 p, vec3 n, vec2 uv) {{
    Material m;
    m.albedo = vec3(0.5, 0.45, 0.4);
    m.roughness = 0.5;
    m.emission = vec3(0.0);
    material_{k}(p, m);
    vec3 taps[3];
    for (int t = 0; t < 3; t++) {{
        taps[t] = texture(u_tex, uv * float(t + {k4})).rgb;
    }}
    m.albedo *= (taps[0] + taps[1] + taps[2]) / 3.0;
    vec3 diffuse;
    vec3 specular;
    lighting_{k}(n, normalize(u_light - p), normalize(u_camera - p), m, diffuse, specular);
    vec4 c = vec4(0.0, 0.0, 0.0, 1.0);
    c.rgb += diffuse + specular * 0.25;
    c.rgb += m.emission;
    return c.rgb;
}}
"""


def realistic_shader(target_lines: int = 8000, octaves: int = 6) -> str:
    """A shader of about ``target_lines`` lines (module docstring)."""
    per_module = _MODULE.count("\n") + 1
    modules = max(1, (target_lines - _HEADER.count("\n") - 12) // per_module)
    out = [_HEADER]
    for k in range(modules):
        out.append(_MODULE.format(k=k, k1=(k * 37) % 97 + 1, k2=(k * 53) % 89 + 1,
                                  k3=(k * 71) % 83 + 1, k4=k % 4 + 1, octaves=octaves,
                                  scale=f"{1.0 + 0.25 * (k % 7):.2f}"))
    out.append("\nvoid main() {\n    vec3 p = v_position.xyz;\n    vec3 n = normalize(v_normal);\n"
               "    vec4 color = vec4(0.0, 0.0, 0.0, 1.0);\n")
    for k in range(modules):
        out.append(f"    color.rgb += module_{k}(p, n, v_texcoord);\n")
    out.append(f"    color.rgb /= {float(modules)};\n    fragColor = color;\n}}\n")
    return "".join(out)


_SKETCH_HEAD = """#version 330
in vec4 v_position;
in vec3 v_normal;
in vec2 v_texcoord;
uniform float u_time;
out vec4 fragColor;

void main() {
    vec3 p0 = v_position.xyz;
    float d0 = length(p0) - 1.0;
    vec4 col = vec4(0.0, 0.0, 0.0, 1.0);
"""

_SKETCH_STEP = """    vec3 p{k} = abs(p{j}.yzx * 1.{a}) - vec3(0.{b}, 0.{c}, 0.3);
    p{k}.xy = vec2(p{k}.x * 0.8 - p{k}.y * 0.6, p{k}.x * 0.6 + p{k}.y * 0.8);
    float d{k} = min(d{j}, length(p{k}) * 0.5 - 0.{b});
    col.rgb += 0.02 * vec3(sin(d{k} * 3.0), cos(p{k}.z), exp(-abs(d{k})));
"""


def sketch_shader(target_lines: int = 8000) -> str:
    """An ES-sketch-shaped shader of about ``target_lines`` lines (module docstring)."""
    per_step = _SKETCH_STEP.count("\n")
    steps = max(1, (target_lines - _SKETCH_HEAD.count("\n") - 3) // per_step)
    out = [_SKETCH_HEAD]
    for k in range(1, steps + 1):
        out.append(_SKETCH_STEP.format(k=k, j=k - 1, a=k % 9 + 1, b=k % 7 + 1, c=k % 5 + 1))
    out.append(f"    fragColor = vec4(col.rgb * (0.5 + 0.5 * sin(d{steps})), 1.0);\n}}\n")
    return "".join(out)
