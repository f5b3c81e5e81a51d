"""GLSL lexer: preprocessing tokens to classified tokens.

:func:`lex` turns the preprocessor's tokens (``PPToken(kind, text, loc)``, kind ``ident``,
``number``, ``punct`` or ``other``) into :class:`Token` objects of kind ``ident``, ``keyword``,
``int``, ``uint``, ``float``, ``double``, ``bool``, ``punct`` and a final ``eof``. Keywords cover
GLSL 4.60 and GLSL ES 3.00 (type names, qualifiers, control words). Reserved words (``goto``,
``class``, ``input``...) and malformed numbers raise :class:`~rrcache.errors.ParseError` at the
offending token.

Words that only became keywords in later GLSL versions (``sample``, ``patch``, ``buffer``...)
are identifiers when ``version`` says they were not yet keywords.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Iterable, Optional

from rrcache.errors import ParseError, SourceLoc


@dataclass(frozen=True)
class Token:
    """A classified token. ``value`` is the literal's value (int, float or bool) or None."""

    kind: str
    text: str
    value: Any
    loc: SourceLoc


def _expand(prefixes: str, stems: str) -> set[str]:
    return {p + s for p in prefixes.split(",") for s in stems.split()}


_SAMPLER_STEMS = (
    "1D 1DArray 2D 2DArray 2DRect 2DMS 2DMSArray 3D Cube CubeArray Buffer"
)

#: Built-in type names (GLSL 4.60 + ES 3.00).
TYPE_NAMES: frozenset[str] = frozenset(
    {"void", "bool", "int", "uint", "float", "double", "atomic_uint", "samplerExternalOES"}
    | _expand(",b,i,u,d", "vec2 vec3 vec4")
    | _expand(",d", "mat2 mat3 mat4 mat2x2 mat2x3 mat2x4 mat3x2 mat3x3 mat3x4 mat4x2 mat4x3 mat4x4")
    | _expand(",i,u", " ".join("sampler" + s for s in _SAMPLER_STEMS.split()))
    | {
        "sampler1DShadow", "sampler1DArrayShadow", "sampler2DShadow", "sampler2DArrayShadow",
        "sampler2DRectShadow", "samplerCubeShadow", "samplerCubeArrayShadow",
    }
    | _expand(",i,u", " ".join("image" + s for s in _SAMPLER_STEMS.split()))
    # explicit arithmetic types (GL_ARB_gpu_shader_int64, GL_AMD_gpu_shader_half_float...)
    | {"float16_t", "int64_t", "uint64_t"}
    | _expand("f16,i64,u64", "vec2 vec3 vec4")
    | _expand("f16", "mat2 mat3 mat4 mat2x2 mat2x3 mat2x4 mat3x2 mat3x3 mat3x4 mat4x2 mat4x3 mat4x4")
)

#: Qualifier words.
STORAGE_QUALIFIERS = frozenset(
    {"const", "in", "out", "inout", "attribute", "varying", "uniform", "buffer", "shared",
     "centroid", "sample", "patch"}
)
INTERPOLATION_QUALIFIERS = frozenset({"smooth", "flat", "noperspective"})
PRECISION_QUALIFIERS = frozenset({"lowp", "mediump", "highp"})
MEMORY_QUALIFIERS = frozenset({"coherent", "volatile", "restrict", "readonly", "writeonly"})
OTHER_QUALIFIERS = frozenset({"invariant", "precise", "nonuniformEXT"})
QUALIFIER_WORDS: frozenset[str] = (
    STORAGE_QUALIFIERS | INTERPOLATION_QUALIFIERS | PRECISION_QUALIFIERS | MEMORY_QUALIFIERS
    | OTHER_QUALIFIERS
)

CONTROL_WORDS = frozenset(
    {"break", "continue", "do", "for", "while", "switch", "case", "default", "if", "else",
     "discard", "return"}
)

KEYWORDS: frozenset[str] = (
    TYPE_NAMES | QUALIFIER_WORDS | CONTROL_WORDS
    | {"layout", "precision", "struct", "subroutine", "true", "false"}
)

#: Words reserved for future use: using one is an error.
RESERVED_WORDS: frozenset[str] = frozenset(
    "common partition active asm class union enum typedef template this resource goto inline "
    "noinline public static extern external interface long short half fixed unsigned superp "
    "input output hvec2 hvec3 hvec4 fvec2 fvec3 fvec4 filter sizeof cast namespace using "
    "sampler3DRect".split()
)

# Desktop version from which a word is a keyword or reserved; earlier it is an identifier.
_DESKTOP_SINCE = {
    "sample": 400, "patch": 400, "subroutine": 400, "precise": 400, "buffer": 430,
    "shared": 430, "coherent": 420, "restrict": 420, "readonly": 420,
    "writeonly": 420, "atomic_uint": 420, "resource": 420, "common": 400, "partition": 400,
    "active": 400, "filter": 400, "superp": 130, "smooth": 130, "flat": 130,
    "noperspective": 130, "centroid": 120, "invariant": 120, "layout": 140, "uint": 130,
    "uvec2": 130, "uvec3": 130, "uvec4": 130, "case": 130,
}
# ES version from which a word is a keyword or reserved.
_ES_SINCE = {
    "sample": 300, "patch": 300, "subroutine": 300, "precise": 310, "buffer": 310,
    "shared": 310, "coherent": 300, "restrict": 300, "readonly": 300, "writeonly": 300,
    "atomic_uint": 300, "resource": 300, "common": 300, "partition": 300, "active": 300,
    "filter": 300, "smooth": 300, "flat": 300, "noperspective": 300, "centroid": 300,
    "layout": 300, "uint": 300, "uvec2": 300, "uvec3": 300, "uvec4": 300, "case": 300,
}

_INT_RE = re.compile(r"(?:0[xX](?P<hex>[0-9a-fA-F]+)|(?P<dec>[0-9]+))(?P<u>[uU]?)(?P<l>[lL]?)\Z")
_FLOAT_RE = re.compile(
    r"(?P<num>(?:[0-9]+\.[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|[0-9]+[eE][+-]?[0-9]+)"
    r"(?P<suffix>f|F|lf|LF|hf|HF)?\Z"
)

_PUNCTUATORS = frozenset(
    "<<= >>= ++ -- << >> <= >= == != && || ^^ += -= *= /= %= &= ^= |= "
    "( ) [ ] { } . , : ; + - ! ~ * / % < > & ^ | ? =".split()
)


# Extensions that bring the ``layout`` keyword to desktop GLSL before 1.40.
LAYOUT_EXTENSIONS = frozenset({
    "GL_ARB_explicit_attrib_location", "GL_ARB_separate_shader_objects",
    "GL_ARB_shading_language_420pack", "GL_ARB_uniform_buffer_object",
    "GL_ARB_explicit_uniform_location", "GL_ARB_fragment_coord_conventions",
    "GL_ARB_conservative_depth", "GL_AMD_conservative_depth", "GL_ARB_enhanced_layouts",
    "GL_EXT_blend_func_extended", "GL_ARB_shader_image_load_store",
})


def is_keyword(word: str, version: Optional[int] = None, profile: Optional[str] = None) -> bool:
    """Whether ``word`` is a keyword (or reserved word) in the given GLSL version.

    >>> is_keyword("sample", 330), is_keyword("sample", 450), is_keyword("vec3")
    (False, True, True)
    """
    if word not in KEYWORDS and word not in RESERVED_WORDS:
        return False
    if version is None:
        return True
    since = _ES_SINCE if profile == "es" else _DESKTOP_SINCE
    return version >= since.get(word, 0)


def _number(tok: Any) -> Token:
    text = tok.text
    m = _INT_RE.match(text)
    if m:
        if m.group("hex") is not None:
            value = int(m.group("hex"), 16)
        else:
            digits = m.group("dec")
            if len(digits) > 1 and digits[0] == "0":
                if any(c in "89" for c in digits):
                    raise ParseError(
                        f"invalid octal literal '{text}'", tok.loc,
                        "a number starting with 0 is octal; remove the leading 0",
                    )
                value = int(digits, 8)
            else:
                value = int(digits)
        bits = 64 if m.group("l") else 32  # 1l, 2ul: 64-bit (GL_ARB_gpu_shader_int64)
        if value >= 1 << bits:
            raise ParseError(
                f"integer literal '{text}' does not fit in {bits} bits", tok.loc,
                "use a float literal or a smaller value",
            )
        return Token("uint" if m.group("u") else "int", text, value, tok.loc)
    m = _FLOAT_RE.match(text)
    if m:
        suffix = m.group("suffix") or ""
        value = float(m.group("num"))
        kind = "double" if suffix.lower() == "lf" else "float"
        return Token(kind, text, value, tok.loc)
    raise ParseError(
        f"invalid number '{text}'", tok.loc,
        "GLSL numbers look like 12, 0x1F, 3u, 1.5, 2.0e-3, 1.0f or 1.0lf",
    )


def lex(pp_tokens: Iterable[Any], version: Optional[int] = None,
        profile: Optional[str] = None, filename: str = "<string>",
        extensions: Iterable[Any] = ()) -> list[Token]:
    """Classify preprocessing tokens; the result ends with an ``eof`` token.

    ``version``/``profile`` (from ``#version``) decide whether late keywords such as ``sample``
    are keywords; ``None`` means the newest language. ``filename`` names the place of the
    ``eof`` token when there are no tokens at all. ``extensions`` (``(name, behavior)`` pairs
    from ``#extension``) can make ``layout`` a keyword before GLSL 1.40
    (``GL_ARB_explicit_attrib_location`` and the like).

    >>> from rrcache.glsl.preprocessor import preprocess
    >>> [t.kind for t in lex(preprocess("vec3 a = 1.0;", "a.frag").tokens)]
    ['keyword', 'ident', 'punct', 'float', 'punct', 'eof']
    """
    out: list[Token] = []
    layout_ext = any(name in LAYOUT_EXTENSIONS and behavior != "disable"
                     for name, behavior in extensions)
    last_loc: Optional[SourceLoc] = None
    last_len = 0
    for tok in pp_tokens:
        kind, text, loc = tok.kind, tok.text, tok.loc
        if kind == "ident":
            if text in ("true", "false"):
                out.append(Token("bool", text, text == "true", loc))
            elif is_keyword(text, version, profile) or (text == "layout" and layout_ext):
                if text in RESERVED_WORDS:
                    raise ParseError(
                        f"'{text}' is a reserved word", loc, "rename it; GLSL reserves this name"
                    )
                out.append(Token("keyword", text, None, loc))
            else:
                out.append(Token("ident", text, None, loc))
        elif kind == "number":
            out.append(_number(tok))
        elif kind == "punct":
            if text not in _PUNCTUATORS:
                raise ParseError(f"unexpected character '{text}'", loc)
            out.append(Token("punct", text, None, loc))
        else:
            raise ParseError(
                f"unexpected character '{text}'", loc,
                "GLSL has no strings or characters like this outside comments",
            )
        last_loc, last_len = loc, len(text)
    if last_loc is None:
        eof_loc = SourceLoc(filename, 1, 1)
    else:
        eof_loc = SourceLoc(last_loc.file, last_loc.line, last_loc.col + last_len)
    out.append(Token("eof", "", None, eof_loc))
    return out
