"""Loading a shader for a session: the steps every command shares.

A shader is loaded with the ``MODEL_VERTEX_*`` defines of the session's meshes (plus the user's
``-D`` defines), prepared for the harness (core GLSL with a line map) and analysed (the
cacheable nodes). :func:`load_for_session` does the three once, and :func:`variant_for`
compiles the variant of one node.

>>> work = load_for_session("shaders/marble.glsl", load_session("sessions/marble.json"))  # doctest: +SKIP
>>> variant = variant_for(work, "n2575", period=16)                                      # doctest: +SKIP
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Optional

from rrcache.analysis import cacheable_nodes
from rrcache.compiler import Variant, instance
from rrcache.errors import RRCacheError
from rrcache.glsl.frontend import Shader, load_shader
from rrcache.harness.prepare import PreparedShader, prepare
from rrcache.harness.vertex import session_defines


@dataclass
class ShaderWork:
    """A shader loaded for a session: the checked ``shader``, the harness's ``prepared`` core
    source, the ``table`` of cacheable nodes and the ``defines`` used."""

    shader: Shader
    prepared: PreparedShader
    table: object
    defines: dict

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
                     include_dirs=()) -> ShaderWork:
    """Load, prepare and analyse ``shader_path``; with a ``session`` its meshes' attributes set
    the ``MODEL_VERTEX_*`` defines (``defines`` win over them)."""
    all_defines = session_defines(session) if session is not None else {}
    all_defines.update(defines or {})
    shader = load_shader(shader_path, defines=all_defines, include_dirs=include_dirs)
    return ShaderWork(shader, prepare(shader, all_defines), cacheable_nodes(shader), all_defines)


def variant_for(work: ShaderWork, node_id: str, period: Optional[int] = None, algorithm: str = "three-pass",
                filter: str = "bilinear", payload_dtype: str = "f4") -> Variant:
    """Compile the variant of ``work`` caching ``node_id`` (an id such as ``n42``)."""
    variant = instance(work.table, node_id, algorithm, filter, payload_dtype)
    variant.period = period
    return variant
