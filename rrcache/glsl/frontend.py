"""The GLSL front-end entry point: source text or file → checked :class:`Shader`.

``parse_shader`` runs the stages in order (preprocess → lex → parse → check) and rejects shaders
rrcache does not handle (other stages than fragment, several colour outputs) with an
:class:`~rrcache.errors.UnsupportedShaderError`. ``load_shader`` reads the file first.

>>> shader = parse_shader("uniform float u_time;\\nvarying vec2 v_texcoord;\\n"
...                       "void main() { gl_FragColor = vec4(v_texcoord, sin(u_time), 1.0); }")
>>> shader.version, list(shader.uniforms), list(shader.inputs)
(110, ['u_time'], ['v_texcoord'])
"""
from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from typing import Iterable, Mapping, Optional

from rrcache.budgets import budget
from rrcache.deep import deep
from rrcache.errors import GLSLError, SourceLoc, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.visitor import NodeVisitor
from rrcache.glsl.builtins import NON_FRAGMENT_VARIABLES
from rrcache.glsl.parser import parse_preprocessed
from rrcache.glsl.preprocessor import preprocess, read_source
from rrcache.glsl.semantic import SemanticInfo, check
from rrcache.glsl.types import Type

__all__ = ["Shader", "describe_change", "file_records", "load_shader", "parse_shader"]

# Layout qualifiers that belong to compute, geometry and tessellation shaders.
_OTHER_STAGE_LAYOUTS = {
    "local_size_x": "compute", "local_size_y": "compute", "local_size_z": "compute",
    "max_vertices": "geometry", "invocations": "geometry", "triangles_adjacency": "geometry",
    "lines_adjacency": "geometry", "line_strip": "geometry", "triangle_strip": "geometry",
    "vertices": "tessellation control", "isolines": "tessellation evaluation",
    "equal_spacing": "tessellation evaluation", "fractional_even_spacing":
    "tessellation evaluation", "fractional_odd_spacing": "tessellation evaluation",
}
_OTHER_STAGE_FUNCTIONS = {"EmitVertex": "geometry", "EndPrimitive": "geometry",
                          "EmitStreamVertex": "geometry", "EndStreamPrimitive": "geometry",
                          "ftransform": "vertex", "barrier": "compute or tessellation"}


@dataclass
class Shader:
    """A checked fragment shader.

    ``unit`` is the type-checked AST, ``info`` its :class:`SemanticInfo`; ``uniforms``,
    ``samplers`` and ``inputs`` map names to ``(Type, SourceLoc)`` in declaration order
    (``uniforms`` are the non-opaque plain uniforms, ``samplers`` the opaque ones, ``inputs`` the
    user-declared inputs the shader reads); ``hash`` is a sha256 over the *content* of every
    file read (in the order they were read, never their path strings: the same shader reached
    through another working directory or path spelling has the same hash) and the defines;
    ``files`` lists those files (the main one first) and ``file_hashes`` the sha256 of each
    one's content, in the same order (what :func:`describe_change` compares).
    """

    path: Optional[str]
    source: str
    unit: A.TranslationUnit
    info: SemanticInfo
    version: int
    profile: Optional[str]
    hash: str
    uniforms: dict[str, tuple[Type, SourceLoc]] = field(default_factory=dict)
    samplers: dict[str, tuple[Type, SourceLoc]] = field(default_factory=dict)
    inputs: dict[str, tuple[Type, SourceLoc]] = field(default_factory=dict)
    outputs: dict[str, tuple[Type, SourceLoc]] = field(default_factory=dict)
    defines: dict[str, object] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)
    pragmas: list = field(default_factory=list)  # (text after #pragma, SourceLoc) in source order
    file_hashes: list[str] = field(default_factory=list)
    #: without ``#version``: the language assumed and why (``Preprocessed.assumed``)
    assumed: Optional[str] = None

    @property
    def language(self) -> str:
        """The GLSL the shader was read as, in words: ``GLSL 330 core``, ``GLSL ES 3.00``, or for
        a shader without ``#version`` the assumption and its reason.

        >>> parse_shader("#version 300 es\\nprecision highp float; out vec4 c;\\n"
        ...              "void main() { c = vec4(1.0); }").language
        'GLSL ES 3.00'
        """
        if self.assumed:
            return self.assumed
        if self.es:
            return f"GLSL ES {self.version // 100}.{self.version % 100:02d}"
        return f"GLSL {self.version}" + (f" {self.profile}" if self.profile else "")

    @property
    def varyings(self) -> dict[str, tuple[Type, SourceLoc]]:
        """The inputs (varyings) the shader reads; the same as :attr:`inputs`."""
        return self.inputs

    @property
    def es(self) -> bool:
        """Whether the shader is GLSL ES."""
        return self.info.es


@deep
def parse_shader(source: str, filename: str = "<string>",
                 defines: Optional[Mapping[str, object]] = None,
                 include_dirs: Iterable[str] = ()) -> Shader:
    """Preprocess, parse and type-check the fragment shader ``source``.

    Raises the stage's :class:`~rrcache.errors.GLSLError` subclass on invalid input, and
    :class:`~rrcache.errors.UnsupportedShaderError` for a vertex/geometry/compute shader or a
    shader with several colour outputs.

    >>> s = parse_shader("#version 330\\nout vec4 c;\\nuniform sampler2D tex;\\nin vec2 uv;\\n"
    ...                  "void main() { c = texture(tex, uv); }", "a.frag")
    >>> list(s.samplers), s.outputs["c"][0]
    (['tex'], Type('vec4'))
    """
    defines = dict(defines or {})
    pp = preprocess(source, filename, defines, tuple(include_dirs))
    unit = parse_preprocessed(pp, filename)
    check_size(unit, filename)
    frag_data = _reject_other_stages(unit, filename)
    info = check(unit, filename)
    _reject_multiple_outputs(frag_data, info)
    path = None if filename.startswith("<") else filename
    files = list(pp.files) or ([filename] if path else [])
    digests = file_digests(source, files, filename, pp.file_hashes)
    return Shader(
        path=path, source=source, unit=unit, info=info, version=info.version,
        profile=unit.profile or ("es" if info.es else None),
        hash=_hash(digests, defines),
        uniforms={n: (s.type, s.loc) for n, s in info.uniforms.items()
                  if isinstance(s.decl, A.VariableDecl) and not s.type.contains_opaque()},
        samplers={n: (s.type, s.loc) for n, s in info.uniforms.items()
                  if s.type.contains_opaque()},
        inputs={n: (s.type, s.loc) for n, s in info.inputs.items() if n in info.used_globals},
        outputs={n: (s.type, s.loc) for n, s in info.outputs.items()},
        defines=defines, files=files, file_hashes=digests, assumed=pp.assumed,
        pragmas=list(pp.pragmas))


def check_size(unit: A.TranslationUnit, filename: str) -> None:
    """Refuse a program beyond the analysis budgets (:mod:`rrcache.budgets`): more syntax nodes
    than ``budget.analysis_nodes`` or an expression nested deeper than ``budget.expression_depth``
    (counted without recursion, before any recursive pass runs)."""
    count = 0
    deepest, deepest_node = 0, None
    stack = [(unit, 0)]
    pop, push = stack.pop, stack.append
    while stack:
        node, depth = pop()
        count += 1
        if depth > deepest:
            deepest, deepest_node = depth, node
        for child in node.children():
            push((child, depth + 1))
    if count > budget.analysis_nodes:
        raise GLSLError(f"the shader has {count:,} syntax nodes after preprocessing, more than the analysis "
                        f"budget of {budget.analysis_nodes:,}", SourceLoc(filename, 1, 1),
                        "raise it with 'rrcache --max-ast-nodes N ...' if the machine has the memory "
                        "(analysis took about 2 KB per node here)")
    if deepest > budget.expression_depth:
        loc = getattr(deepest_node, "loc", None) or SourceLoc(filename, 1, 1)
        raise GLSLError(f"an expression is nested {deepest:,} levels deep, more than the "
                        f"{budget.expression_depth:,} rrcache analyses", loc,
                        "split it into several statements, or raise the limit with "
                        "'rrcache --max-depth N ...'")


def load_shader(path: "str | os.PathLike[str]", defines: Optional[Mapping[str, object]] = None,
                include_dirs: Iterable[str] = ()) -> Shader:
    """Read the fragment shader file ``path`` and return the checked :class:`Shader`.

    A missing or unreadable file raises :class:`~rrcache.errors.GLSLError` naming the path.

    >>> shader = load_shader("shaders/marble.glsl")
    >>> shader.uniforms["u_camera"][0]
    Type('vec3')
    """
    path = os.fspath(path)
    source, _ = read_source(path)
    return parse_shader(source, path, defines, include_dirs)


def file_digests(source: str, files: list[str], filename: str, read: Mapping[str, str]) -> list[str]:
    """The sha256 of each file's content, ``files`` order: the main file's from ``source`` (the
    text that was parsed), the included ones' from what the preprocessor read (``read``:
    :attr:`~rrcache.glsl.preprocessor.Preprocessed.file_hashes`); no file is opened again."""
    return [hashlib.sha256(source.encode("utf-8")).hexdigest() if path == filename else read[path]
            for path in files or [filename]]


def _hash(digests: list[str], defines: Mapping[str, object]) -> str:
    # content only: a path spelling (relative, absolute, through a symlink) never changes it
    h = hashlib.sha256(b"rrcache shader hash 2\0")
    for digest in digests:
        h.update(b"\0file\0" + digest.encode("ascii"))
    for name in sorted(defines):
        h.update(f"\0define\0{name}={defines[name]!r}".encode("utf-8"))
    return h.hexdigest()


def describe_change(recorded_files: Optional[list], shader: Shader,
                    recorded_defines: Optional[Mapping[str, object]] = None) -> str:
    """Why ``shader`` no longer has a recorded hash, in words: which file changed (by content),
    which include appeared or went, or that no file changed and what else differs.
    ``recorded_files`` is ``[{"path": ..., "sha256": ...}]`` as :func:`file_records` wrote it
    (None for a record made before rrcache kept one).

    >>> s = parse_shader("void main() { gl_FragColor = vec4(1.0); }", "a.frag")
    >>> describe_change(file_records(s), s)
    'no shader file changed'
    """
    if not recorded_files:
        return ("the record predates per-file hashes, so which file changed cannot be told "
                "(rrcache then hashed include paths, not only content)")
    now = {_same_file_key(p): (p, d) for p, d in zip(shader.files, shader.file_hashes)}
    then = {_same_file_key(r.get("path", "")): (r.get("path", ""), r.get("sha256")) for r in recorded_files}
    said = []
    # the main file is compared by position: the profile may have been made with another path
    if shader.file_hashes and recorded_files[0].get("sha256") != shader.file_hashes[0]:
        said.append(f"'{shader.files[0] if shader.files else shader.path}' changed")
    main_keys = {_same_file_key(recorded_files[0].get("path", ""))}
    if shader.files:
        main_keys.add(_same_file_key(shader.files[0]))
    for key, (path, digest) in now.items():
        if key in main_keys:
            continue
        if key not in then:
            said.append(f"it now includes '{path}'")
        elif then[key][1] != digest:
            said.append(f"'{path}' changed")
    for key, (path, _digest) in then.items():
        if key not in main_keys and key not in now:
            said.append(f"it no longer includes '{path}'")
    if said:
        return "; ".join(said)
    if recorded_defines is not None and dict(recorded_defines) != dict(shader.defines):
        return "no shader file changed, but the defines differ"
    return "no shader file changed"


def file_records(shader: Shader) -> list[dict]:
    """``[{"path": absolute path, "sha256": content hash}]`` of every file the shader read,
    for a record (a profile) that :func:`describe_change` later compares against."""
    return [{"path": p if p.startswith("<") else os.path.abspath(p), "sha256": d}
            for p, d in zip(shader.files, shader.file_hashes)]


def _same_file_key(path: str) -> str:
    return path if not path or path.startswith("<") else os.path.realpath(path)


def _unsupported(what: str, loc: Optional[SourceLoc], filename: str) -> UnsupportedShaderError:
    return UnsupportedShaderError(
        f"this looks like a {what}; rrcache optimizes fragment shaders only", loc or
        SourceLoc(filename, 1, 1), "pass the fragment (pixel) shader")


class _OtherStages(NodeVisitor):
    """Raises for what only another stage writes; collects the ``gl_FragData[...]`` indices."""

    def __init__(self, filename: str):
        self.filename = filename
        self.frag_data: list[A.Index] = []

    def refuse(self, what: str, loc) -> UnsupportedShaderError:
        return _unsupported(what, loc, self.filename)

    def visit_Index(self, node: A.Index) -> None:
        if isinstance(node.obj, A.Ident) and node.obj.name == "gl_FragData":
            self.frag_data.append(node)
        self.generic_visit(node)

    def visit_Ident(self, node: A.Ident) -> None:
        if node.name in NON_FRAGMENT_VARIABLES:
            raise self.refuse(f"non-fragment shader (it uses '{node.name}')", node.loc)

    def visit_Call(self, node: A.Call) -> None:
        if node.name in _OTHER_STAGE_FUNCTIONS:
            raise self.refuse(f"{_OTHER_STAGE_FUNCTIONS[node.name]} shader (it calls "
                              f"'{node.name}')", node.loc)
        self.generic_visit(node)

    def visit_FullType(self, node: A.FullType) -> None:
        if "attribute" in node.qualifiers:
            raise self.refuse("vertex shader (it declares an 'attribute')", node.loc)
        self.generic_visit(node)

    def visit_Layout(self, node: A.Layout) -> None:
        for name, _ in node.items:
            if name in _OTHER_STAGE_LAYOUTS:
                raise self.refuse(f"{_OTHER_STAGE_LAYOUTS[name]} shader (layout '{name}')",
                                  node.loc)
        self.generic_visit(node)

    def visit_VariableDecl(self, node: A.VariableDecl) -> None:
        for d in node.declarators:
            if d.name in NON_FRAGMENT_VARIABLES:
                raise self.refuse(f"non-fragment shader (it declares '{d.name}')",
                                  d.loc or node.loc)
        self.generic_visit(node)

    def visit_InterfaceBlock(self, node: A.InterfaceBlock) -> None:
        if node.block_name == "gl_PerVertex":
            raise self.refuse("non-fragment shader (it declares 'gl_PerVertex')", node.loc)
        self.generic_visit(node)


def _reject_other_stages(unit: A.TranslationUnit, filename: str) -> list[A.Index]:
    """Raise for a non-fragment stage; returns the ``gl_FragData[...]`` index nodes. Runs before
    :func:`check`, so that a vertex shader is reported as one rather than as an undeclared
    ``gl_Position``."""
    v = _OtherStages(filename)
    v.visit(unit)
    return v.frag_data


def _reject_multiple_outputs(frag_data: list[A.Index], info: SemanticInfo) -> None:
    outs = [s for s in info.outputs.values()]
    arrays = [s for s in outs if s.type.dims and s.type.dims[0] != 1]
    if len(outs) > 1 or arrays:
        names = ", ".join(f"'{s.name}'" for s in outs)
        first = (arrays or outs[1:])[0]
        raise UnsupportedShaderError(
            f"the shader has several colour outputs ({names}); rrcache handles one",
            first.loc, "write the final colour to a single 'out vec4'")
    legacy = {"gl_FragColor", "gl_FragData"} & info.used_globals
    if outs and legacy:
        raise UnsupportedShaderError(
            f"the shader writes both '{outs[0].name}' and '{sorted(legacy)[0]}'",
            outs[0].loc, "use only one colour output")
    for node in frag_data:
        idx = node.index
        if not (isinstance(idx, A.IntLit) and idx.value == 0):
            raise UnsupportedShaderError(
                "the shader writes several colour outputs through gl_FragData", node.loc,
                "write the final colour to gl_FragData[0] or gl_FragColor only")
