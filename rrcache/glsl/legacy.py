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
from typing import Optional

from rrcache.errors import UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.lexer import KEYWORDS, PRECISION_QUALIFIERS, RESERVED_WORDS, is_keyword
from rrcache.glsl.visitor import NodeTransformer, NodeVisitor

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
    fix = _ToCore(u, version, profile, _clash_names(unit, version, profile))
    _FragData(fix).visit(u)
    fix.visit(u)
    if fix.uses_frag_color:
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


def _qualifiers(quals: list) -> list:
    out = []
    for q in quals:
        if isinstance(q, str):
            if q in PRECISION_QUALIFIERS:
                continue
            if q == "varying":
                q = "in"
        out.append(q)
    return out


class _FragData(NodeTransformer):
    """``gl_FragData[0]`` becomes ``rr_FragColor``, before :class:`_ToCore` sees the bare name."""

    def __init__(self, core: "_ToCore"):
        self.core = core

    def visit_Index(self, n: A.Index):
        self.generic_visit(n)
        if not (isinstance(n.obj, A.Ident) and n.obj.name == "gl_FragData"):
            return n
        idx = n.index
        if isinstance(idx, A.IntLit) and idx.value == 0:
            self.core.uses_frag_color = True
            return A.Ident(FRAG_COLOR, loc=n.loc)
        if isinstance(idx, A.IntLit):
            raise _unsupported(
                f"gl_FragData[{idx.value}] writes several colour outputs", n,
                "rrcache handles shaders with one colour output (gl_FragData[0])")
        raise _unsupported("gl_FragData indexed by a non-constant expression", n,
                           "write gl_FragData[0] or gl_FragColor")


class _ToCore(NodeTransformer):
    """The rewrite of every node (bottom-up: children first) into core GLSL."""

    def __init__(self, u: A.TranslationUnit, version: int, profile: Optional[str],
                 clash: frozenset):
        nodes = list(A.walk(u))
        self.user_functions = {n.name for n in nodes if isinstance(n, A.FunctionDecl)}
        declared: set[str] = set(self.user_functions)
        members: set[str] = set()
        _Declared(declared, members).visit(u)
        declared -= members
        self.renames = {name: f"rr_{name}" for name in declared if name in clash}
        self.member_renames = {name: f"rr_{name}" for name in members if name in clash
                               and is_keyword(name, version, profile)}
        self.struct_names = {n.name for n in nodes if isinstance(n, A.StructSpecifier) and n.name}
        self.uses_frag_color = False

    def visit_FullType(self, n):
        self.generic_visit(n)
        if "attribute" in n.qualifiers:
            raise _unsupported(
                "'attribute' declares a vertex shader input", n,
                "rrcache optimises fragment shaders; pass the fragment shader file")
        n.qualifiers = _qualifiers(n.qualifiers)
        return n

    def visit_InterfaceBlock(self, n):
        self.generic_visit(n)
        n.qualifiers = _qualifiers(n.qualifiers)
        return n

    def visit_QualifierDecl(self, n):
        self.generic_visit(n)
        had = bool(n.qualifiers)
        n.qualifiers = _qualifiers(n.qualifiers)
        n.names = [FRAG_COLOR if x in ("gl_FragColor",) else self.renames.get(x, x)
                   for x in n.names]
        return None if had and not n.qualifiers else n

    def visit_PrecisionDecl(self, n):
        return None

    def visit_DeclStmt(self, n):
        self.generic_visit(n)
        return None if n.decl is None else n

    def visit_Ident(self, n):
        if n.name == "gl_FragColor":
            self.uses_frag_color = True
            return A.Ident(FRAG_COLOR, loc=n.loc)
        if n.name == "gl_FragDepthEXT":
            return A.Ident("gl_FragDepth", loc=n.loc)
        if n.name == "gl_FragData":
            raise _unsupported("gl_FragData used without a constant index", n,
                               "write gl_FragData[0] or gl_FragColor")
        n.name = self.renames.get(n.name, n.name)
        return n

    def visit_Declarator(self, n):
        self.generic_visit(n)
        if n.name:
            n.name = self.renames.get(n.name, n.name)
        return n

    visit_Param = visit_FunctionDecl = visit_Declarator

    def visit_StructSpecifier(self, n):
        self.generic_visit(n)
        if n.name:
            n.name = self.renames.get(n.name, n.name)
        for m in n.members:
            for d in m.declarators:
                d.name = self.member_renames.get(d.name, d.name)
        return n

    def visit_TypeSpecifier(self, n):
        self.generic_visit(n)
        if n.name in self.struct_names:
            n.name = self.renames.get(n.name, n.name)
        return n

    def visit_Field(self, n):
        self.generic_visit(n)
        n.name = self.member_renames.get(n.name, n.name)
        return n

    def visit_Call(self, n):
        self.generic_visit(n)
        if n.name in self.user_functions or n.name in self.struct_names:
            n.name = self.renames.get(n.name, n.name)
            return n
        new = LEGACY_TEXTURE_FUNCTIONS.get(n.name)
        if new is None:
            return n
        call = A.Call(new, n.args, n.array_dims, loc=n.loc)
        if n.name.startswith("shadow"):
            return A.Call("vec4", [call], loc=n.loc)
        return call


class _Declared(NodeVisitor):
    """The names a unit declares (variables, parameters, struct types) and its struct members."""

    def __init__(self, declared: set, members: set):
        self.declared, self.members = declared, members

    def visit_StructMember(self, n):
        self.members.update(d.name for d in n.declarators)
        self.generic_visit(n)

    def visit_Declarator(self, n):
        self.declared.add(n.name)
        self.generic_visit(n)

    def visit_Param(self, n):
        if n.name:
            self.declared.add(n.name)
        self.generic_visit(n)

    def visit_StructSpecifier(self, n):
        if n.name:
            self.declared.add(n.name)
        self.generic_visit(n)
