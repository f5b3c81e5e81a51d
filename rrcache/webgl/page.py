"""The WebGL2 page: one self-contained HTML file that runs the original shader and the cached
variant side by side in a browser, each with its frame time.

Everything is inside the file: the passes and the original in GLSL ES 3.00
(:mod:`rrcache.webgl.glsl_es`), the session's meshes, per-frame uniforms and textures
(:mod:`rrcache.webgl.scene`), and the runtime (``runtime.js`` beside this module: the cache of
:mod:`rrcache.runtime.cache` in about 480 lines of JavaScript over WebGL2). Open it from disk; it
fetches nothing. URL parameters: ``?period=N`` (the refresh period to start with),
``?size=WxH`` (the render size; keep the session's aspect ratio), ``?autoplay=0`` (start paused;
``window.rrcache.step(frame)`` renders one frame).
"""
from __future__ import annotations

import html
from pathlib import Path

from rrcache.jsonable import script_json

RUNTIME_JS = Path(__file__).with_name("runtime.js")

_CSS = """
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 0; color: #1d2330;
       background: #fbfbfd; }
header { background: #1d2330; color: #fff; padding: 14px 24px; }
header h1 { margin: 0; font-size: 19px; }
header p { margin: 4px 0 0; color: #c9cfdb; }
main { padding: 12px 24px 32px; }
.pair { display: inline-block; max-width: 100%; }  /* as wide as the canvas: each label over its half */
.labels { display: flex; }
.labels span { flex: 1; font-weight: 600; color: #5d6678; }
canvas { display: block; max-width: 100%; image-rendering: pixelated; background: #000; }
#times { font-size: 16px; font-variant-numeric: tabular-nums; }
.errors { display: none; color: #b3122e; white-space: pre-wrap; border: 1px solid #b3122e; padding: 8px; }
.notes { color: #5d6678; white-space: pre-wrap; }
code { background: #eef0f5; padding: 0 3px; }
"""


def page_html(title: str, subtitle: str, data: dict, explain: str) -> str:
    """The page (a string) for ``data``: ``{"variant", "original", "scene"}``."""
    e = lambda s: html.escape(str(s), quote=True)  # noqa: E731
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{e(title)}</title><style>{_CSS}</style></head><body>"
            f"<header><h1>{e(title)}</h1><p>{e(subtitle)}</p></header><main>"
            '<div class="pair"><div class="labels"><span>original</span><span>cached</span></div>'
            '<canvas id="view" width="2" height="1"></canvas></div>'
            '<p id="times">starting…</p>'
            '<p><button id="playpause">pause</button> refresh period Δn '
            '<input type="range" id="period" min="1" max="50"> <b id="periodText"></b> · <span id="frame"></span></p>'
            '<pre id="errors" class="errors"></pre><pre id="notes" class="notes"></pre>'
            f"<details><summary>How this page runs the cache</summary>{explain}</details>"
            f'</main><script id="rr-data" type="application/json">{script_json(data)}</script>'
            f"<script>{RUNTIME_JS.read_text(encoding='utf-8')}</script></body></html>\n")
