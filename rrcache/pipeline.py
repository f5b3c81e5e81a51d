"""Loading a shader for a session, and compiling what a selection caches: the steps every command
shares.

A shader is loaded with the ``MODEL_VERTEX_*`` defines of the session's meshes (plus the user's
``-D`` defines; :func:`rrcache.harness.prepare.load_for_meshes`, the one place that does it),
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
from dataclasses import dataclass
from functools import cached_property
from typing import Mapping, Optional

from rrcache.analysis import cacheable_nodes
from rrcache.analysis.unroll import DEFAULT_MAX_ITERATIONS
from rrcache.compiler import Variant, instance, instance_nodes
from rrcache.errors import RRCacheError
from rrcache.glsl.frontend import Shader
from rrcache.harness.prepare import PreparedShader, combined_hash, load_for_meshes, load_user_vertex, prepare
from rrcache.runtime.cache import DEFAULT_FILTER
from rrcache.selection import AdaptiveNode, AmortizedLoop, CachedNode, Selection
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
    #: the cache filter every variant of this work compiles with unless told otherwise (a
    #: profile's: ``Profile.filter``, chosen by rrcache.profiler.filters)
    filter: str = DEFAULT_FILTER

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
    return ShaderWork(shader, table, all_defines, user, tuple(os.path.abspath(d) for d in include_dirs or ()))


def all_include_dirs(include_dirs=(), session=None) -> tuple[str, ...]:
    """The command line's ``-I`` folders, then the session's ``"include_dirs"``."""
    return tuple(include_dirs or ()) + tuple(getattr(session, "include_dirs", ()) or ())


def variant_for(work: ShaderWork, node_id: str, algorithm: str = "three-pass", filter: Optional[str] = None,
                payload_dtype: str = "f4", adaptive: bool = False) -> Variant:
    """Compile the variant of ``work`` caching ``node_id`` (an id such as ``n42``;
    ``adaptive``: refreshed by :mod:`rrcache.runtime.adaptive`'s rule; ``filter``: the work's
    when not given)."""
    return instance(work.table, node_id, algorithm, filter or work.filter, payload_dtype, work.vertex,
                    adaptive=adaptive)


def variant_for_nodes(work: ShaderWork, node_ids, algorithm: str = "three-pass", filter: Optional[str] = None,
                      payload_dtype: str = "f4") -> Variant:
    """Compile the variant of ``work`` caching every node of ``node_ids`` (two or more; one:
    :func:`variant_for`), each with its own payload and period
    (:func:`rrcache.compiler.instance_nodes`)."""
    node_ids = list(node_ids)
    if len(node_ids) == 1:
        return variant_for(work, node_ids[0], algorithm, filter, payload_dtype)
    return instance_nodes(work.table, node_ids, algorithm, filter or work.filter, payload_dtype, work.vertex)


def variant_for_selection(work: ShaderWork, selection: Selection) -> tuple[Variant, int]:
    """The compiled variant of ``selection`` (with its ``algorithm``; three-pass when it names
    none) and the refresh period it runs with (for several nodes, a list of periods in the
    order of the parts): where each kind of choice becomes code. The
    original shader (no part) has no variant: RRCacheError."""
    algorithm = selection.algorithm or "three-pass"
    if len(selection.parts) == 1 and isinstance(selection.parts[0], CachedNode):
        part = selection.parts[0]
        return variant_for(work, part.node, algorithm), int(part.period)
    if len(selection.parts) == 1 and isinstance(selection.parts[0], AdaptiveNode):
        # the runtime takes the threshold, fast period and spread from the part
        # (rrcache.profiles.choice.adaptive_kwargs)
        part = selection.parts[0]
        return variant_for(work, part.node, algorithm, adaptive=True), int(part.period)
    if selection.multi:  # several nodes, each at its own period (a list, in part order)
        return variant_for_nodes(work, list(selection.nodes), algorithm), list(selection.periods)
    if len(selection.parts) == 1 and isinstance(selection.parts[0], AmortizedLoop):
        from rrcache.compiler.amortize import instance_amortized
        from rrcache.runtime.cache import DEFAULT_PERIOD

        part = selection.parts[0]
        variant = instance_amortized(work.shader, part.estimator, algorithm, samples=part.samples,
                                     blend=part.blend, phase=part.phase, history=part.history,
                                     filter=part.filter, payload_dtype=part.payload, vertex=work.vertex)
        # an amortized variant does not use the refresh rule: the period is the runtime's default
        return variant, DEFAULT_PERIOD
    raise RRCacheError(f"no variant for a selection of kind {selection.kind!r}", "selection",
                       hint="the original shader needs none; other kinds are compiled where they are added")
