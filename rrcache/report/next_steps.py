"""What to do with a level's choice: the report's "Use it" part of each level's card.

Read from the files the profile wrote (the level's ``manifest.json`` in ``optimized/eN``): what
each file is (every pass of the algorithm, what it does and what it reads and writes), what the
manifest records, the code that runs the passes with :class:`rrcache.runtime.CacheRuntime` with
this level's options filled in, and the commands for the same choice elsewhere (the files again,
the browser page, a measurement) or for another level (``rrcache select``).

>>> code = runtime_snippet({"algorithm": "two-pass", "period": 50, "payload_dtype": "f4", "depth_channel": None,
...     "node": {"components": 3}, "runtime": {"block": 4, "refresh": "random", "depth_epsilon": 0.001},
...     "passes": {"hit": {"uniforms": ["u_light"]}, "miss": {"uniforms": ["u_scale"]}}},
...     "demo.rrprofile/optimized/e2", (640, 480))
>>> print(code[code.index("cache = "):code.index("\\n\\n\\ndef")])
cache = CacheRuntime(ctx, programs, "two-pass", (640, 480), period=50, payload_dtype="f4",
                     payload_components=3, block=4, refresh="random", depth_epsilon=0.001)
"""
from __future__ import annotations

import html
import json
import os
from pathlib import Path
from typing import Optional

#: what each pass of each algorithm does (rrcache/runtime/cache.py's docstring is the specification)
PASS_ROLES = {
    "reproject": "pass 1 of 3. Reprojects the pixel into the previous frame's cache; where the cached depth "
                 "matches and the pixel is not due for refresh, writes the cached value and its inverse depth "
                 "into this frame's cache; elsewhere it discards. Depth test less, depth writes on.",
    "payload": "pass 2 of 3. Runs only where pass 1 left no depth (early depth test): computes the value from "
               "scratch into this frame's cache.",
    "shade": "pass 3 of 3. The original shader with the value read from this frame's cache, into your colour "
             "target. Depth test equal, depth writes off.",
    "hit": "pass 1 of 2. Where the previous frame's cache holds this surface and the pixel is not due for refresh, "
           "shades it completely from the cached value (colour, the value and its inverse depth); elsewhere it "
           "discards. Depth test less, depth writes on.",
    "miss": "pass 2 of 2. Runs only where pass 1 left no depth (early depth test): shades from scratch and "
            "writes the value into this frame's cache. Render targets: colour, payload, inverse depth.",
    "single": "the one pass: a dynamic branch reuses the cached value at a hit or computes it.",
}

#: the algorithms in words
ALGORITHM_WORDS = {
    "three-pass": "three-pass (Sitthi-amorn et al. 2008): reproject, compute the missing values, shade",
    "two-pass": "two-pass (Nehab et al. 2007): shade the hits, then the misses",
    "one-pass": "one-pass: one shader with a dynamic branch",
}


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def read_manifest(prof, sel) -> Optional[dict]:
    """The level's ``manifest.json`` as the profile wrote it, or None (not written, or moved)."""
    if not sel.files or prof.path is None:
        return None
    from rrcache.budgets import budget
    from rrcache.files import Refused, read_file

    path = Path(prof.path) / sel.files / "manifest.json"
    try:  # by rrcache.files' rule, inside the profile's folder (profile.json names the folder)
        return json.loads(read_file(path, budget.document_bytes, [os.path.realpath(prof.path)]).data)
    except (Refused, ValueError):
        return None


def _components(manifest: dict):
    if "nodes" in manifest:
        return [int(n.get("components", 4)) for n in manifest["nodes"]]
    return int(manifest.get("node", {}).get("components", 4))


def _py(value) -> str:
    """A value as Python source, strings in double quotes."""
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        inner = ", ".join(_py(v) for v in value)
        return f"[{inner}]" if isinstance(value, list) else f"({inner})"
    return repr(value)


def runtime_snippet(manifest: dict, folder: str, size: tuple[int, int]) -> str:
    """Python that loads the level's passes from ``folder`` and makes the
    :class:`~rrcache.runtime.CacheRuntime` with every option of ``manifest`` written out."""
    kwargs = [f"period={_py(manifest['period'])}", f"payload_dtype={_py(manifest['payload_dtype'])}",
              f"payload_components={_py(_components(manifest))}"]
    for name, value in (manifest.get("runtime") or {}).items():
        kwargs.append(f"{name}={_py(value)}")
    if manifest.get("depth_channel") is not None:
        kwargs.append(f"depth_channel={_py(manifest['depth_channel'])}")
    amortized = manifest.get("amortized") or {}
    if amortized:
        kwargs.append(f"blend={_py(amortized.get('lambda', 0.0))}")
        if amortized.get("cycle", 1) > 1:
            kwargs.append(f"phase_cycle={_py(amortized['cycle'])}")
        enc = amortized.get("payload_encoding")
        if enc:
            kwargs.append(f"payload_decode=({_py(list(enc['offset']))}, {_py(list(enc['span']))})")
    uniforms = sorted({u for p in manifest["passes"].values() for u in p.get("uniforms", [])})
    textures = sorted({s for p in manifest["passes"].values() for s in p.get("samplers", [])})
    per_object = [u for u in uniforms if u in ("u_modelMatrix", "u_modelViewProjectionMatrix", "u_normalMatrix",
                                              "u_prevModelViewProjectionMatrix", "u_reprojectionMatrix")]
    others = [u for u in uniforms if u not in per_object]
    lines = ["import json", "from pathlib import Path", "", "import moderngl", "from rrcache.runtime import CacheRuntime",
             "", f"folder = Path({_py(str(folder))})",
             "manifest = json.loads((folder / \"manifest.json\").read_text())",
             "ctx = moderngl.create_standalone_context(backend=\"egl\")   # or your window's moderngl context",
             "programs = {name: ctx.program(vertex_shader=(folder / p[\"vertex\"]).read_text(),\n"
             "                              fragment_shader=(folder / p[\"fragment\"]).read_text())\n"
             "            for name, p in manifest[\"passes\"].items()}"]
    call = f"cache = CacheRuntime(ctx, programs, {_py(manifest['algorithm'])}, {_py(tuple(size))}, "
    rest = ", ".join(kwargs) + ")"
    # wrap the keyword arguments at about 110 columns
    text, line = [], call
    for part in rest.split(", "):
        piece = part + (", " if not part.endswith(")") else "")
        if len(line) + len(piece) > 112 and line.strip():
            text.append(line.rstrip())
            line = " " * 21 + piece
        else:
            line += piece
    text.append(line.rstrip())
    lines.append("\n".join(text))
    lines += ["", "", "def draw(program, pass_name):",
              "    \"\"\"Called once per pass each frame: set your uniforms on program and render your meshes",
              f"    (per object: {', '.join(per_object) or 'none'};",
              f"    per frame: {', '.join(others) or 'none'}"
              + (f"; textures: {', '.join(textures)}" if textures else "") + ").",
              "    u_prevModelViewProjectionMatrix is the object's model-view-projection of the previous frame.\"\"\"",
              "", "",
              "for frame in range(100):",
              "    stats = cache.frame(draw)    # the passes in order, then this frame's cache becomes the previous one",
              "    image = cache.read_color()   # or use cache.color (a moderngl texture) as your frame"]
    return "\n".join(lines) + "\n"


def _files_table(manifest: dict) -> str:
    rows = []
    for name, p in manifest["passes"].items():
        base = name.split("@")[0]
        role = PASS_ROLES.get(base, "")
        if "@" in name:
            role = f"the {base} pass at frames ≡ {name.split('@')[1]} (mod {manifest['amortized']['cycle']})"
        reads = ", ".join(p.get("uniforms", []) + p.get("samplers", []))
        rows.append(f"<tr><td><code>{_e(p['vertex'])}</code>, <code>{_e(p['fragment'])}</code></td><td>{_e(role)}"
                    f"<br><span class=\"muted\">you set: {_e(reads or 'nothing')}</span></td></tr>")
    what = ("the node" if "node" in manifest else "the nodes") + ", the algorithm, the refresh period it was chosen "
    what += ("with, the cache's options (refresh block, pattern, depth tolerance), and per pass the uniforms and "
             "textures you set and the rr_ uniforms the runtime sets")
    rows.append(f"<tr><td><code>manifest.json</code></td><td>{_e(what)}</td></tr>")
    return "<table class=\"files\">" + "".join(rows) + "</table>"


def _what(manifest: dict) -> str:
    runtime = manifest.get("runtime") or {}
    if "nodes" in manifest:
        cached = " + ".join(f"{n['id']} ({n.get('type')}) every Δn = {n['period']}" for n in manifest["nodes"])
    elif manifest.get("amortized"):
        a = manifest["amortized"]
        cached = (f"estimator {a['estimator']}: {a['samples']} of {a['of']} terms per frame, λ = {a['lambda']:g}, "
                  f"{a['history']} history")
    else:
        n = manifest["node"]
        cached = f"{n['id']} ({n['type']}, {n.get('location')}) every Δn = {manifest['period']} frames"
    options = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in runtime.items())
    return (f"{cached}; {ALGORITHM_WORDS.get(manifest['algorithm'], manifest['algorithm'])}; "
            f"{manifest['payload_dtype']} payload, {manifest.get('filter', 'bilinear')} filter"
            + (f"; {options}" if options else ""))


def level_commands(prof, sel) -> list[tuple[str, str]]:
    """(command, what it does) for this level's choice and for another level."""
    path = str(prof.path) if prof.path is not None else "PROFILE"
    other = (f"rrcache select {path} --min-psnr 38 --out DIR" if sel.min_psnr is not None or sel.max_error is None
             else f"rrcache select {path} --max-error 0.01 --out DIR")
    out = []
    if sel.parts:
        out += [(f"rrcache instance {path} --level {sel.label} --out DIR", "these files again (the same bytes)"),
                (f"rrcache instance {path} --level {sel.label} --target webgl2 --out DIR",
                 "the passes in GLSL ES 3.00 and a page running them beside the original in a browser, with each "
                 "one's frame time"),
                (f"rrcache render {path} --level {sel.label}", "measure this choice beside the original again")]
    out.append((other, "another level, chosen from the models in milliseconds, with its files"))
    return out


def next_steps_html(prof, sel, size: tuple[int, int]) -> str:
    """The "Use it" block of a level's card (see the module docstring)."""
    commands = "".join(f"<tr><td><code>{_e(c)}</code></td><td>{_e(w)}</td></tr>" for c, w in level_commands(prof, sel))
    commands = f"<table class=\"cmds\">{commands}</table>"
    if not sel.parts:
        return (f'<div class="next"><h4>Use it</h4><p>Keep your shader as it is: nothing cached pays at this level. '
                f"Another level:</p>{commands}</div>")
    manifest = read_manifest(prof, sel)
    if manifest is None:
        return (f'<div class="next"><h4>Use it</h4><p class="warn">The files of this level are not in '
                f"<code>{_e(sel.files)}</code> any more: write them again with the first command.</p>{commands}</div>")
    folder = str(Path(prof.path) / sel.files) if prof.path is not None else sel.files
    snippet = runtime_snippet(manifest, folder, size)
    return (f'<div class="next"><h4>Use it</h4><p>Files in <code>{_e(sel.files)}</code>: {_e(_what(manifest))}. '
            "Every pass draws your geometry with the same vertex processing; the cache is two ping-pong payload "
            "textures and two inverse-depth textures at your render size, and one depth buffer the passes share."
            f"</p>{_files_table(manifest)}<p>Run them in a moderngl render loop (another engine: port "
            "<code>rrcache/runtime/cache.py</code>, which this code drives; the WebGL2 page's script is a port "
            f"to JavaScript):</p><pre class=\"snippet\"><code>{_e(snippet)}</code></pre>{commands}</div>")
