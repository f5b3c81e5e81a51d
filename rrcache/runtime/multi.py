"""`MultiCacheRuntime`: the cache of a variant that caches k ≥ 2 nodes, each at its own rate.

:class:`MultiCacheRuntime` takes a sequence of periods (``period=(50, 4)``, one per node, in the
variant's node order; a compiled variant of several nodes makes it with
``variant.runtime(ctx, programs, size)``); everything else is as for one node
(the passes, their depth tests, the clears, the window, the queries: the frame loop is the
one-node runtime's). What differs:

- every node ``j`` has its own double-buffered payload (``payload_components[j]`` channels) and
  inverse-depth textures (:mod:`rrcache.runtime.multi_glsl` says why), attached in node order:
  node j's payload at colour attachment ``base + 2j``, its inverse depth at ``base + 2j + 1``
  (``base`` 0 for three-pass, 1 after the colour for two-pass and one-pass);
- every node has its own refresh period and its own seed (``seed + j``), so two nodes at the
  same period refresh different blocks; the phase follows from the seed and the clock as for
  one node (:func:`rrcache.runtime.refresh.refresh_uniforms`);
- the number of render targets and texture units is checked against the driver's
  ``GL_MAX_DRAW_BUFFERS``, ``GL_MAX_COLOR_ATTACHMENTS`` and ``GL_MAX_TEXTURE_IMAGE_UNITS`` before
  anything is allocated: a ``ValueError`` says how many nodes the driver allows.

A pixel is a miss for node j when the reprojection of node j's entry fails or node j refreshes
this frame (``rr_hit_j() && !rr_refreshNow_j()`` is its hit). The first pass of three-pass and
two-pass keeps only the pixels where every node hits; the passes after it compute, per node,
only the nodes that miss there (see :mod:`rrcache.compiler.multi_passes`). A three-pass variant
with ``node_j`` programs runs the per-node layout (:meth:`MultiCacheRuntime.frame`): the nodes'
passes in the order the programs are given.
"""
from __future__ import annotations

from typing import Sequence

import moderngl
import numpy as np

from rrcache.budgets import MAX_RUNTIME_PERIOD, check_period
from rrcache.errors import RRCacheError
from rrcache.gl.formats import bytes_per_texel
from rrcache.gl.limits import check_target_size, target_guard
from rrcache.runtime import glsl as G
from rrcache.runtime.cache import PAYLOAD_DTYPES, CacheRuntime
from rrcache.runtime.multi_glsl import suffixed
from rrcache.runtime.refresh import refresh_uniforms

#: the first texture unit of the nodes' cache textures (node j: 16 + 3j, + 1, + 2); the
#: application's own textures take the units from 0 up, as with one node (12, 13, 15)
FIRST_UNIT = 16

_PER_NODE_REFRESH = ("rr_period", "rr_refreshPhase", "rr_seed", "rr_refreshScale")


def target_budget(ctx: moderngl.Context, algorithm: str, k: int) -> None:
    """Raise ``ValueError`` when ``k`` nodes need more render targets or texture units than the
    driver allows."""
    base = 0 if algorithm == "three-pass" else 1
    needed = base + 2 * k
    info = ctx.info
    limit = min(int(info.get("GL_MAX_DRAW_BUFFERS", 8)), int(info.get("GL_MAX_COLOR_ATTACHMENTS", 8)))
    if needed > limit:
        allowed = (limit - base) // 2
        raise ValueError(
            f"caching {k} nodes with {algorithm} needs {needed} render targets (a payload and an "
            f"inverse depth per node{'' if base == 0 else ', plus the colour'}); this driver allows "
            f"{limit} (GL_MAX_DRAW_BUFFERS/GL_MAX_COLOR_ATTACHMENTS): cache at most {allowed} nodes"
            + (" or use three-pass" if base else ""))
    units = int(info.get("GL_MAX_TEXTURE_IMAGE_UNITS", 16))
    if FIRST_UNIT + 3 * k > units:
        raise ValueError(f"caching {k} nodes needs texture units up to {FIRST_UNIT + 3 * k - 1}; this "
                         f"driver has {units} (GL_MAX_TEXTURE_IMAGE_UNITS): cache at most "
                         f"{max((units - FIRST_UNIT) // 3, 0)} nodes")


class MultiCacheRuntime(CacheRuntime):
    """The cache of several nodes (see the module docstring). ``payload_components`` is one count per node; ``period`` reads
    as the tuple of periods and may be set to one int (every node) or a sequence."""

    def __init__(self, ctx: moderngl.Context, programs, algorithm: str = "three-pass",
                 size=(640, 480), *, period: Sequence[int], payload_components=None, seed: int = 0,
                 **kwargs):
        periods = tuple(period)
        k = len(periods)
        if k < 2:
            raise ValueError("a multi-node cache needs at least two periods")
        comps = tuple(payload_components) if payload_components is not None else (4,) * k
        if isinstance(payload_components, int):
            comps = (payload_components,) * k
        if len(comps) != k or any(c not in (1, 2, 3, 4) for c in comps):
            raise ValueError(f"payload_components must be {k} counts of 1 to 4 (one per node), "
                             f"not {payload_components!r}")
        if kwargs.get("payload_dtype", "f4") not in PAYLOAD_DTYPES:
            raise ValueError(f"a multi-node cache holds payloads of {PAYLOAD_DTYPES}, not {kwargs['payload_dtype']!r}")
        target_budget(ctx, algorithm, k)
        # per-node three-pass layout: programs "hit_j" and "node_j" per node, in the order they run
        self.node_passes = [name for name in programs if name.startswith("node_")]
        self._node_queries = [ctx.query(samples=True) for _ in self.node_passes]
        self.node_count = k
        self.node_components = comps
        self._periods = (1,) * k
        super().__init__(ctx, programs, algorithm, size, period=periods, seed=seed,
                         payload_components=max(comps), **kwargs)

    # ------------------------------------------------------------------ configuration

    @property
    def period(self):
        return self._periods

    @period.setter
    def period(self, value) -> None:
        values = (value,) * self.node_count if isinstance(value, (int, np.integer)) else tuple(value)
        if len(values) != self.node_count:
            raise ValueError(f"{self.node_count} periods expected (one per node), not {len(values)}")
        try:
            self._periods = tuple(check_period(v, "period", MAX_RUNTIME_PERIOD) for v in values)
        except RRCacheError as err:
            raise ValueError(str(err)) from None
        self._period = self._periods[0]

    # ------------------------------------------------------------------ resources

    def _cache_textures(self) -> list:
        return [t for pair in self._payloads + self._invdepths for t in pair]

    def bytes_per_pixel(self) -> int:
        """Depth, colour, each node's two payloads and two inverse depths, and the read-back."""
        size = 4 if self.payload_dtype == "f4" else 2
        return 4 + bytes_per_texel(self.color_format) + sum(2 * c * size + 2 * 4 for c in self.node_components) + 41

    def resize(self, size) -> None:
        w, h = int(size[0]), int(size[1])
        if w < 1 or h < 1:
            raise ValueError(f"viewport size must be positive, not {w}x{h}")
        check_target_size(self.ctx, (w, h), self.bytes_per_pixel(), "cache size")
        self._release_targets()
        ctx = self.ctx
        self.size = (w, h)
        k = self.node_count
        with target_guard((w, h), "cache size"):
            self.depth = ctx.depth_texture((w, h))
            self.color = ctx.texture((w, h), 4, dtype=self._color_dtype)
            self._payloads = [[ctx.texture((w, h), c, dtype=self.payload_dtype) for _ in range(2)]
                              for c in self.node_components]
            self._invdepths = [[ctx.texture((w, h), 1, dtype="f4") for _ in range(2)] for _ in range(k)]
            for tex in [t for pair in self._payloads + self._invdepths for t in pair]:
                tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
                tex.repeat_x = tex.repeat_y = False
            # the one-node names, for what the base class reads (node 0)
            self._payload, self._invdepth = self._payloads[0], self._invdepths[0]
            lead = [] if self.algorithm == "three-pass" else [self.color]
            self._cache_fbos = [ctx.framebuffer(lead + [t for j in range(k) for t in
                                                        (self._payloads[j][i], self._invdepths[j][i])], self.depth)
                                for i in range(2)]
            self._clear_fbos = [ctx.framebuffer([self._invdepths[j][i] for j in range(k)], self.depth)
                                for i in range(2)]
            self._out_fbo = ctx.framebuffer([self.color], self.depth)
            self._color_only_fbo = ctx.framebuffer([self.color])
            # node j's own targets (per-node three-pass: node j's pass writes only these)
            self._node_fbos = [[ctx.framebuffer([self._payloads[j][i], self._invdepths[j][i]], self.depth)
                                for i in range(2)] for j in range(k)]
            self._depth_only = [ctx.framebuffer(depth_attachment=self.depth) for _ in range(2)]
        self._resources = [self.depth, self.color, *[t for pair in self._payloads + self._invdepths for t in pair],
                           *self._cache_fbos, *self._clear_fbos, self._out_fbo, self._color_only_fbo,
                           *[f for pair in self._node_fbos for f in pair], *self._depth_only]
        self._make_zero_fbos()
        if self.window is not None:
            from rrcache.gl.window import check_window
            try:
                check_window(self.window, self.size)
            except ValueError:
                self.window = None
        self._apply_window()
        self.reset()

    def _apply_window(self) -> None:
        super()._apply_window()
        for pair in getattr(self, "_node_fbos", []) + [getattr(self, "_depth_only", [])]:
            for fbo in pair:
                fbo.scissor = self.window

    # ------------------------------------------------------------------ the frame

    def required_passes(self, algorithm: str, programs) -> tuple:
        if algorithm == "three-pass" and any(name.startswith("node_") for name in programs):
            return tuple(name for name in programs if name.startswith(("hit_", "node_"))) + ("shade",)
        return super().required_passes(algorithm, programs)

    def frame(self, draw, count: bool = True, after_first_pass=None):
        """As :meth:`CacheRuntime.frame`; with the per-node three-pass layout, per node j in the
        order of its programs: clear the depth, ``hit_j`` (depth ``<`` with writes, node j's
        targets: copies node j where it hits, discards where it misses), ``node_j`` (``<``: runs
        only where node j misses, early depth testing culls the rest, and computes it); then
        ``shade`` (``==``; the last ``node_j`` left the whole depth). ``misses`` is the most
        misses of any one node (a lower bound of the pixels where some node misses);
        ``after_first_pass`` runs after the first node's ``hit`` pass."""
        if not (self.algorithm == "three-pass" and self.node_passes):
            return super().frame(draw, count, after_first_pass)


        ctx = self.ctx
        self._begin_frame()
        ctx.depth_func = "<"
        queries = self._node_queries if count else [None] * len(self.node_passes)
        for n, name in enumerate(self.node_passes):
            j = int(name[5:])
            fbo = self._node_fbos[j][self._index]
            fbo.depth_mask = True
            fbo.use()
            if n:
                depth_only = self._depth_only[self._index]
                depth_only.depth_mask = True
                depth_only.use()
                depth_only.clear(depth=1.0)
                fbo.use()
            self._run(f"hit_{j}", draw)
            if after_first_pass and n == 0:
                after_first_pass()
                fbo.use()
            self._run(name, draw, queries[n])
        self._out_fbo.depth_mask = False
        self._out_fbo.use()
        ctx.depth_func = "=="
        second = self._queries[1] if count else None
        self._run("shade", draw, second)
        self._out_fbo.depth_mask = True
        covered = misses = None
        if count:
            misses, covered = max(int(q.samples) for q in queries), int(second.samples)
        return self._end_frame(covered, misses)

    def node_refresh_values(self, j: int) -> dict:
        """The refresh rule's uniforms of node ``j`` at the current clock (its own period and
        seed ``seed + j``), under node j's names."""
        values = refresh_uniforms(self.size, self._block, self._refresh_mode, self.seed + j,
                                  self._periods[j], self.clock)
        return {(suffixed(n, j) if n in _PER_NODE_REFRESH else n): v for n, v in values.items()}

    def _bind_cache_uniforms(self, program: moderngl.Program) -> None:
        prev = 1 - self._index
        for j in range(self.node_count):
            unit = FIRST_UNIT + 3 * j
            self._payloads[j][prev].use(unit)
            self._invdepths[j][prev].use(unit + 1)
            self._set(program, suffixed(G.PREV_PAYLOAD, j), unit)
            self._set(program, suffixed(G.PREV_INVDEPTH, j), unit + 1)
            if self.algorithm == "three-pass":
                self._payloads[j][self._index].use(unit + 2)
                self._set(program, suffixed(G.CUR_PAYLOAD, j), unit + 2)
            for name, value in self.node_refresh_values(j).items():
                self._set(program, name, value)
        self._set(program, "rr_valid", self._valid)
        self._set(program, "rr_depthEpsilon", self.depth_epsilon)

    # ------------------------------------------------------------------ read-back

    def read_payload(self, node: int = 0) -> np.ndarray:
        """Node ``node``'s cache payload of the last frame (height, width, 4; unused channels 0)."""
        c = self.node_components[node]
        payload = self._read(self._payloads[node][1 - self._index], c)
        if c < 4:
            payload = np.concatenate([payload, np.zeros(payload.shape[:2] + (4 - c,), np.float32)], axis=-1)
        return payload

    def read_payloads(self) -> list:
        """Every node's payload (:meth:`read_payload`), in node order."""
        return [self.read_payload(j) for j in range(self.node_count)]

    def read_inverse_depth(self, current: bool = False, node: int = 0) -> np.ndarray:
        """Node ``node``'s 1/w per pixel (0 where it holds nothing), row 0 = top (see
        :meth:`CacheRuntime.read_inverse_depth`; after the first pass every node's is non-zero
        exactly where every node hit)."""
        index = self._index if current else 1 - self._index
        return self._read(self._invdepths[node][index], 1)[..., 0]


