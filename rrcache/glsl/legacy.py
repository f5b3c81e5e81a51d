"""Legacy-to-core conversion: any accepted fragment shader as ``#version 330 core``.

:func:`to_core` returns a rewritten deep copy of a parsed shader that compiles as a core-profile
fragment shader (the version of every variant rrcache emits):

* ``#version`` below 330 (or absent) and GLSL ES 1.00/3.00 become ``330 core``; ES 3.10/3.20
  become 430/450 core; a desktop version of 330 or more is kept as is;
* ``varying`` inputs become ``in``; ``attribute`` (a vertex shader input) is an
  :class:`~rrcache.errors.UnsupportedShaderError`;
* ``gl_FragColor`` and ``gl_FragData[0]`` become ``out vec4 rr_FragColor;`` (declared once);
  ``gl_FragData[n]`` with ``n > 0`` is unsupported (several colour outputs);
* ``texture2D``/``texture2DProj``/``texture2DLod``/``textureCube``/``texture3D``/``shadow2D``...
  become ``texture``/``textureProj``/``textureLod``...; ``shadow*`` calls are wrapped in
  ``vec4(...)`` since they returned a vec4 where ``texture`` on a shadow sampler returns a float;
  user functions with those names are left alone;
* precision statements and precision qualifiers are dropped, as are the ES-only extensions
  (``GL_OES_standard_derivatives``, ``GL_EXT_shader_texture_lod``, ``GL_EXT_frag_depth``);
  ``gl_FragDepthEXT`` becomes ``gl_FragDepth``;
* user names that are keywords or built-in functions in the new version (``texture``,
  ``sample``, ``flat``...) are renamed ``rr_<name>``.
"""
from __future__ import annotations

import copy
from dataclasses import fields
from typing import Callable, Optional

from rrcache.errors import UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.lexer import KEYWORDS, PRECISION_QUALIFIERS, RESERVED_WORDS, is_keyword

#: The colour output that replaces gl_FragColor / gl_FragData[0].
FRAG_COLOR = "rr_FragColor"

#: Legacy texture built-ins and their core replacements.
LEGACY_TEXTURE_FUNCTIONS: dict[str, str] = {
    "texture1D": "texture", "texture1DProj": "textureProj", "texture1DLod": "textureLod",
    "texture1DProjLod": "textureProjLod",
    "texture2D": "texture", "texture2DProj": "textureProj", "texture2DLod": "textureLod",
    "texture2DProjLod": "textureProjLod", "texture2DRect": "texture",
    "texture2DRectProj": "textureProj",
    "texture3D": "texture", "texture3DProj": "textureProj", "texture3DLod": "textureLod",
    "texture3DProjLod": "textureProjLod",
    "textureCube": "texture", "textureCubeLod": "textureLod",
    "texture2DLodEXT": "textureLod", "texture2DProjLodEXT": "textureProjLod",
    "textureCubeLodEXT": "textureLod", "texture2DGradEXT": "textureGrad",
    "texture2DProjGradEXT": "textureProjGrad", "textureCubeGradEXT": "textureGrad",
    "texture2DGradARB": "textureGrad", "texture2DProjGradARB": "textureProjGrad",
    "textureCubeGradARB": "textureGrad",
    "shadow1D": "texture", "shadow2D": "texture", "shadow1DProj": "textureProj",
    "shadow2DProj": "textureProj", "shadow1DLod": "textureLod", "shadow2DLod": "textureLod",
    "shadow1DProjLod": "textureProjLod", "shadow2DProjLod": "textureProjLod",
    "shadow2DRect": "texture", "shadow2DRectProj": "textureProj",
    "shadow2DEXT": "texture", "shadow2DProjEXT": "textureProj",
}

#: Built-in functions added in GLSL 1.30+ that a 1.10/1.20/ES 1.00 shader may use as names.
NEW_BUILTINS = frozenset(
    "texture textureProj textureLod textureOffset textureProjOffset textureLodOffset "
    "textureProjLod textureProjLodOffset textureGrad textureGradOffset textureProjGrad "
    "textureProjGradOffset texelFetch texelFetchOffset textureSize round roundEven trunc "
    "sinh cosh tanh asinh acosh atanh isnan isinf modf floatBitsToInt floatBitsToUint "
    "intBitsToFloat uintBitsToFloat packSnorm2x16 packUnorm2x16 unpackSnorm2x16 "
    "unpackUnorm2x16 packHalf2x16 unpackHalf2x16 inverse determinant outerProduct "
    "transpose".split()
)

_ES_ONLY_EXTENSIONS = frozenset({
    "GL_OES_standard_derivatives", "GL_EXT_shader_texture_lod", "GL_EXT_frag_depth",
    "GL_EXT_draw_buffers", "GL_OES_texture_3D",
})


def _skip(node, name: str) -> bool:
    """Fields that are not part of the tree: places and semantic annotations."""
    if name == "loc":
        return True
    if isinstance(node, A.Expr) and name == "type":
        return True
    return (isinstance(node, A.Call) and name in ("target", "kind")) or (
        isinstance(node, A.Ident) and name == "symbol")


def _rewrite(node, fn: Callable):
    """Rewrite a tree bottom-up in place: every child is replaced by ``fn(child)``."""
    for f in fields(node):
        if _skip(node, f.name):
            continue
        value = getattr(node, f.name)
        if isinstance(value, A.Node):
            setattr(node, f.name, fn(_rewrite(value, fn)))
        elif isinstance(value, list):
            new = []
            for item in value:
                if isinstance(item, A.Node):
                    item = fn(_rewrite(item, fn))
                    if item is None:
                        continue
                elif isinstance(item, tuple):
                    item = tuple(fn(_rewrite(x, fn)) if isinstance(x, A.Node) else x
                                 for x in item)
                new.append(item)
            setattr(node, f.name, new)
    return node


def _all_nodes(unit: A.TranslationUnit):
    out = []

    def visit(n):
        out.append(n)
        return n

    _rewrite(unit, visit)
    return out


def _target_version(unit: A.TranslationUnit) -> tuple[int, Optional[str]]:
    v = unit.version
    if unit.profile == "es" or v in (100, 300, 310, 320):
        return {310: 430, 320: 450}.get(v or 100, 330), "core"
    if v is None or v < 330:
        return 330, "core"
    return v, unit.profile


def _clash_names(unit: A.TranslationUnit, version: int, profile: Optional[str]) -> frozenset:
    """Names that are identifiers in the source but keywords or built-ins in the target."""
    clash = {w for w in KEYWORDS | RESERVED_WORDS if is_keyword(w, version, profile)}
    src = unit.version if unit.version is not None else (100 if unit.profile == "es" else 110)
    if src < 130 or (unit.profile == "es" and src < 300):
        clash |= NEW_BUILTINS
    return frozenset(clash)


def _unsupported(message: str, node: A.Node, hint: Optional[str] = None) -> UnsupportedShaderError:
    return UnsupportedShaderError(message, node.loc, hint)


def to_core(unit: A.TranslationUnit) -> A.TranslationUnit:
    """A rewritten deep copy of ``unit`` in ``#version 330 core`` (or its own version >= 330).

    >>> from rrcache.glsl.parser import parse_source
    >>> from rrcache.glsl.printer import print_glsl
    >>> src = "varying vec2 uv; uniform sampler2D t; void main() { gl_FragColor = texture2D(t, uv); }"
    >>> print(print_glsl(to_core(parse_source(src))), end="")
    #version 330 core
    out vec4 rr_FragColor;
    in vec2 uv;
    uniform sampler2D t;
    <BLANKLINE>
    void main()
    {
        rr_FragColor = texture(t, uv);
    }
    """
    u = copy.deepcopy(unit)
    version, profile = _target_version(unit)
    was_es = unit.profile == "es" or unit.version in (100, 300, 310, 320)
    clash = _clash_names(unit, version, profile)
    nodes = _all_nodes(u)

    user_functions = {n.name for n in nodes if isinstance(n, A.FunctionDecl)}
    declared: set[str] = set(user_functions)
    members: set[str] = set()
    for n in nodes:
        if isinstance(n, A.StructMember):
            members.update(d.name for d in n.declarators)
        elif isinstance(n, A.Declarator):
            declared.add(n.name)
        elif isinstance(n, A.Param) and n.name:
            declared.add(n.name)
        elif isinstance(n, A.StructSpecifier) and n.name:
            declared.add(n.name)
    declared -= members
    renames = {name: f"rr_{name}" for name in declared if name in clash}
    member_renames = {name: f"rr_{name}" for name in members if name in clash
                      and is_keyword(name, version, profile)}
    struct_names = {n.name for n in nodes if isinstance(n, A.StructSpecifier) and n.name}
    uses_frag_color = False

    def qualifiers(quals: list) -> list:
        out = []
        for q in quals:
            if isinstance(q, str):
                if q in PRECISION_QUALIFIERS:
                    continue
                if q == "varying":
                    q = "in"
            out.append(q)
        return out

    def fix(n):
        nonlocal uses_frag_color
        if isinstance(n, (A.FullType, A.InterfaceBlock, A.QualifierDecl)):
            if isinstance(n, A.FullType) and "attribute" in n.qualifiers:
                raise _unsupported(
                    "'attribute' declares a vertex shader input", n,
                    "rrcache optimises fragment shaders; pass the fragment shader file")
            had = bool(n.qualifiers)
            n.qualifiers = qualifiers(n.qualifiers)
            if isinstance(n, A.QualifierDecl):
                n.names = [FRAG_COLOR if x in ("gl_FragColor",) else renames.get(x, x)
                           for x in n.names]
                if had and not n.qualifiers:
                    return None
            return n
        if isinstance(n, A.PrecisionDecl):
            return None
        if isinstance(n, A.DeclStmt) and n.decl is None:
            return None
        if isinstance(n, A.Ident):
            if n.name == "gl_FragColor":
                uses_frag_color = True
                return A.Ident(FRAG_COLOR, loc=n.loc)
            if n.name == "gl_FragDepthEXT":
                return A.Ident("gl_FragDepth", loc=n.loc)
            if n.name == "gl_FragData":
                raise _unsupported("gl_FragData used without a constant index", n,
                                   "write gl_FragData[0] or gl_FragColor")
            n.name = renames.get(n.name, n.name)
            return n
        if isinstance(n, A.Declarator) or isinstance(n, A.Param):
            if n.name:
                n.name = renames.get(n.name, n.name)
            return n
        if isinstance(n, A.FunctionDecl):
            n.name = renames.get(n.name, n.name)
            return n
        if isinstance(n, A.StructSpecifier):
            if n.name:
                n.name = renames.get(n.name, n.name)
            for m in n.members:
                for d in m.declarators:
                    d.name = member_renames.get(d.name, d.name)
            return n
        if isinstance(n, A.TypeSpecifier):
            if n.name in struct_names:
                n.name = renames.get(n.name, n.name)
            return n
        if isinstance(n, A.Field):
            n.name = member_renames.get(n.name, n.name)
            return n
        if isinstance(n, A.Call):
            if n.name in user_functions or n.name in struct_names:
                n.name = renames.get(n.name, n.name)
                return n
            new = LEGACY_TEXTURE_FUNCTIONS.get(n.name)
            if new is None:
                return n
            call = A.Call(new, n.args, n.array_dims, loc=n.loc)
            if n.name.startswith("shadow"):
                return A.Call("vec4", [call], loc=n.loc)
            return call
        return n

    def frag_data(n):
        """gl_FragData[i] must be rewritten before the generic pass sees the bare name."""
        nonlocal uses_frag_color
        if isinstance(n, A.Index) and isinstance(n.obj, A.Ident) and n.obj.name == "gl_FragData":
            idx = n.index
            if isinstance(idx, A.IntLit) and idx.value == 0:
                uses_frag_color = True
                return A.Ident(FRAG_COLOR, loc=n.loc)
            if isinstance(idx, A.IntLit):
                raise _unsupported(
                    f"gl_FragData[{idx.value}] writes several colour outputs", n,
                    "rrcache handles shaders with one colour output (gl_FragData[0])")
            raise _unsupported("gl_FragData indexed by a non-constant expression", n,
                               "write gl_FragData[0] or gl_FragColor")
        return n

    _rewrite(u, frag_data)
    _rewrite(u, fix)
    if uses_frag_color:
        decl = A.VariableDecl(
            A.FullType(["out"], A.TypeSpecifier("vec4")), [A.Declarator(FRAG_COLOR)])
        u.decls.insert(0, decl)
    u.version, u.profile = version, profile
    locs = list(u.extension_locs) + [None] * (len(u.extensions) - len(u.extension_locs))
    kept = [(ext, loc) for ext, loc in zip(u.extensions, locs)
            if not (was_es and (ext[0] in _ES_ONLY_EXTENSIONS or ext[0].startswith("GL_OES_")))
            and ext[0] not in _ES_ONLY_EXTENSIONS]
    u.extensions = [ext for ext, _ in kept]
    u.extension_locs = [loc for _, loc in kept]
    return u
