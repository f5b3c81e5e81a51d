"""A fragment shader made ready for the GL: core-profile text plus what the harness must know.

:class:`PreparedShader` is all the harness needs from the GLSL front-end: the ``#version 330
core`` fragment text the driver compiles, the printer's line map (so driver errors name the
original ``file:line``), the declared uniforms/samplers and fragment inputs with the place of their
declaration, the source path and a content hash. :func:`prepare` makes one from a front-end
``Shader``; :func:`load_for_meshes` loads a shader file with the ``MODEL_VERTEX_*`` defines of a
session's meshes (the one place that does) and :func:`prepare_file` prepares what it loaded.

>>> p = PreparedShader(source="#version 330 core\\nout vec4 c;\\nvoid main(){c=vec4(1);}",
...                    path="white.frag", hash="h1")
>>> p.declaration("u_missing") is None
True
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Optional, Sequence

from rrcache.deep import deep
from rrcache.errors import SourceLoc
from rrcache.compiler.vertex import VARYINGS, mesh_defines, session_attributes, shadow_defines


@dataclass(frozen=True)
class Decl:
    """A global declaration of the fragment shader: its GLSL type name (``vec3``, ``sampler2D``;
    array dimensions left out) and where it is declared (None when unknown)."""

    type: str
    loc: Optional[SourceLoc] = None


@dataclass
class PreparedShader:
    """A core-profile fragment shader and its declarations, independent of front-end internals.

    ``uniforms`` holds every declared uniform, samplers included; ``inputs`` the fragment inputs
    (varyings). ``line_map[i]`` is the original place of line ``i + 1`` of ``source``.
    """

    source: str
    path: str
    hash: str
    line_map: Optional[Sequence[Optional[SourceLoc]]] = None
    uniforms: dict[str, Decl] = field(default_factory=dict)
    inputs: dict[str, Decl] = field(default_factory=dict)
    defines: dict[str, str] = field(default_factory=dict)
    #: the user's vertex shader (``rrcache.compiler.user_vertex.UserVertex``); None: generated
    vertex: Optional[object] = None

    def declaration(self, name: str) -> Optional[Decl]:
        """The declaration of uniform or input ``name`` (None when the shader declares none)."""
        return self.uniforms.get(name) or self.inputs.get(name)

    def where(self, name: str) -> str:
        """``file:line:col`` of the declaration of ``name``, or the shader path when unknown."""
        decl = self.declaration(name)
        return str(decl.loc) if decl is not None and decl.loc is not None else self.path


def _qualifier_names(qualifiers) -> set[str]:
    return {q for q in qualifiers if isinstance(q, str)}


def declarations(unit) -> tuple[dict[str, Decl], dict[str, Decl]]:
    """The global uniforms and fragment inputs (``in``/``varying``) of a translation unit.

    Interface blocks are skipped (the harness binds no uniform blocks).
    """
    from rrcache.glsl import ast

    uniforms: dict[str, Decl] = {}
    inputs: dict[str, Decl] = {}
    for decl in unit.decls:
        if not isinstance(decl, ast.VariableDecl):
            continue
        quals = _qualifier_names(decl.type.qualifiers)
        spec = decl.type.spec
        type_name = spec.name if spec.name else (spec.struct.name if spec.struct is not None else "struct")
        for d in decl.declarators:
            entry = Decl(type_name or "struct", d.loc or decl.loc)
            if "uniform" in quals:
                uniforms[d.name] = entry
            elif ("in" in quals or "varying" in quals) and not d.name.startswith("gl_"):
                # ``layout(origin_upper_left) in vec4 gl_FragCoord;`` redeclares a built-in
                # (names starting gl_ are reserved, GLSL 4.60 §3.7): not a varying to supply.
                inputs[d.name] = entry
    return uniforms, inputs


@deep
def prepare(shader, defines: Optional[Mapping[str, str]] = None, vertex=None) -> PreparedShader:
    """A :class:`PreparedShader` from a front-end ``Shader``: rewritten to ``#version 330 core``
    (``rrcache.glsl.legacy.to_core``) and printed with a line map.

    ``defines`` are recorded (the shader must already have been loaded with them). ``vertex``
    is the user's vertex shader (a ``UserVertex``; None: the harness generates one); the hash
    then covers it too.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> shader = parse_shader("varying vec3 v_normal;\\nvoid main() { gl_FragColor = vec4(v_normal, 1.0); }",
    ...                       "normal.frag")
    >>> p = prepare(shader)
    >>> p.source[:17], sorted(p.inputs)
    ('#version 330 core', ['v_normal'])
    """
    from rrcache.glsl.legacy import to_core
    from rrcache.glsl.printer import print_with_map

    core = to_core(shader.unit)
    text, line_map = print_with_map(core)
    uniforms, inputs = declarations(core)
    # the front-end's table knows the original declaration places even where the rewrite moved them
    for table in (getattr(shader, "uniforms", None), getattr(shader, "samplers", None)):
        if isinstance(table, Mapping):
            for name, entry in table.items():
                loc = entry[1] if isinstance(entry, tuple) and len(entry) > 1 else None
                if name in uniforms and loc is not None:
                    uniforms[name] = Decl(uniforms[name].type, loc)
    used_inputs = getattr(shader, "inputs", None)
    if isinstance(used_inputs, Mapping):
        # an input the harness does not know about matters only when the shader reads it
        inputs = {name: d for name, d in inputs.items() if name in VARYINGS or name in used_inputs}
    return PreparedShader(
        source=text,
        path=str(shader.path) if getattr(shader, "path", None) else "<string>",
        hash=combined_hash(shader.hash, vertex),
        line_map=list(line_map),
        uniforms=uniforms,
        inputs=inputs,
        defines=dict(defines or {}),
        vertex=vertex,
    )


def combined_hash(fragment_hash: str, vertex=None) -> str:
    """The fragment shader's hash, or with a user vertex shader a hash over both."""
    if vertex is None:
        return fragment_hash
    import hashlib

    return hashlib.sha256(f"{fragment_hash}\0vertex\0{vertex.hash}".encode()).hexdigest()


def load_for_meshes(path, session_or_attributes=None, defines: Optional[Mapping[str, str]] = None,
                    include_dirs=()):
    """Load a fragment shader file with the ``MODEL_VERTEX_*`` defines of the mesh attributes (and
    a session light's ``LIGHT_SHADOWMAP*``): the one place a shader is loaded for a session. Returns ``(shader, defines)``: the front-end
    ``Shader`` and every define it was loaded with.

    ``session_or_attributes`` is a session (the union of its meshes' attributes counts), an
    iterable of attribute names (``normal texcoord color tangent``) or None (no mesh defines).
    ``defines`` (e.g. from ``-D`` on the command line) are added and win over the mesh defines.

    >>> shader, defines = load_for_meshes("shaders/glslviewer_basic.glsl", {"normal", "texcoord"})
    >>> defines
    {'MODEL_VERTEX_NORMAL': '1', 'MODEL_VERTEX_TEXCOORD': '1'}
    """
    from rrcache.glsl.frontend import load_shader

    if session_or_attributes is None:
        all_defines = {}
    elif hasattr(session_or_attributes, "objects"):
        # the meshes' MODEL_VERTEX_* and, when the light has a shadow map, LIGHT_SHADOWMAP*
        all_defines = {**mesh_defines(session_attributes(session_or_attributes)),
                       **shadow_defines(session_or_attributes)}
    else:
        all_defines = mesh_defines(frozenset(session_or_attributes))
    all_defines.update(defines or {})
    return load_shader(path, defines=all_defines, include_dirs=include_dirs), all_defines


def prepare_file(path, session_or_attributes=(), extra_defines: Optional[Mapping[str, str]] = None,
                 include_dirs=(), vertex=None) -> PreparedShader:
    """:func:`load_for_meshes`, then :func:`prepare`; ``vertex`` is the path of the user's vertex
    shader (None: the session's ``"vertex"`` when ``session_or_attributes`` is a session that has
    one, else generated).

    >>> prepare_file("marble.frag", {"normal", "texcoord"}).defines     # doctest: +SKIP
    {'MODEL_VERTEX_NORMAL': '1', 'MODEL_VERTEX_TEXCOORD': '1'}
    """
    shader, defines = load_for_meshes(path, session_or_attributes, extra_defines, include_dirs)
    return prepare(shader, defines, load_user_vertex(vertex, session_or_attributes, defines, include_dirs))


def load_user_vertex(vertex, session=None, defines=None, include_dirs=()):
    """The ``UserVertex`` of path ``vertex``, or of the session's ``"vertex"`` when ``vertex`` is
    None; None when neither names one."""
    path = vertex if vertex is not None else getattr(session, "vertex", None)
    if path is None:
        return None
    from rrcache.compiler.user_vertex import load_vertex, user_vertex_from_text

    if vertex is None and getattr(session, "vertex_text", None) is not None:
        return user_vertex_from_text(session.vertex_text, path, defines, include_dirs)  # read, confined, at load
    return load_vertex(path, defines, include_dirs)
