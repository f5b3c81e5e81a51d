"""Loading a shader for a session, and compiling what a selection caches: the steps every command
shares.

A shader is loaded with the ``MODEL_VERTEX_*`` defines of the session's meshes (plus the user's
``-D`` defines; :func:`rrcache.compiler.prepared.load_for_meshes`, the one place that does it),
prepared for the harness (core GLSL with a line map) and analysed (the cacheable nodes).
:func:`load_for_session` does the three once (the preparation when first asked for);
:func:`variant_for` compiles the variant of one node, and :func:`variant_for_selection` turns a
:class:`~rrcache.selection.Selection` into the variant and the refresh period it runs with.

The refresh period is not part of a variant: the same compiled passes run at any period. It is
given to the runtime (:class:`rrcache.runtime.CacheRuntime`, ``period=``) and recorded in the
manifest when the variant is written (:meth:`rrcache.compiler.Variant.write`, ``period=``).

>>> from rrcache.session import load_session
>>> work = load_for_session("shaders/glslviewer_basic.glsl", load_session("sessions/marble.json"))
>>> work.defines
{'MODEL_VERTEX_NORMAL': '1', 'MODEL_VERTEX_TANGENT': '1', 'MODEL_VERTEX_TEXCOORD': '1'}
>>> node = max(work.table.nodes, key=lambda n: n.cost)
>>> variant = variant_for(work, node.id, "two-pass")
>>> variant.algorithm, sorted(variant.passes)
('two-pass', ['hit', 'miss'])
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import cached_property
from typing import Mapping, Optional

from rrcache.analysis import cacheable_nodes
from rrcache.analysis.unroll import DEFAULT_MAX_ITERATIONS
from rrcache import kinds
from rrcache.compiler import Variant
from rrcache.compiler.prepared import PreparedShader, combined_hash, load_for_meshes, load_user_vertex, prepare
from rrcache.errors import RRCacheError
from rrcache.glsl.frontend import Shader
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.runtime.spec import VariantSpec
from rrcache.selection import Selection
from rrcache.session.changes import per_frame_uniforms


@dataclass
class ShaderWork:
    """A shader loaded for a session: the checked ``shader``, the ``table`` of cacheable nodes,
    the ``defines`` used and (made when first read) the harness's ``prepared`` core source."""

    shader: Shader
    table: object
    defines: dict
    #: the user's vertex shader (``UserVertex``), or None when the harness generates it
    vertex: object = None
    #: the command line's include folders (absolute; the session's own are in the session)
    include_dirs: tuple = ()
    #: the unroll limit the table was analysed with (part of the compile cache's key)
    max_unroll: int = DEFAULT_MAX_ITERATIONS
    #: the cache filter every variant of this work compiles with unless told otherwise (a
    #: profile's: ``Profile.filter``, chosen by rrcache.profiler.filters)
    filter: str = DEFAULT_FILTER
    #: the measured order of its sums (rrcache.profiler.terms; node ids refer to the program it
    #: ordered; part of the compile cache's key); empty: none measured
    term_scores: dict = field(default_factory=dict)

    @cached_property
    def prepared(self) -> PreparedShader:
        return prepare(self.shader, self.defines, self.vertex)

    @property
    def hash(self) -> str:
        """The fragment shader's hash, covering the user's vertex shader too when there is one."""
        return combined_hash(self.shader.hash, self.vertex)

    def node(self, node_id: str):
        """The table entry (listed or excluded) with this id; an unknown id raises the analysis'
        error with a hint."""
        for entry in list(self.table.nodes) + list(self.table.excluded):
            if entry.id == node_id:
                return entry
        self.table.find(node_id)  # raises RRCacheError for an id that names no expression
        raise RRCacheError(f"node '{node_id}' is not a value rrcache can cache",
                           str(self.shader.path or "<string>"),
                           hint="pick an id listed by 'rrcache nodes SHADER --all'")


def load_for_session(shader_path, session=None, defines: Optional[Mapping[str, str]] = None,
                     include_dirs=(), max_unroll: int = DEFAULT_MAX_ITERATIONS, vertex=None,
                     term_scores=None) -> ShaderWork:
    """Load and analyse ``shader_path`` (loops of at most ``max_unroll`` iterations unrolled);
    with a ``session`` its meshes' attributes set the ``MODEL_VERTEX_*`` defines (``defines``
    win over them). Includes are looked up next to the including file, then in ``include_dirs``
    (``-I``), then in the session's ``"include_dirs"``. ``vertex`` is the path of the user's
    vertex shader (None: the session's ``"vertex"``, else a generated one). ``term_scores``: the
    measured order of sums whose weights do not fold (:mod:`rrcache.profiler.terms`; node ids
    then refer to the program ordered by them)."""
    dirs = all_include_dirs(include_dirs, session)
    shader, all_defines = load_for_meshes(shader_path, session, defines, dirs)
    user = load_user_vertex(vertex, session, all_defines, dirs)
    # what changes between the session's frames: the terms of a sum that read it go last
    moving = sorted(per_frame_uniforms(session)) if session is not None else ()
    table = cacheable_nodes(shader, max_iterations=max_unroll, moving=moving, scores=term_scores or None)
    return ShaderWork(shader, table, all_defines, user, tuple(os.path.abspath(d) for d in include_dirs or ()),
                      max_unroll=int(max_unroll), term_scores=dict(term_scores or {}))


def all_include_dirs(include_dirs=(), session=None) -> tuple[str, ...]:
    """The command line's ``-I`` folders, then the session's ``"include_dirs"``."""
    return tuple(include_dirs or ()) + tuple(getattr(session, "include_dirs", ()) or ())


def variant_for(work: ShaderWork, node_id: str, algorithm: str = "three-pass", filter: Optional[str] = None,
                payload_dtype: str = "f4", adaptive: bool = False) -> Variant:
    """The variant of ``work`` caching ``node_id`` (an id such as ``n42``; ``adaptive``: refreshed
    by :mod:`rrcache.runtime.adaptive`'s rule; ``filter``: the work's when not given), compiled
    once (:func:`rrcache.kinds.compile`)."""
    spec = VariantSpec("adaptive" if adaptive else "cache", (node_id,), algorithm, filter or work.filter, payload_dtype)
    return kinds.compile(work, spec)


def variant_for_nodes(work: ShaderWork, node_ids, algorithm: str = "three-pass", filter: Optional[str] = None,
                      payload_dtype: str = "f4") -> Variant:
    """The variant of ``work`` caching every node of ``node_ids`` (two or more; one:
    :func:`variant_for`), each with its own payload and period
    (:func:`rrcache.compiler.instance_nodes`), compiled once."""
    node_ids = list(node_ids)
    if len(node_ids) == 1:
        return variant_for(work, node_ids[0], algorithm, filter, payload_dtype)
    return kinds.compile(work, VariantSpec("nodes", tuple(node_ids), algorithm, filter or work.filter, payload_dtype))


def variant_for_selection(work: ShaderWork, selection: Selection, **runtime) -> tuple[Variant, object]:
    """The compiled variant of ``selection`` (with its ``algorithm``; three-pass when it names
    none; ``runtime``: the cache's run-time fields, ``block``, ``refresh``, ``depth_epsilon``) and
    the refresh period it runs with (for several nodes, the list of periods in part order): the
    kind of choice (:mod:`rrcache.kinds`) says how it compiles. The variant's ``spec`` is the
    selection's, whole. The original shader (no part) has no variant: RRCacheError."""
    spec = kinds.spec_for(selection, selection.algorithm or "three-pass", work.filter, **runtime)
    period = spec.period
    return kinds.compile(work, spec), list(period) if isinstance(period, tuple) else period


@dataclass(frozen=True)
class WorkSource:
    """How to load a :class:`ShaderWork` and its session, as a plain record (a worker of a
    distributed executor loads it once): the shader and session paths, the user's ``defines``
    (pairs), include folders, vertex shader and unroll limit, as :func:`load_for_session` takes
    them."""

    shader: str
    session: str
    defines: tuple = ()
    include_dirs: tuple = ()
    vertex: Optional[str] = None
    max_unroll: int = DEFAULT_MAX_ITERATIONS
    #: the measured order of sums (``load_for_session(term_scores=)``; None: the analysis's own)
    term_scores: Optional[dict] = None

    @classmethod
    def of(cls, work: ShaderWork, session, user_defines=None) -> "WorkSource":
        """The source of a loaded ``work`` over ``session`` (``user_defines``: the ``-D`` ones)."""
        return cls(str(work.shader.path), str(session.path), tuple(sorted((user_defines or {}).items())),
                   tuple(work.include_dirs), getattr(work.vertex, "path", None), int(work.max_unroll))

    def load(self) -> tuple[ShaderWork, object]:
        """(work, session), loaded and analysed."""
        from rrcache.session import load_session

        session = load_session(self.session)
        work = load_for_session(self.shader, session, dict(self.defines), self.include_dirs, self.max_unroll,
                                vertex=self.vertex, term_scores=self.term_scores)
        return work, session


def load_bench(source: WorkSource):
    """A :class:`rrcache.harness.execute.Bench` for ``source`` (what a worker makes once, then runs
    :func:`rrcache.harness.execute.execute` on for every spec it is given)."""
    from rrcache.harness.execute import Bench

    return Bench(*source.load())
