"""The user's own vertex shader (glslViewer's ``.vert`` beside a ``.frag``), made ready for every
pass of the harness and of the cached variants.

glslViewer pairs a fragment shader with a vertex shader whose outputs the fragment shader reads
(``v_ratio``, ``v_position``...), written against glslViewer's attributes (``a_position``,
``a_normal``, ``a_texcoord``, ``a_color``, ``a_tangent``; declared as glslViewer does, e.g.
``attribute vec4 a_position``: a mesh supplies three components and GL fills ``w = 1``) and
uniforms (``u_modelViewProjectionMatrix``, ``u_modelMatrix``, ``u_viewMatrix``,
``u_projectionMatrix``, ``u_normalMatrix``, ``u_time``, ...; the harness sets them per frame and
per object). :func:`load_vertex` reads such a file (``--vert FILE``, or ``"vertex"`` in a session)
and :meth:`UserVertex.source` gives the text the driver compiles:

- it is preprocessed by rrcache's preprocessor with the fragment shader's defines (the meshes'
  ``MODEL_VERTEX_*`` and ``-D``), its includes resolved, and read as the same GLSL the fragment
  shader is (a versionless sketch with ``precision`` statements is GLSL ES 1.00, ``GL_ES``
  defined);
- it becomes ``#version 330 core`` (or the file's own later core version): ``attribute`` → ``in``,
  ``varying`` → ``out``, ``texture2D``/``textureCube``... → ``texture``/``textureLod``;
- ``gl_Position`` is declared ``invariant`` (every pass must rasterise the same depths), the
  user's ``main`` is renamed ``rr_userMain`` and called from a ``main`` that, for a pass that
  reprojects, also writes the previous frame's clip position the cache needs::

      rr_prevClip = u_reprojectionMatrix * gl_Position;

  ``u_reprojectionMatrix`` (set per object by the harness, computed in double precision) is the
  previous frame's model-view-projection times the inverse of this frame's: whatever the user's
  shader does to the vertex (displacement included) is carried along with the object.

Every fragment input must be an output of the vertex shader, with the same type; otherwise the
error names the fragment shader's declaration and the vertex file.

>>> v = user_vertex_from_text("attribute vec4 a_position;\\nvarying vec2 v_ratio;\\n"
...     "uniform mat4 u_modelViewProjectionMatrix;\\nvoid main() { v_ratio = a_position.xy;\\n"
...     "gl_Position = u_modelViewProjectionMatrix * a_position; }", "glslviewer.vert")
>>> v.outputs
{'v_ratio': 'vec2'}
>>> print(v.source(prev_clip=True).splitlines()[:3])
['#version 330 core', 'invariant gl_Position;', 'uniform mat4 u_reprojectionMatrix;']
"""
from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from typing import Iterable, Mapping, Optional

from rrcache.errors import SourceLoc, UnsupportedShaderError
from rrcache.glsl.preprocessor import read_source

#: the uniform the harness sets per object for the previous-frame clip position
REPROJECTION_UNIFORM = "u_reprojectionMatrix"
USER_MAIN = "rr_userMain"

# legacy names of the core lookups (vertex stage)
_LEGACY_CALLS = {
    "texture2D": "texture", "texture3D": "texture", "textureCube": "texture",
    "texture2DProj": "textureProj", "texture2DLod": "textureLod", "textureCubeLod": "textureLod",
    "texture3DLod": "textureLod", "texture2DProjLod": "textureProjLod",
    "texture2DLodEXT": "textureLod", "textureCubeLodEXT": "textureLod",
}
_INTERPOLATION = {"flat", "smooth", "noperspective", "centroid", "invariant", "lowp", "mediump",
                  "highp", "precise", "sample"}
_ES_ONLY_EXTENSIONS = {"GL_OES_standard_derivatives", "GL_EXT_shader_texture_lod",
                       "GL_EXT_frag_depth", "GL_OES_texture_3D", "GL_EXT_draw_buffers"}


@dataclass
class UserVertex:
    """A user's vertex shader, preprocessed and rewritten to core GLSL (see the module).

    ``body`` is the rewritten text after the ``#version``/``#extension`` lines, ``outputs`` its
    ``out`` variables (name → GLSL type), ``hash`` a sha256 over the content of every file read
    and the defines.
    """

    path: str
    version_line: str
    extensions: list[str]
    body: str
    outputs: dict[str, str]
    hash: str
    files: list[str] = field(default_factory=list)
    declares_invariant: bool = False
    uniforms: list[str] = field(default_factory=list)

    def uniform_names(self, prev_clip: bool = False) -> list[str]:
        """The uniforms the vertex shader declares (the application sets them per object or
        per frame), with ``u_reprojectionMatrix`` when it writes ``rr_prevClip``."""
        return self.uniforms + ([REPROJECTION_UNIFORM] if prev_clip else [])

    def source(self, prev_clip: bool = False) -> str:
        """The vertex shader text; with ``prev_clip`` it also writes ``rr_prevClip``."""
        lines = [self.version_line, *self.extensions]
        if not self.declares_invariant:
            lines.append("invariant gl_Position;")
        if prev_clip:
            lines += [f"uniform mat4 {REPROJECTION_UNIFORM};", "out vec4 rr_prevClip;"]
        lines.append(self.body)
        lines += ["void main() {", f"    {USER_MAIN}();"]
        if prev_clip:
            lines.append(f"    rr_prevClip = {REPROJECTION_UNIFORM} * gl_Position;")
        lines += ["}", ""]
        return "\n".join(lines)

    def check_inputs(self, inputs: Mapping[str, str],
                     locs: Optional[Mapping[str, Optional[SourceLoc]]] = None) -> None:
        """Raise :class:`UnsupportedShaderError` at the fragment declaration for an input the
        vertex shader does not write, or writes with another type."""
        locs = locs or {}
        for name, declared in inputs.items():
            if name == "rr_prevClip":
                continue
            if name not in self.outputs:
                raise UnsupportedShaderError(
                    f"fragment input `{name}` is not an output of the vertex shader {self.path}",
                    locs.get(name), hint=f"declare `varying {declared} {name};` (or `out`) in "
                    f"{os.path.basename(self.path)} and write it, or remove it from the fragment shader")
            if self.outputs[name] != declared:
                raise UnsupportedShaderError(
                    f"fragment input `{name}` is `{declared}` but the vertex shader {self.path} "
                    f"writes a `{self.outputs[name]}`", locs.get(name),
                    hint="declare it with the same type in both shaders")


def load_vertex(path: "str | os.PathLike[str]", defines: Optional[Mapping[str, object]] = None,
                include_dirs: Iterable[str] = ()) -> UserVertex:
    """Read and prepare the vertex shader file ``path`` (see the module)."""
    path = os.fspath(path)
    text, _ = read_source(path, "vertex shader file")
    return user_vertex_from_text(text, path, defines, include_dirs)


def user_vertex_from_text(text: str, path: str, defines: Optional[Mapping[str, object]] = None,
                          include_dirs: Iterable[str] = ()) -> UserVertex:
    """:func:`load_vertex` on text already read (``path`` names it in messages)."""
    from rrcache.glsl.frontend import file_digests
    from rrcache.glsl.preprocessor import preprocess

    defines = dict(defines or {})
    pp = preprocess(text, path, defines, tuple(include_dirs))
    legacy = pp.profile == "es" and pp.version in (None, 100) or (pp.version or 110) < 130
    toks = list(pp.tokens)
    names = [t.text for t in toks]
    if "gl_Position" not in names:
        raise UnsupportedShaderError("the vertex shader never writes gl_Position",
                                     SourceLoc(path, 1, 1), "set gl_Position in its main()")
    if "main" not in names:
        raise UnsupportedShaderError("the vertex shader has no main()", SourceLoc(path, 1, 1))
    if "gl_FragColor" in names or "gl_FragCoord" in names:
        raise UnsupportedShaderError("this looks like a fragment shader, not a vertex shader",
                                     SourceLoc(path, 1, 1),
                                     "give the .vert file with --vert or \"vertex\"")
    out_texts: list[str] = []
    for i, t in enumerate(toks):
        word = t.text
        if t.kind == "ident":
            if legacy and word == "attribute":
                word = "in"
            elif legacy and word == "varying":
                word = "out"
            elif legacy and word in _LEGACY_CALLS and i + 1 < len(toks) and toks[i + 1].text == "(":
                word = _LEGACY_CALLS[word]
            elif word == "main":
                word = USER_MAIN
            elif word.startswith("rr_") or word == REPROJECTION_UNIFORM:
                raise UnsupportedShaderError(
                    f"the vertex shader uses the name '{word}', reserved for rrcache", t.loc,
                    "rename it")
        out_texts.append(word)
    outputs, invariant, uniforms = _globals(out_texts)
    body = _layout(toks, out_texts)
    version = pp.version if pp.version is not None and pp.profile != "es" and pp.version >= 330 else 330
    keep = [f"#extension {name} : {behavior}" for name, behavior in pp.extensions
            if name not in _ES_ONLY_EXTENSIONS]
    files = list(pp.files) or [path]
    digests = file_digests(text, files, path, pp.file_hashes)
    h = hashlib.sha256(b"rrcache user vertex 1\0")
    for d in digests:
        h.update(d.encode("ascii") + b"\0")
    for name in sorted(defines):
        h.update(f"{name}={defines[name]!r}\0".encode())
    return UserVertex(path=path, version_line=f"#version {version} core", extensions=keep,
                      body=body, outputs=outputs, hash=h.hexdigest(), files=files,
                      declares_invariant=invariant, uniforms=uniforms)


def _globals(words: list[str]) -> tuple[dict[str, str], bool, list[str]]:
    """The global ``out`` variables (name → type) of the rewritten token words, whether
    ``invariant gl_Position`` is declared, and the uniform names."""
    outputs: dict[str, str] = {}
    uniforms: list[str] = []
    invariant = False
    depth = 0
    stmt: list[str] = []
    for w in words:
        if w == "{":
            depth += 1
            stmt = []
            continue
        if w == "}":
            depth -= 1
            stmt = []
            continue
        if depth:
            continue
        if w != ";":
            stmt.append(w)
            continue
        if stmt and stmt[0] == "layout" and ")" in stmt:
            stmt = stmt[stmt.index(")") + 1:]
        if stmt[:2] == ["invariant", "gl_Position"]:
            invariant = True
        for qual in ("out", "uniform"):
            if qual in stmt and "(" not in stmt[:stmt.index(qual)]:
                found = _declared(stmt[stmt.index(qual) + 1:])
                if qual == "out":
                    outputs.update(found)
                else:
                    uniforms += [n for n in found if n not in uniforms]
        stmt = []
    return outputs, invariant, uniforms


def _declared(rest: list[str]) -> dict[str, str]:
    """``[qualifiers] type name [array] (, name [array])*`` → {name: type}."""
    out: dict[str, str] = {}
    while rest and rest[0] in _INTERPOLATION:
        rest = rest[1:]
    if len(rest) < 2 or rest[1] == "{":  # an interface block: its members are not listed
        return out
    typ, k = rest[0], 1
    while k < len(rest):
        out[rest[k]] = typ
        k += 1
        depth = 0
        while k < len(rest) and (rest[k] != "," or depth):
            depth += 1 if rest[k] in ("[", "(") else -1 if rest[k] in ("]", ")") else 0
            k += 1
        k += 1
    return out


def _layout(toks, words: list[str]) -> str:
    """The words laid out on the original lines (``#line`` where lines jump), so that a driver
    error points into the user's file."""
    lines: list[str] = []
    current: list[str] = []
    last = None
    for t, w in zip(toks, words):
        key = (t.loc.file, t.loc.line) if t.loc is not None else last
        if key != last:
            if current:
                lines.append(" ".join(current))
                current = []
            if last is None or key[0] != last[0] or key[1] != last[1] + 1:
                lines.append(f"#line {key[1]}")
            last = key
        current.append(w)
    if current:
        lines.append(" ".join(current))
    return "\n".join(lines)
