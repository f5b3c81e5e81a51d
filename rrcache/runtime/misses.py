"""Why a cache misses: each missing pixel of a frame sorted by its cause (diagnostics).

A pixel misses for one of these reasons (:data:`MISS_CAUSES`, in this order of precedence):

``empty``         the cache holds nothing yet (the first frame, or after a reset or a cut);
``outside``       the surface was off the screen (or outside the window) or behind the camera
                  in the previous frame;
``disocclusion``  none of the four texels around the reprojected position holds this surface
                  (within twice the depth tolerance): the surface was hidden, or it is new;
``band``          the filter's hit test fails but a texel of the four with some bilinear weight
                  holds this surface (its inverse depth is this surface's there, predicted from
                  the depth's screen-space gradient, within the tolerance; the ``plane``
                  filter's test): the one- or two-pixel band
                  along every depth edge, where the bilinear mix of foreground and background
                  matches neither (a miss under ``bilinear``, a hit under ``edge``);
``refresh``       the surface is in the cache and the hit test passes, but the refresh rule
                  recomputes the pixel this frame.

The geometric cause comes from a small classifier program (:func:`classifier_glsl`: the
variant's own hit test, then the band and disocclusion tests where it fails) drawn with the
variant's own vertex shader against the previous frame's inverse depth, before the frame
(it reads the cache the frame's first pass reads; it changes nothing the frame uses); which
pixels actually hit comes from the frame's exact hit map, so the refresh rule (fixed or
adaptive) and the filter's hit test are the variant's own. A missing pixel whose geometric test
passed is a refresh; any other miss takes its geometric cause.

On llvmpipe a miss costs its whole 4x4 block (the fragment shader runs every lane of a block), so
:func:`summarise` counts the aligned 4x4 blocks holding a miss too, each block under the cause of
most of its missing pixels (refresh only when all of them are refreshes): refresh blocks are
aligned (k = 4), whole and cheap per pixel; the band and disocclusions scatter single pixels
over many blocks.

A shader that discards fragments is classified at the first surface the classifier draws, which
may differ from what the frame shows where the shader discards.
"""
from __future__ import annotations

from typing import Optional

import moderngl
import numpy as np

from rrcache.gl.window import crop_rows
from rrcache.runtime.glsl import PLANE_INPUTS

#: the causes, in order of precedence (a code's index + 1 in the classifier's output is its
#: geometric code; refresh is decided from the hit map)
MISS_CAUSES = ("empty", "outside", "disocclusion", "band", "refresh")

_CODE_CAUSE = {2: "band", 3: "disocclusion", 4: "outside", 5: "empty"}
#: the codes of a pixel that passed the filter's hit test (a miss there is a refresh)
_PASSED = (1, 6)

_CLASSIFIER_MAIN = """
layout(location = 0) out vec4 rr_missCause;

void main() {
    // codes: 1 a hit (the whole bilinear footprint), 6 a hit on this surface's texels alone
    // (edge, plane), 2 the band (a miss, but a texel with some bilinear weight holds this
    // surface), 3 a disocclusion, 4 outside the screen or behind the camera, 5 nothing cached
    float code;
    // this fragment's place and inverse depth in the previous frame's texels, and their
    // derivatives (taken here, in uniform control flow), to tell which texels hold this surface
    // (the plane filter's test, rrcache.runtime.glsl.PLANE_TEXELS)
""" + PLANE_INPUTS + """    bool hit = rr_hit();
    if (!rr_valid) {
        code = 5.0;
    } else if (hit) {
        code = ONE_SIDED ? 6.0 : 1.0;
    } else {
        vec2 uv = rr_prevClip.xy / rr_prevClip.w * 0.5 + 0.5;
        if (rr_prevClip.w <= 0.0 || any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) {
            code = 4.0;
        } else {
            ivec2 base;
            vec4 weights;
            vec4 ok = rr_planeTexels(p, expected, dpx, dpy, de, rr_depthEpsilon * expected, base, weights);
            code = dot(weights * ok, vec4(1.0)) >= 0.01 ? 2.0 : 3.0;
        }
    }
    rr_missCause = vec4(code, 0.0, 0.0, 1.0);
}
"""

def classifier_glsl(filter: str = "bilinear", depth_channel: Optional[int] = None) -> str:
    """The classifier's fragment shader: the hit test of ``filter`` (the variant's, from
    :func:`rrcache.runtime.glsl.lookup_glsl`) and, where it fails, the geometric cause.

    >>> "texelFetch(rr_prevPayload, t0, 0).y" in classifier_glsl("bilinear", 1)
    True
    """
    from rrcache.runtime.glsl import PLANE_TEXELS, lookup_glsl, packed_depth

    one_sided = "!rr_edgeFull" if filter in ONE_SIDED_FILTERS else "false"
    lookup = lookup_glsl(filter, depth_channel)
    texels = "" if "rr_planeTexels(" in lookup else packed_depth(PLANE_TEXELS, depth_channel)
    main = packed_depth(_CLASSIFIER_MAIN.replace("ONE_SIDED", one_sided), depth_channel)
    return "#version 330 core\n" + lookup + texels + main


#: the filters whose hit test accepts a pixel on some texels of its surface (``rr_edgeFull``)
ONE_SIDED_FILTERS = ("edge", "plane")


class MissClassifier:
    """Classify the pixels of the next frame of ``runtime`` (a one-node
    :class:`~rrcache.runtime.CacheRuntime`): ``vertex`` is the vertex shader of the variant's
    passes (they all share it); ``add_program(program)`` registers the classifier's program with
    whatever draws the scene (the harness's drawer) and returns nothing useful."""

    def __init__(self, ctx: moderngl.Context, runtime, vertex: str, filter: str = "bilinear", add_program=None):
        if len(runtime.node_components) > 1:
            raise ValueError("the miss breakdown is for one cached node (not several)")
        self.ctx = ctx
        self.runtime = runtime
        self.program = ctx.program(vertex_shader=vertex,
                                   fragment_shader=classifier_glsl(filter, runtime.depth_channel))
        if add_program is not None:
            add_program(self.program)
        self._size = None
        self._targets: list = []

    def _fbo(self):
        size = self.runtime.size
        if self._size != size:
            self._release_targets()
            self._codes = self.ctx.texture(size, 1, dtype="f4")
            self._depth = self.ctx.depth_texture(size)
            self._framebuffer = self.ctx.framebuffer([self._codes], self._depth)
            self._targets = [self._framebuffer, self._codes, self._depth]
            self._size = size
        self._framebuffer.scissor = self.runtime.window
        return self._framebuffer

    def classify(self, draw) -> np.ndarray:
        """Draw the scene with the classifier (``draw(program, "classify")``) before the runtime's
        next frame: the geometric code of each pixel's visible surface, float32 (height, width),
        row 0 = top, only the window when the runtime has one (0 where nothing was drawn)."""
        rt = self.runtime
        texture = rt._payload[1 - rt._index] if rt.depth_channel is not None else rt._invdepth[1 - rt._index]
        fbo = self._fbo()
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        ctx = self.ctx
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        unit = 12
        texture.use(unit)
        program = self.program
        name = "rr_prevInvDepth" if rt.depth_channel is None else "rr_prevPayload"
        for name, value in ((name, unit), ("rr_valid", bool(rt._valid)), ("rr_depthEpsilon", float(rt.depth_epsilon))):
            if name in program:
                program[name].value = value
        draw(program, "classify")
        w, h = rt.size
        codes = np.frombuffer(self._codes.read(), dtype=np.float32).reshape(h, w)
        return crop_rows(codes, rt.window).copy()

    def _release_targets(self) -> None:
        for res in self._targets:
            res.release()
        self._targets = []

    def release(self) -> None:
        self._release_targets()
        self.program.release()


def causes(codes: np.ndarray, hits: np.ndarray, covered: np.ndarray) -> np.ndarray:
    """Per pixel the index into :data:`MISS_CAUSES` of why it missed, -1 where it hit or is not
    covered (``codes`` from :meth:`MissClassifier.classify`, ``hits`` the frame's hit map,
    ``covered`` its covered pixels; all row 0 = top). A pixel that passed the filter's hit test
    and missed was refreshed."""
    out = np.full(codes.shape, -1, np.int8)
    missed = covered & ~hits
    rounded = np.rint(codes).astype(np.int64)
    passing = np.isin(rounded, _PASSED) | (rounded == 0)
    for code, cause in _CODE_CAUSE.items():
        out[missed & (rounded == code) & ~passing] = MISS_CAUSES.index(cause)
    out[missed & passing] = MISS_CAUSES.index("refresh")
    return out


def summarise(cause_map: np.ndarray, covered: np.ndarray, origin: tuple[int, int] = (0, 0),
              height: Optional[int] = None, block: int = 4) -> dict:
    """Counts of one frame: covered pixels and missing pixels per cause, and the aligned
    ``block``×``block`` blocks (aligned in GL window coordinates, origin bottom left; ``origin``
    the (x, y) of the map's bottom-left pixel in the target, ``height`` the map's rows) that
    cover something and that hold a miss, per cause (the cause of most of the block's missing
    pixels, refresh only when every one is a refresh).

    >>> m = np.full((4, 8), -1, np.int8); m[0, 0] = 4; m[1, 5] = 3
    >>> s = summarise(m, np.ones((4, 8), bool))
    >>> s["pixels"]["refresh"], s["pixels"]["band"], s["blocks"]["band"], s["covered_blocks"]
    (1, 1, 1, 2)
    """
    rows, cols = cause_map.shape
    height = rows if height is None else height
    gy = (origin[1] + (height - 1 - np.arange(rows)))[:, None] // block
    gx = (origin[0] + np.arange(cols))[None, :] // block
    block_id = (gy * 1_000_003 + gx).astype(np.int64)
    block_id = np.broadcast_to(block_id, cause_map.shape)
    covered_blocks = np.unique(block_id[covered]).size
    pixels = {c: int((cause_map == i).sum()) for i, c in enumerate(MISS_CAUSES)}
    blocks = {c: 0 for c in MISS_CAUSES}
    missed = cause_map >= 0
    if missed.any():
        ids, inverse = np.unique(block_id[missed], return_inverse=True)
        counts = np.zeros((ids.size, len(MISS_CAUSES)), np.int64)
        np.add.at(counts, (inverse, cause_map[missed].astype(np.int64)), 1)
        refresh = MISS_CAUSES.index("refresh")
        other = counts.copy()
        other[:, refresh] = 0
        winner = np.where(other.sum(axis=1) > 0, other.argmax(axis=1), refresh)
        for i, c in enumerate(MISS_CAUSES):
            blocks[c] = int((winner == i).sum())
    return {"covered": int(covered.sum()), "covered_blocks": int(covered_blocks), "pixels": pixels,
            "blocks": blocks, "block": block}


def add_summaries(total: Optional[dict], frame: dict) -> dict:
    """Two summaries (of frames) added up."""
    if total is None:
        return {k: (dict(v) if isinstance(v, dict) else v) for k, v in frame.items()}
    out = dict(total)
    for key in ("covered", "covered_blocks"):
        out[key] = total[key] + frame[key]
    for key in ("pixels", "blocks"):
        out[key] = {c: total[key][c] + frame[key][c] for c in MISS_CAUSES}
    return out
