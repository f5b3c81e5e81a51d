"""The WebGL2 target: a compiled variant's passes in GLSL ES 3.00 and a page that runs them in a
browser beside the original (``rrcache instance ... --target webgl2``).

:func:`write_page` takes what the compiler made (:func:`rrcache.compiler.instance`, through
:mod:`rrcache.pipeline`) and writes into a folder:

- ``<pass>.vert`` / ``<pass>.frag`` for every pass and ``original.vert`` / ``original.frag``, in
  GLSL ES 3.00 (:mod:`rrcache.webgl.glsl_es`);
- ``manifest.json``: the variant's manifest (:meth:`rrcache.compiler.Variant.manifest`) with
  ``"target": "webgl2"``;
- ``index.html``: the page (:mod:`rrcache.webgl.page`): the session's objects, camera path,
  light, uniforms and textures baked in (:mod:`rrcache.webgl.scene`), the original on the left
  and the cached variant on the right, each frame rendered with both, and each one's frame time
  (GPU timer queries where the browser has them, else the wall clock around each draw with a
  one-pixel read-back), the speed-up, and a slider for Δn. Open it on a machine with a GPU to
  see the speed-up there.

The page runs one cached node (three-pass, two-pass or one-pass, any filter, 32- or 16-bit
payload). An amortized estimator, adaptive refresh, several cached nodes or a packed inverse
depth are refused with a clear error, as is a session whose light has a shadow map.

>>> write_page(variant, session, work, "marble-e3-web", period=12)     # doctest: +SKIP
['marble-e3-web/reproject.vert', ..., 'marble-e3-web/index.html']
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Optional

from rrcache import atomic
from rrcache.errors import RRCacheError
from rrcache.webgl.glsl_es import to_glsl_es
from rrcache.webgl.page import page_html
from rrcache.webgl.scene import bake

__all__ = ["write_page", "page_data"]

PAGE_NAME = "index.html"

_EXPLAIN = """<p>Each frame the page renders the session's frame with the original shader into one
target and with the cached variant into another, then shows both. The cached variant is the
passes of its algorithm (<code>manifest.json</code> names them, in order), drawn over the same
geometry into the cache's targets: two ping-pong payload textures (RGBA, 32-bit float) and two
inverse-depth textures (R32F) at the render size, one depth buffer shared by the passes, and
this frame's colour. The first pass reprojects each pixel into the previous frame's cache
(through <code>u_prevModelViewProjectionMatrix</code>, last frame's matrix) and keeps the cached
value where the depth matches and the pixel is not due for refresh; the others compute the value
where it missed and shade. A pixel is refreshed every Δn frames in 4×4 blocks. The script at the
end of this file is the whole runtime: a port of rrcache's Python runtime
(<code>rrcache/runtime/cache.py</code> documents the passes' depth tests) that an engine can copy.
A jump in the session (the loop back to frame 0) starts the cache empty, as a camera cut does.</p>"""


def _refuse(what: str) -> RRCacheError:
    return RRCacheError(f"the WebGL2 target runs one cached node; {what} is not supported there", "--target webgl2",
                        hint="write it with --target glsl (the default) and run it with rrcache.CacheRuntime")


def page_data(variant, session, work, period: int, runtime: Optional[dict] = None,
              size: Optional[tuple[int, int]] = None) -> dict:
    """The page's data: ``variant`` (algorithm, pass order, GLSL ES sources, period, the cache's
    options, payload precision, node), ``original`` (its GLSL ES sources) and ``scene``
    (:func:`rrcache.webgl.scene.bake` at ``size``, default the session's resolution)."""
    from rrcache.compiler.vertex import vertex_for
    from rrcache.runtime import DEFAULT_BLOCK, DEFAULT_DEPTH_EPSILON, DEFAULT_REFRESH

    if variant.amortized:
        raise _refuse("an amortized estimator")
    if variant.adaptive:
        raise _refuse("adaptive refresh")
    if getattr(variant, "nodes", None) or isinstance(period, (list, tuple)):
        raise _refuse("a variant of several cached nodes")
    if variant.depth_channel is not None:
        raise _refuse("a payload with the inverse depth packed in")
    options = {"block": DEFAULT_BLOCK, "refresh": DEFAULT_REFRESH, "depth_epsilon": DEFAULT_DEPTH_EPSILON, "seed": 0}
    options.update({k: v for k, v in (runtime or {}).items() if k in options})
    passes = {}
    for name in variant.pass_names:
        src = variant.passes[name]
        passes[name] = {"vertex": to_glsl_es(src.vertex, "vertex", f"{name}.vert"),
                        "fragment": to_glsl_es(src.fragment, "fragment", f"{name}.frag")}
    prepared = work.prepared
    inputs = {n: d.type for n, d in prepared.inputs.items()}
    original_vertex = vertex_for(inputs, {n: d.loc for n, d in prepared.inputs.items()}, work.vertex)
    original = {"vertex": to_glsl_es(original_vertex, "vertex", "original.vert"),
                "fragment": to_glsl_es(prepared.source, "fragment", "original.frag")}
    size = tuple(size) if size is not None else tuple(int(v) for v in session.resolution)
    manifest = variant.manifest(period, runtime)
    return {"variant": {"algorithm": variant.algorithm, "order": list(variant.pass_names), "passes": passes,
                        "period": int(period), "options": options, "payload_dtype": variant.payload_dtype,
                        "filter": variant.filter, "node": manifest["node"]},
            "original": original,
            "scene": bake(session, prepared, size)}


def write_page(variant, session, work, out_dir, period: int, runtime: Optional[dict] = None) -> list[str]:
    """Write the WebGL2 target of ``variant`` (the compiled variant of ``work``, the shader loaded
    for ``session``) into ``out_dir``: the GLSL ES passes, the original, ``manifest.json`` and
    ``index.html`` (see the module docstring). Returns the paths written."""
    data = page_data(variant, session, work, period, runtime)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    sources = dict(data["variant"]["passes"], original=data["original"])
    for name, src in sources.items():
        for ext, stage in (("vert", "vertex"), ("frag", "fragment")):
            path = out / f"{name}.{ext}"
            atomic.write_text(path, src[stage] + "\n")
            written.append(str(path))
    manifest = dict(variant.manifest(period, runtime), target="webgl2", glsl="300 es",
                    original={"vertex": "original.vert", "fragment": "original.frag"}, page=PAGE_NAME)
    path = out / "manifest.json"
    atomic.write_text(path, json.dumps(manifest, indent=2) + "\n")
    written.append(str(path))
    node = manifest["node"]
    text = node["text"]
    try:  # the expression as written (the manifest's is the inlined one)
        text = work.node(node["id"]).text
    except (RRCacheError, AttributeError, TypeError):
        pass
    shader = os.path.basename(str(variant.shader_path or "shader"))
    where = os.path.basename(str(node["location"])) if node.get("location") else "?"
    title = f"rrcache: {shader}, original and cached"
    subtitle = (f"caching {node['id']} ({node['type']}, {where}: {text}) with {variant.algorithm}, "
                f"refresh every Δn = {int(period)} frames; session {os.path.basename(str(session.path))}, "
                f"{data['scene']['frames']} frames at {data['scene']['size'][0]}×{data['scene']['size'][1]}")
    path = out / PAGE_NAME
    atomic.write_text(path, page_html(title, subtitle, data, _EXPLAIN))
    written.append(str(path))
    return written
