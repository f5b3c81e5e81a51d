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

>>> work = load_for_session("shaders/marble.glsl", load_session("sessions/marble.json"))  # doctest: +SKIP
>>> variant = variant_for(work, "n2575", "two-pass")                                     # doctest: +SKIP
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Mapping, Optional

from rrcache.analysis import cacheable_nodes
from rrcache.analysis.unroll import DEFAULT_MAX_ITERATIONS
from rrcache.compiler import Variant, instance
from rrcache.errors import RRCacheError
from rrcache.glsl.frontend import Shader
from rrcache.harness.prepare import PreparedShader, load_for_meshes, prepare
from rrcache.selection import CachedNode, Selection


@dataclass
class ShaderWork:
    """A shader loaded for a session: the checked ``shader``, the ``table`` of cacheable nodes,
    the ``defines`` used and (made when first read) the harness's ``prepared`` core source."""

    shader: Shader
    table: object
    defines: dict

    @cached_property
    def prepared(self) -> PreparedShader:
        return prepare(self.shader, self.defines)

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
                     include_dirs=(), max_unroll: int = DEFAULT_MAX_ITERATIONS) -> ShaderWork:
    """Load and analyse ``shader_path`` (loops of at most ``max_unroll`` iterations unrolled);
    with a ``session`` its meshes' attributes set the ``MODEL_VERTEX_*`` defines (``defines``
    win over them)."""
    shader, all_defines = load_for_meshes(shader_path, session, defines, include_dirs)
    return ShaderWork(shader, cacheable_nodes(shader, max_iterations=max_unroll), all_defines)


def variant_for(work: ShaderWork, node_id: str, algorithm: str = "three-pass", filter: str = "bilinear",
                payload_dtype: str = "f4") -> Variant:
    """Compile the variant of ``work`` caching ``node_id`` (an id such as ``n42``)."""
    return instance(work.table, node_id, algorithm, filter, payload_dtype)


def variant_for_selection(work: ShaderWork, selection: Selection) -> tuple[Variant, int]:
    """The compiled variant of ``selection`` (with its ``algorithm``; three-pass when it names
    none) and the refresh period it runs with: where each kind of choice becomes code. The
    original shader (no part) has no variant: RRCacheError."""
    algorithm = selection.algorithm or "three-pass"
    if len(selection.parts) == 1 and isinstance(selection.parts[0], CachedNode):
        part = selection.parts[0]
        return variant_for(work, part.node, algorithm), int(part.period)
    raise RRCacheError(f"no variant for a selection of kind {selection.kind!r}", "selection",
                       hint="the original shader needs none; other kinds are compiled where they are added")
