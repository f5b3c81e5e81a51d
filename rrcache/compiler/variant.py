"""The compiled variant: one cached node, every pass of one algorithm, ready to run.

A :class:`Variant` holds, per pass, the vertex and fragment sources (and the fragment line map
to the original shader), what the application must bind, and how the runtime must be set up
(payload precision, reconstruction filter). :meth:`Variant.manifest` describes it as JSON,
:meth:`Variant.write` writes ``<pass>.vert``, ``<pass>.frag`` and ``manifest.json``, and
:meth:`Variant.build_programs` links the programs for :class:`rrcache.runtime.CacheRuntime`::

    variant = instance(analysed, node_id)            # rrcache.compiler.instance
    programs = variant.build_programs(ctx)
    rt = variant.runtime(ctx, programs, (w, h), spec=variant.spec.with_runtime(periods=(16,)))
    variant.write("out/", period=16)                 # the manifest records the period it ran with

``variant.spec`` (a :class:`rrcache.runtime.spec.VariantSpec`) is what was compiled: the kind, the
nodes, the algorithm, the filter and payload, and the runtime's fields at their defaults; the
runtime takes a spec whole (:meth:`Variant.runtime`, with this variant's compiled facts: payload
components, where the inverse depth is kept, the 8-bit payload's decoding, the phase cycle). The
refresh period and the cache's other run-time parameters are not part of a variant (the same
passes run at any period): they are the spec's runtime fields, with their defaults in
:mod:`rrcache.runtime.cache` (``DEFAULT_PERIOD`` …).
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Optional

import moderngl

from rrcache import atomic
from rrcache.errors import GLError, SourceLoc
from rrcache.gl.program import build_program
from rrcache.runtime.cache import ALGORITHMS, DEFAULT_PERIOD, CacheRuntime
from rrcache.runtime.spec import VariantSpec


@dataclass
class PassSource:
    """The sources of one pass. ``fragment_line_map[i]`` is the original place of fragment line
    ``i + 1`` (None for generated lines)."""

    vertex: str
    fragment: str
    fragment_line_map: list[Optional[SourceLoc]] = field(default_factory=list)


@dataclass
class Variant:
    """A node cached with one algorithm.

    ``uniforms`` / ``samplers`` map each pass to the names the application binds (the vertex
    shader's per-object matrices included; the ``rr_`` ones, set by the runtime, are in
    ``runtime_uniforms``). ``forms`` records, per pass, how the value was bound (``hoist``,
    ``inline`` or ``replace``; see :mod:`rrcache.compiler.hoist`).
    """

    algorithm: str
    node_id: Any
    node_type: str
    node_text: str
    components: int
    filter: str
    payload_dtype: str
    passes: dict[str, PassSource]
    uniforms: dict[str, list[str]] = field(default_factory=dict)
    samplers: dict[str, list[str]] = field(default_factory=dict)
    runtime_uniforms: dict[str, list[str]] = field(default_factory=dict)
    forms: dict[str, str] = field(default_factory=dict)
    node_loc: Optional[SourceLoc] = None
    shader_path: Optional[str] = None
    vertex_path: Optional[str] = None  # the user's vertex shader (None: generated)
    # an amortized estimator (rrcache.compiler.amortize): {"estimator", "samples" (m), "of" (N),
    # "lambda", "phase", "cycle", "history", "accumulators"}; None for a cached node
    amortized: Optional[dict] = None
    #: the payload channel holding the inverse depth (None: its own texture); the runtime must
    #: be made with it (``CacheRuntime(..., depth_channel=variant.depth_channel)``)
    depth_channel: Optional[int] = None
    # adaptive refresh (rrcache.runtime.adaptive): the passes keep each entry's volatility
    adaptive: bool = False
    #: what was compiled (the runtime's fields at their defaults); the compiler sets it
    spec: Optional[VariantSpec] = None

    #: the runtime class these passes run in (MultiVariant: one cache per node)
    runtime_class = CacheRuntime

    @property
    def node_count(self) -> int:
        """The cached values: one (MultiVariant: one per node, each with its own period)."""
        return 1

    def describe(self) -> str:
        """What is cached, for messages: ``node n12 'sin(x)'``."""
        what = "estimator" if self.amortized else "node"
        return f"{what} {self.node_id} '{self.node_text}'"

    def runtime(self, ctx: moderngl.Context, programs: dict, size: tuple[int, int],
                spec: Optional[VariantSpec] = None, **target):
        """The runtime that runs these passes (:attr:`runtime_class`), made from ``spec`` (this
        variant's spec with the runtime's fields it runs with; default :attr:`spec`) and this
        variant's compiled facts; ``target``: ``color_format``, ``clear_color``, ``seed``,
        ``cull_back_faces``, ``payload_dtype`` (see :meth:`rrcache.runtime.CacheRuntime.from_spec`)."""
        spec = spec if spec is not None else self.spec
        if spec is None:
            raise ValueError("this variant has no spec: compile it with rrcache.compiler (or rrcache.kinds.compile)")
        if spec.compiled() != self.spec.compiled():
            raise ValueError(f"the spec {spec.compiled()} is not the one these passes were compiled for "
                             f"({self.spec.compiled()})")
        return self.runtime_class.from_spec(
            ctx, programs, spec, size, payload_components=self.components, depth_channel=self.depth_channel,
            payload_decode=self.payload_decode, phase_cycle=(self.amortized or {}).get("cycle", 1), **target)

    @property
    def pass_names(self) -> tuple[str, ...]:
        """The passes in the order the runtime runs them."""
        return ALGORITHMS[self.algorithm]

    @property
    def payload_decode(self) -> Optional[tuple[list[float], list[float]]]:
        """(offset, span) per payload channel of an 8-bit payload (``payload_dtype`` ``u8``: the
        passes store ``(value − offset) / span``, :mod:`rrcache.compiler.payload_encoding`), for
        the runtime's ``payload_decode``; None for a float payload."""
        enc = (self.amortized or {}).get("payload_encoding")
        return (list(enc["offset"]), list(enc["span"])) if enc else None

    def manifest(self, period: Optional[int] = None, runtime: Optional[dict] = None) -> dict:
        """A JSON-able description of the variant; ``period`` is the refresh period Δn it runs
        with (the runtime's default when None): the passes do not depend on it, the runtime
        takes it, and the manifest records it. ``runtime`` (the cache's other keyword arguments
        it ran with: ``block``, ``refresh``, ``depth_epsilon``) is recorded as ``"runtime"`` when
        given.

        >>> v = Variant("one-pass", 3, "float", "sin(x)", 1, "bilinear", "f4",
        ...             {"single": PassSource("vs", "fs")})
        >>> m = v.manifest()
        >>> m["passes"]["single"], m["node"]["type"], m["default_period"]
        ({'vertex': 'single.vert', 'fragment': 'single.frag', 'uniforms': [], 'samplers': [], 'runtime_uniforms': []}, 'float', 8)
        """
        node_id = self.node_id if isinstance(self.node_id, (int, str)) else None
        return {
            "rrcache_variant": 1,
            "node": {
                "id": node_id, "type": self.node_type, "text": self.node_text,
                "components": self.components,
                "location": str(self.node_loc) if self.node_loc else None,
            },
            "shader": self.shader_path,
            "vertex": self.vertex_path,  # the user's vertex shader the passes' .vert derive from (None: generated)
            "algorithm": self.algorithm,
            "filter": self.filter,
            "payload_dtype": self.payload_dtype,
            "depth_channel": self.depth_channel,
            "default_period": DEFAULT_PERIOD,
            "period": int(period) if period is not None else DEFAULT_PERIOD,
            "passes": {
                name: {
                    "vertex": f"{name}.vert", "fragment": f"{name}.frag",
                    "uniforms": list(self.uniforms.get(name, [])),
                    "samplers": list(self.samplers.get(name, [])),
                    "runtime_uniforms": list(self.runtime_uniforms.get(name, [])),
                }
                for name in self.passes
            },
            "uniforms": sorted({u for names in self.uniforms.values() for u in names}),
            "textures": sorted({s for names in self.samplers.values() for s in names}),
            **({"runtime": dict(runtime)} if runtime else {}),
            **({"amortized": dict(self.amortized)} if self.amortized else {}),
            **({"adaptive": True} if self.adaptive else {}),
        }

    def write(self, out_dir: "str | os.PathLike[str] | atomic.OutputFolder", period: Optional[int] = None,
              runtime: Optional[dict] = None) -> list[str]:
        """Write ``<pass>.vert``, ``<pass>.frag`` and ``manifest.json`` (recording ``period``
        and ``runtime``, see :meth:`manifest`) into ``out_dir`` (a folder path, created when
        missing, or an open :class:`~rrcache.atomic.OutputFolder`) by :mod:`rrcache.atomic`'s
        rule; returns the paths written."""
        if not isinstance(out_dir, atomic.OutputFolder):
            with atomic.OutputFolder(out_dir) as folder:
                return self.write(folder, period, runtime)
        written = []
        # each file whole or not at all (a full disk leaves no truncated shader or manifest)
        for name, src in self.passes.items():
            for ext, text in (("vert", src.vertex), ("frag", src.fragment)):
                written.append(out_dir.write_text(f"{name}.{ext}", text if text.endswith("\n") else text + "\n"))
        written.append(out_dir.write_text("manifest.json", json.dumps(self.manifest(period, runtime), indent=2) + "\n"))
        return written

    def build_programs(self, ctx: moderngl.Context) -> dict[str, moderngl.Program]:
        """Compile and link every pass. A pass the driver refuses raises :class:`GLError`
        naming the node and the pass (at the original line where the log allows); programs
        already linked are released first."""
        programs: dict[str, moderngl.Program] = {}
        for name, src in self.passes.items():
            shader = self.shader_path or "<shader>"
            try:
                programs[name] = build_program(
                    ctx, src.vertex, src.fragment, src.fragment_line_map,
                    fragment_name=f"{shader} ({name} pass)",
                    vertex_name=(f"{self.vertex_path} ({name} pass)" if self.vertex_path
                                 else f"<generated vertex shader of the {name} pass>"))
            except GLError as err:
                for prog in programs.values():
                    prog.release()
                new = GLError(
                    f"the {name} pass of the {self.algorithm} variant caching {self.describe()} was refused: "
                    f"{err.message}",
                    err.where, err.hint or "this is a bug in rrcache's compiler; please report it")
                new.loc = getattr(err, "loc", None)
                new.diagnostics = getattr(err, "diagnostics", [])
                new.pass_name = name
                raise new from None
        return programs
