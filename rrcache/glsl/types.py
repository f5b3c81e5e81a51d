"""The GLSL type representation.

A :class:`Type` is a frozen, hashable value: a base kind (``float double int uint bool void``,
an opaque name such as ``sampler2D`` or ``image2D``, or ``struct``), a vector size or a matrix
shape, array dimensions (outermost first) and, for structs, the name and the member list.

>>> Type.from_name("vec3")
Type('vec3')
>>> Type.from_name("mat2x3").column_type()
Type('vec3')
>>> swizzle(VEC4, "xz")
(Type('vec2'), True)
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from rrcache.errors import SemanticError, SourceLoc

# The last three are the explicit arithmetic types of GL_ARB_gpu_shader_int64,
# GL_AMD_gpu_shader_half_float and GL_EXT_shader_explicit_arithmetic_types.
SCALAR_BASES = ("float", "double", "int", "uint", "bool", "float16_t", "int64_t", "uint64_t")
FLOAT_BASES = frozenset({"float", "double", "float16_t"})
INTEGER_BASES = frozenset({"int", "uint", "int64_t", "uint64_t"})
_VEC_PREFIX = {"float": "vec", "double": "dvec", "int": "ivec", "uint": "uvec", "bool": "bvec",
               "float16_t": "f16vec", "int64_t": "i64vec", "uint64_t": "u64vec"}
_MAT_PREFIX = {"float": "mat", "double": "dmat", "float16_t": "f16mat"}
_PREFIX_BASE = {v: k for k, v in _VEC_PREFIX.items()}

# Opaque types: samplers and images in their float/int/uint flavours, plus atomic counters.
_SAMPLER_SHAPES = ("1D", "2D", "3D", "Cube", "2DRect", "1DArray", "2DArray", "CubeArray",
                   "Buffer", "2DMS", "2DMSArray")
_SHADOW_SHAPES = ("1DShadow", "2DShadow", "CubeShadow", "2DRectShadow", "1DArrayShadow",
                  "2DArrayShadow", "CubeArrayShadow")
_IMAGE_SHAPES = ("1D", "2D", "3D", "2DRect", "Cube", "Buffer", "1DArray", "2DArray", "CubeArray",
                 "2DMS", "2DMSArray")
OPAQUE_NAMES = frozenset(
    [f"{p}sampler{s}" for p in ("", "i", "u") for s in _SAMPLER_SHAPES]
    + [f"sampler{s}" for s in _SHADOW_SHAPES]
    + [f"{p}image{s}" for p in ("", "i", "u") for s in _IMAGE_SHAPES]
    + ["atomic_uint", "samplerExternalOES"]
)

#: Vulkan GLSL (GL_KHR_vulkan_glsl) opaque types: separate textures and samplers, combined by
#: constructors such as ``sampler2D(texture2D, sampler)``, and subpass inputs. In OpenGL GLSL these
#: words are ordinary identifiers (``uniform sampler2D sampler;`` is valid there), so they are
#: types only where a declaration expects one (see the parser) and may still name variables.
SOFT_TYPE_NAMES = frozenset(
    [f"{p}texture{s}" for p in ("", "i", "u") for s in _SAMPLER_SHAPES]
    + [f"{p}subpassInput{ms}" for p in ("", "i", "u") for ms in ("", "MS")]
    + ["sampler", "samplerShadow"]
)
OPAQUE_NAMES = OPAQUE_NAMES | SOFT_TYPE_NAMES

SWIZZLE_SETS = ("xyzw", "rgba", "stpq")


@dataclass(frozen=True)
class Type:
    """A GLSL type.

    ``base`` is a scalar base (``float``...), ``void``, an opaque name (``sampler2D``) or
    ``struct``. ``size`` is the vector size (1 for scalars and non-vectors); ``cols``/``rows`` the
    matrix shape (0 when not a matrix); ``dims`` the array dimensions, outermost first (``None``
    for an unsized ``[]``); ``struct_name``/``fields`` describe a struct.

    >>> Type("float", 3).glsl_name()
    'vec3'
    >>> Type.from_name("float").array_of(4).glsl_name()
    'float[4]'
    """

    base: str
    size: int = 1
    cols: int = 0
    rows: int = 0
    dims: tuple[Optional[int], ...] = ()
    struct_name: Optional[str] = None
    fields: tuple[tuple[str, "Type"], ...] = ()

    # ------------------------------------------------------------------ construction
    @staticmethod
    def from_name(name: str) -> "Type":
        """The built-in type called ``name`` (``vec3``, ``mat4x2``, ``usampler2D``...).

        Raises ``KeyError`` when ``name`` is not a built-in type name.

        >>> Type.from_name("dmat3").glsl_name()
        'dmat3x3'
        """
        t = _BUILTIN_TYPES.get(name)
        if t is None:
            raise KeyError(name)
        return t

    @staticmethod
    def is_type_name(name: str) -> bool:
        """Whether ``name`` is a built-in type name (``vec3`` yes, ``foo`` no)."""
        return name in _BUILTIN_TYPES

    @staticmethod
    def vector(base: str, size: int) -> "Type":
        """``vector("float", 3)`` is ``vec3``; size 1 gives the scalar."""
        return Type(base, size)

    @staticmethod
    def matrix(cols: int, rows: int, base: str = "float") -> "Type":
        """``matrix(2, 3)`` is ``mat2x3`` (2 columns of vec3)."""
        return Type(base, 1, cols, rows)

    @staticmethod
    def struct(name: str, fields: tuple[tuple[str, "Type"], ...]) -> "Type":
        """A struct type with ordered ``(name, Type)`` fields."""
        return Type("struct", struct_name=name, fields=tuple(fields))

    def array_of(self, *dims: Optional[int]) -> "Type":
        """This type with array dimensions ``dims`` added outermost.

        >>> FLOAT.array_of(2).array_of(3).glsl_name()
        'float[3][2]'
        """
        return Type(self.base, self.size, self.cols, self.rows, tuple(dims) + self.dims,
                    self.struct_name, self.fields)

    def element_type(self) -> "Type":
        """The type of ``a[i]`` for an array ``a``: one dimension less."""
        if not self.dims:
            raise ValueError(f"{self.glsl_name()} is not an array")
        return Type(self.base, self.size, self.cols, self.rows, self.dims[1:], self.struct_name,
                    self.fields)

    def without_array(self) -> "Type":
        """The type with every array dimension removed."""
        return Type(self.base, self.size, self.cols, self.rows, (), self.struct_name, self.fields)

    def with_base(self, base: str) -> "Type":
        """The same shape with another scalar base: ``VEC3.with_base("int")`` is ``ivec3``."""
        return Type(base, self.size, self.cols, self.rows, self.dims, None, ())

    def scalar_type(self) -> "Type":
        """The component type: ``float`` for ``vec3`` and ``mat4``."""
        return Type(self.base)

    def column_type(self) -> "Type":
        """The column vector of a matrix (``vec3`` for ``mat2x3``)."""
        if not self.is_matrix:
            raise ValueError(f"{self.glsl_name()} is not a matrix")
        return Type(self.base, self.rows)

    # ------------------------------------------------------------------ predicates
    @property
    def is_array(self) -> bool:
        return bool(self.dims)

    @property
    def is_struct(self) -> bool:
        return self.base == "struct" and not self.dims

    @property
    def is_void(self) -> bool:
        return self.base == "void"

    @property
    def is_scalar(self) -> bool:
        return self.base in SCALAR_BASES and self.size == 1 and not self.cols and not self.dims

    @property
    def is_vector(self) -> bool:
        return self.base in SCALAR_BASES and self.size > 1 and not self.dims

    @property
    def is_matrix(self) -> bool:
        return self.cols > 0 and not self.dims

    @property
    def is_numeric(self) -> bool:
        """Scalar, vector or matrix of a non-bool base (not an array)."""
        return (self.base in FLOAT_BASES or self.base in INTEGER_BASES) and not self.dims

    @property
    def is_float(self) -> bool:
        """Base ``float``, ``double`` or ``float16_t`` (scalar, vector or matrix; not an array)."""
        return self.base in FLOAT_BASES and not self.dims

    @property
    def is_integer(self) -> bool:
        """Base ``int``, ``uint`` or a 64-bit integer (scalar or vector; not an array)."""
        return self.base in INTEGER_BASES and not self.dims

    @property
    def is_bool(self) -> bool:
        return self.base == "bool" and not self.dims

    @property
    def is_opaque(self) -> bool:
        """Samplers, images and atomic counters (also arrays of them)."""
        return self.base in OPAQUE_NAMES

    @property
    def is_sampler(self) -> bool:
        return "sampler" in self.base

    @property
    def is_basic(self) -> bool:
        """Scalar, vector or matrix (what constructors and arithmetic take)."""
        return self.base in SCALAR_BASES and not self.dims

    def contains_opaque(self) -> bool:
        """Whether this type is or holds (in a struct member) an opaque type."""
        if self.is_opaque:
            return True
        return any(t.contains_opaque() for _, t in self.fields)

    @property
    def components(self) -> int:
        """Number of scalar components (vectors: size; matrices: cols×rows; structs: the sum of
        the members; arrays: times every dimension). Opaque types count 1."""
        if self.base == "struct":
            n = sum(t.components for _, t in self.fields)
        elif self.cols:
            n = self.cols * self.rows
        else:
            n = self.size
        for d in self.dims:
            n *= d or 0
        return n

    def field_type(self, name: str) -> Optional["Type"]:
        """The type of struct member ``name`` (``None`` if there is none)."""
        for fname, ftype in self.fields:
            if fname == name:
                return ftype
        return None

    # ------------------------------------------------------------------ printing
    def glsl_name(self) -> str:
        """The GLSL spelling: ``vec3``, ``mat2x3``, ``float[4]``, ``Light[2]``."""
        if self.base == "struct":
            head = self.struct_name or "<anonymous struct>"
        elif self.cols:
            head = f"{_MAT_PREFIX[self.base]}{self.cols}x{self.rows}"
        elif self.size > 1:
            head = f"{_VEC_PREFIX[self.base]}{self.size}"
        else:
            head = self.base
        return head + "".join(f"[{'' if d is None else d}]" for d in self.dims)

    def short_name(self) -> str:
        """Like :meth:`glsl_name` but square matrices as ``mat3`` (for messages)."""
        if self.cols and self.cols == self.rows and self.base in _MAT_PREFIX:
            head = f"{_MAT_PREFIX[self.base]}{self.cols}"
            return head + "".join(f"[{'' if d is None else d}]" for d in self.dims)
        return self.glsl_name()

    def __str__(self) -> str:
        return self.short_name()

    def __repr__(self) -> str:
        return f"Type({self.short_name()!r})"


def _build_type_table() -> dict[str, Type]:
    table: dict[str, Type] = {b: Type(b) for b in SCALAR_BASES}
    table["void"] = Type("void")
    for base, prefix in _VEC_PREFIX.items():
        for n in (2, 3, 4):
            table[f"{prefix}{n}"] = Type(base, n)
    for base, prefix in _MAT_PREFIX.items():
        for c in (2, 3, 4):
            table[f"{prefix}{c}"] = Type(base, 1, c, c)
            for r in (2, 3, 4):
                table[f"{prefix}{c}x{r}"] = Type(base, 1, c, r)
    for name in OPAQUE_NAMES:
        table[name] = Type(name)
    return table


_BUILTIN_TYPES = _build_type_table()
BUILTIN_TYPE_NAMES = frozenset(_BUILTIN_TYPES)

VOID = Type("void")
FLOAT, DOUBLE, INT, UINT, BOOL = (Type(b) for b in ("float", "double", "int", "uint", "bool"))
FLOAT16, INT64, UINT64 = Type("float16_t"), Type("int64_t"), Type("uint64_t")
VEC2, VEC3, VEC4 = (Type("float", n) for n in (2, 3, 4))
DVEC2, DVEC3, DVEC4 = (Type("double", n) for n in (2, 3, 4))
IVEC2, IVEC3, IVEC4 = (Type("int", n) for n in (2, 3, 4))
UVEC2, UVEC3, UVEC4 = (Type("uint", n) for n in (2, 3, 4))
BVEC2, BVEC3, BVEC4 = (Type("bool", n) for n in (2, 3, 4))
MAT2, MAT3, MAT4 = (Type("float", 1, n, n) for n in (2, 3, 4))
SAMPLER2D = Type("sampler2D")
SAMPLERCUBE = Type("samplerCube")


def swizzle(t: Type, name: str, loc: Optional[SourceLoc] = None) -> tuple[Type, bool]:
    """Type a swizzle ``v.name`` of a scalar or vector ``t``: returns ``(type, is_lvalue)``.

    The letters must come from one set (``xyzw``, ``rgba`` or ``stpq``), address components that
    exist, and number at most 4; the result is an l-value only when no component repeats.
    Raises :class:`SemanticError` (at ``loc``) otherwise.

    >>> swizzle(VEC3, "bgr")
    (Type('vec3'), True)
    >>> swizzle(VEC2, "xx")
    (Type('vec2'), False)
    """
    if not (t.is_scalar or t.is_vector):
        raise SemanticError(f"cannot swizzle a value of type '{t}'", loc)
    if len(name) > 4:
        raise SemanticError(f"swizzle '.{name}' has more than 4 components", loc)
    letter_set = next((s for s in SWIZZLE_SETS if name[0] in s), None)
    if letter_set is None:
        raise SemanticError(f"'{name}' is not a field or swizzle of '{t}'", loc,
                            "swizzles use the letters xyzw, rgba or stpq")
    for ch in name:
        if ch not in letter_set:
            raise SemanticError(
                f"swizzle '.{name}' mixes component sets", loc,
                f"use only one of xyzw, rgba, stpq ('{letter_set}' here)")
        if letter_set.index(ch) >= t.size:
            raise SemanticError(f"swizzle component '{ch}' is out of range for '{t}'", loc)
    result = Type(t.base, len(name))
    return result, len(set(name)) == len(name)


def swizzle_indices(name: str) -> tuple[int, ...]:
    """The component indices of a swizzle: ``swizzle_indices("zyx") == (2, 1, 0)``."""
    for s in SWIZZLE_SETS:
        if name and all(ch in s for ch in name):
            return tuple(s.index(ch) for ch in name)
    raise ValueError(f"not a swizzle: {name!r}")
