"""Measure what texture fetches and early-exit loops cost on this renderer, in the static cost
model's units (one scalar add or multiply; rrcache/analysis/cost.py).

    python tools/calibrate_costs.py [--size 256] [--repeats 15] [--threads 1] [--json OUT]

Each kernel is a full-frame fragment shader that does one operation N times in a dependent chain
(each step reads the last, so nothing is folded or skipped), drawn at two chain lengths; the
time per pixel per step is the difference of their median frame times (wall clock around the
draws and ``ctx.finish()``, kernels interleaved repeat by repeat) over the difference of N,
which cancels the frame's fixed costs. A control kernel does the same chain with the fetch
replaced by a multiply of its coordinate, so the fetch's own cost is its time minus the
control's, plus the multiply's 4 units. The unit is measured the same way on a chain of vec4
``(x + a) * b`` (8 units a step: the model counts per component, as llvmpipe runs SoA).

Textures are as sessions give them: a 1024x1024 RGBA8 2D texture and a 6x256x256 RGBA16F
cube map, both mipmapped (and the 2D one without mipmaps, as the cache's own targets are), read with spatially coherent coordinates (neighbouring pixels read
neighbouring texels, as a surface's UVs do).

The cache's own lookup (the runtime's hit test on a one-channel inverse depth and its bilinear
payload fetch, both without mipmaps) is timed the same way.

Early-exit loops: a 64-step loop of ALU work whose exit step is spread over the pixels evenly
(a smooth gradient across the frame, as a ray march's exits are: neighbours leave at nearby
steps) and the same loop with the exit step hashed per pixel, each timed against the loop that
runs all 64 steps; the ratio is the share of the full trip count such a loop costs.

Prints a table (and writes it as JSON with ``--json``); the numbers kept in
rrcache/analysis/cost.py came from this tool (the command is quoted there).
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

import numpy as np

VERTEX = """#version 400
in vec2 in_pos;
out vec2 v_uv;
void main() { v_uv = in_pos * 0.5 + 0.5; gl_Position = vec4(in_pos, 0.0, 1.0); }
"""

HEAD = """#version 400
in vec2 v_uv;
uniform sampler2D u_tex;
uniform sampler2D u_flat;
uniform samplerCube u_cube;
uniform sampler2D u_depth;
uniform sampler2D u_payload;
uniform vec4 u_a;
uniform vec4 u_b;
out vec4 fragColor;
"""

#: the step of each chain: ``c`` is the running vec4, ``p`` the coordinate the fetch reads
STEPS = {
    "alu": "c = (c + u_a) * u_b;",
    "control": "c += vec4(p, p) * u_a; p = v_uv + c.xy * 0.0001;",
    "texture 2D": "c += texture(u_tex, p); p = v_uv + c.xy * 0.0001;",
    "texture 2D, explicit LOD": "c += textureLod(u_tex, p, 1.0); p = v_uv + c.xy * 0.0001;",
    "texture 2D, no mipmaps": "c += texture(u_flat, p); p = v_uv + c.xy * 0.0001;",
    "textureGather 2D": "c += textureGather(u_tex, p); p = v_uv + c.xy * 0.0001;",
    "texelFetch 2D": "c += texelFetch(u_tex, ivec2(p * 1023.0), 0); p = v_uv + c.xy * 0.0001;",
    "texture cube": "c += texture(u_cube, vec3(p * 2.0 - 1.0, 0.7)); p = v_uv + c.xy * 0.0001;",
    "texture cube, explicit LOD": "c += textureLod(u_cube, vec3(p * 2.0 - 1.0, 0.7), 1.0); "
                                  "p = v_uv + c.xy * 0.0001;",
    "sin": "c = sin(c) * u_b + u_a;",
    "cache lookup (hit test + bilinear payload)": (
        "{ vec4 clip = vec4(p * 2.0 - 1.0, 0.5, 1.0 + c.z * 0.0001);"
        " vec2 uv = clip.xy / clip.w * 0.5 + 0.5;"
        " bool inside = !(any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))));"
        " float expected = 1.0 / clip.w; float stored = texture(u_depth, uv).r;"
        " bool hit = inside && abs(stored - expected) <= 0.001 * expected;"
        " c += hit ? texture(u_payload, uv) : vec4(0.0); } p = v_uv + c.xy * 0.0001;"),
}
#: the model's cost of one step besides the operation measured: control ``c += vec4(p,p) * a``
#: (4 + 4) and ``p = v_uv + c.xy * k`` (2 + 2), and for sin the vec4 multiply and add (8)
_CONTROL_UNITS = 12
_FETCH_STEP_UNITS = 8   # the fetch's step besides the fetch: c += (4), p = ... (4)

LOOP = """
void main() {{
    vec4 c = vec4(v_uv, v_uv.yx);
    float exit_at = {exit_at};
    for (int i = 0; i < 64; i++) {{
        c = (c + u_a) * u_b; c = (c + u_a) * u_b; c = (c + u_a) * u_b; c = (c + u_a) * u_b;
        {brk}
    }}
    fragColor = c;
}}
"""
EXITS = {
    "spread (a gradient)": "(v_uv.x * 0.5 + v_uv.y * 0.5) * 64.0",
    "hashed per pixel": "fract(sin(dot(v_uv, vec2(12.9898, 78.233))) * 43758.5453) * 64.0",
}


def kernel(step: str, n: int) -> str:
    body = "\n    ".join([step] * n)
    return HEAD + f"""
void main() {{
    vec4 c = vec4(v_uv, v_uv.yx);
    vec2 p = v_uv;
    {body}
    fragColor = c + vec4(p, p) * 0.0;
}}
"""


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--threads", type=int, default=1, help="LP_NUM_THREADS (llvmpipe's threads)")
    ap.add_argument("--short", type=int, default=8, help="steps of the short chain")
    ap.add_argument("--long", type=int, default=40, help="steps of the long chain")
    ap.add_argument("--json", help="write the table here too")
    args = ap.parse_args(argv)

    from rrcache.gl.context import get_context

    ctx = get_context(args.threads)
    size = args.size
    fbo = ctx.framebuffer(color_attachments=[ctx.texture((size, size), 4)])
    fbo.use()
    ctx.viewport = (0, 0, size, size)
    rng = np.random.default_rng(7)
    tex = ctx.texture((1024, 1024), 4, rng.integers(0, 256, (1024, 1024, 4), dtype=np.uint8).tobytes())
    tex.build_mipmaps()
    tex.use(0)
    flat = ctx.texture((1024, 1024), 4, rng.integers(0, 256, (1024, 1024, 4), dtype=np.uint8).tobytes())
    flat.use(2)
    # the cache's own targets: the inverse depth (R32F, all 1: every test passes) and the payload
    depth = ctx.texture((size, size), 1, np.ones((size, size), dtype="f4").tobytes(), dtype="f4")
    depth.use(3)
    payload = ctx.texture((size, size), 4, rng.random((size, size, 4), dtype=np.float32).tobytes(), dtype="f4")
    payload.use(4)
    faces = rng.random((6, 256, 256, 4), dtype=np.float32).astype("f2")
    cube = ctx.texture_cube((256, 256), 4, faces.tobytes(), dtype="f2")
    cube.build_mipmaps()
    cube.use(1)
    vbo = ctx.buffer(np.array([-1, -1, 3, -1, -1, 3], dtype="f4").tobytes())

    def program(fragment: str):
        prog = ctx.program(vertex_shader=VERTEX, fragment_shader=fragment)
        for name, value in (("u_tex", 0), ("u_cube", 1), ("u_flat", 2), ("u_depth", 3), ("u_payload", 4), ("u_a", (0.001, 0.002, 0.003, 0.004)),
                            ("u_b", (0.999, 0.998, 0.997, 0.996))):
            if name in prog:
                prog[name].value = value
        return prog, ctx.vertex_array(prog, [(vbo, "2f", "in_pos")])

    runs = {}
    for name, step in STEPS.items():
        for n in (args.short, args.long):
            runs[(name, n)] = program(kernel(step, n))
    for name, exit_at in EXITS.items():
        runs[("loop", name, "break")] = program(HEAD + LOOP.format(exit_at=exit_at,
                                                                   brk="if (float(i) >= exit_at) break;"))
    runs[("loop", "full")] = program(HEAD + LOOP.format(exit_at="0.0", brk=""))

    draws = 4
    times = {k: [] for k in runs}
    for _, vao in runs.values():      # compile and warm every kernel
        vao.render()
    ctx.finish()
    for _ in range(args.repeats):
        for key, (_, vao) in runs.items():
            ctx.finish()
            t0 = time.perf_counter()
            for _ in range(draws):
                vao.render()
            ctx.finish()
            times[key].append((time.perf_counter() - t0) / draws)
    ms = {k: statistics.median(v) * 1e3 for k, v in times.items()}
    pixels = size * size
    dn = args.long - args.short

    def per_step_ns(name: str) -> float:
        return (ms[(name, args.long)] - ms[(name, args.short)]) / dn / pixels * 1e6

    unit = per_step_ns("alu") / 8.0
    control = per_step_ns("control")
    table = {"unit_ns_per_pixel": unit, "size": size, "threads": args.threads,
             "repeats": args.repeats, "costs": {}, "early_exit": {}}
    rows = []
    for name in STEPS:
        if name in ("alu", "control"):
            continue
        if name == "sin":
            units = per_step_ns(name) / unit - 8.0
            model = 32
        else:
            units = (per_step_ns(name) - control) / unit + _CONTROL_UNITS - _FETCH_STEP_UNITS
            model = None
        table["costs"][name] = round(units, 1)
        rows.append((name, units, model))
    for name in EXITS:
        ratio = ms[("loop", name, "break")] / ms[("loop", "full")]
        table["early_exit"][name] = round(ratio, 3)
    print(f"one unit (a scalar add or multiply): {unit:.3f} ns per pixel; {size}x{size}, "
          f"LP_NUM_THREADS={args.threads}, median of {args.repeats}")
    print(f"{'operation':32s} {'units':>8s}")
    for name, units, model in rows:
        print(f"{name:32s} {units:8.1f}" + (f"   (model: {model})" if model else ""))
    for name, ratio in table["early_exit"].items():
        print(f"{'64-step loop, exit ' + name:32s} {ratio:8.3f} of the full trip count's time")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(table, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
