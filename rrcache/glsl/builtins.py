"""Built-in functions and variables of a GLSL fragment shader (GLSL 1.10–4.60, ES 1.00/3.x).

The function table is generated from compact signature specs written as in the GLSL
specification: ``genType`` (float, vec2..vec4), ``genIType``, ``genUType``, ``genBType``,
``genDType`` share one size per signature; ``vec``/``ivec``/``uvec``/``bvec``/``dvec`` mean sizes
2..4; ``mat``/``dmat`` every matrix shape; ``g`` (``gvec4``, ``gsampler2D``, ``gimage2D``) the
float/int/uint flavours of a sampler or image; ``[, float bias]`` an optional trailing argument;
``out``/``inout`` mark parameters the call writes.

Versions are not enforced (legacy names such as ``texture2D`` are accepted in any version, since
the front-end converts them). Each signature records whether it needs screen-space derivatives
(``dFdx``/``fwidth`` families and implicit-LOD texture lookups) and whether it has side effects
(atomics, image stores, memory barriers, ``out`` parameters); the analysis relies on both.

>>> [str(f) for f in lookup("cross")]
['vec3 cross(vec3, vec3)', 'dvec3 cross(dvec3, dvec3)', 'f16vec3 cross(f16vec3, f16vec3)']
>>> lookup("texture2D")[0].derivative
True
>>> BUILTIN_VARIABLES["gl_FragCoord"].read_only
True
"""
from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from typing import Iterable, Optional

from rrcache.glsl.types import Type

# ----------------------------------------------------------------------------- data classes


@dataclass(frozen=True)
class BuiltinFunction:
    """One built-in overload: ``vec4 texture(sampler2D, vec2)``.

    ``qualifiers[i]`` is ``in``, ``out`` or ``inout``; ``derivative`` says the function takes
    screen-space derivatives (explicitly or through an implicit texture LOD); ``side_effects``
    that it writes memory or an ``out`` argument; ``category`` the spec section
    (``trig``, ``texture``...); ``legacy`` names removed from core profiles.
    """

    name: str
    return_type: Type
    params: tuple[Type, ...]
    qualifiers: tuple[str, ...]
    category: str
    derivative: bool = False
    side_effects: bool = False
    legacy: bool = False

    @property
    def out_params(self) -> tuple[int, ...]:
        """Indices of the parameters written by the call (``out`` and ``inout``)."""
        return tuple(i for i, q in enumerate(self.qualifiers) if q != "in")

    def signature(self) -> str:
        """``name(type, type)``, e.g. ``mix(vec3, vec3, float)``."""
        return f"{self.name}({', '.join(map(str, self.params))})"

    def __str__(self) -> str:
        params = ", ".join(
            (f"{q} " if q != "in" else "") + str(t) for q, t in zip(self.qualifiers, self.params))
        return f"{self.return_type} {self.name}({params})"


@dataclass(frozen=True)
class BuiltinVariable:
    """A built-in variable: ``kind`` is ``in``, ``out``, ``uniform`` or ``const``; ``value`` the
    value of an integer constant (``gl_MaxDrawBuffers``)."""

    name: str
    type: Type
    kind: str
    read_only: bool
    value: Optional[int] = None
    legacy: bool = False


# ----------------------------------------------------------------------------- spec expansion

_GEN = {"genType": "float", "genDType": "double", "genIType": "int", "genUType": "uint",
        "genBType": "bool", "genF16Type": "float16_t", "genI64Type": "int64_t",
        "genU64Type": "uint64_t"}
_VEC = {"vec": "float", "dvec": "double", "ivec": "int", "uvec": "uint", "bvec": "bool"}
_SPEC_RE = re.compile(r"^\s*(\S+)\s+(\w+)\s*\((.*)\)\s*$")
_MAT_SHAPES = [(c, r) for c in (2, 3, 4) for r in (2, 3, 4)]


def _resolve(word: str, n: int, g: str, mat: Optional[tuple[int, int]]) -> Type:
    """The concrete type of one spec word under the substitution (n, g, mat)."""
    dims: tuple[Optional[int], ...] = ()
    m = re.match(r"^(\w+)\[(\d+)\]$", word)
    if m:
        word, dims = m.group(1), (int(m.group(2)),)
    if word in _GEN:
        t = Type(_GEN[word], n)
    elif word in _VEC:
        t = Type(_VEC[word], n)
    elif word in ("mat", "dmat"):
        assert mat is not None
        t = Type("double" if word == "dmat" else "float", 1, mat[0], mat[1])
    elif word == "gvec4":
        t = Type({"": "float", "i": "int", "u": "uint"}[g], 4)
    elif word == "gscalar":
        t = Type({"": "float", "i": "int", "u": "uint"}[g])
    elif word.startswith(("gsampler", "gimage", "gsubpassInput", "gtexture")):
        t = Type.from_name(g + word[1:])
    else:
        t = Type.from_name(word)
    return t.array_of(*dims) if dims else t


def _parse_params(text: str) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
    """Split ``"gsampler2D, vec2 [, float]"`` into required and optional ``(qual, word)``."""
    optional: list[tuple[str, str]] = []
    m = re.search(r"\[\s*,", text)
    if m:
        text, opt = text[:m.start()], text[m.end():]
        optional = _parse_params(opt.rstrip("] "))[0]
    required = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        words = part.split()
        qual = words[0] if words[0] in ("out", "inout") else "in"
        words = [w for w in words if w not in ("in", "out", "inout", "readonly", "writeonly")]
        required.append((qual, words[0]))
    return required, optional


def _expand(spec: str, category: str, derivative: bool = False, side_effects: bool = False,
            legacy: bool = False) -> list[BuiltinFunction]:
    """Every concrete overload described by one spec line."""
    m = _SPEC_RE.match(spec)
    if not m:
        raise ValueError(f"bad builtin spec: {spec!r}")
    ret_word, name, params_text = m.groups()
    required, optional = _parse_params(params_text)
    words = [ret_word] + [w for _, w in required + optional]
    bare = [re.sub(r"\[\d+\]$", "", w) for w in words]
    if any(w in _GEN for w in bare):
        sizes = (1, 2, 3, 4)
    elif any(w in _VEC for w in bare):
        sizes = (2, 3, 4)
    else:
        sizes = (1,)
    flavours = ("", "i", "u") if any(w.startswith("g") and not w.startswith("gen")
                                     for w in bare) else ("",)
    mats: list[Optional[tuple[int, int]]] = (
        list(_MAT_SHAPES) if any(w in ("mat", "dmat") for w in bare) else [None])
    out: list[BuiltinFunction] = []
    for n, g, mat in itertools.product(sizes, flavours, mats):
        for count in range(len(required), len(required) + len(optional) + 1):
            plist = (required + optional)[:count]
            params = tuple(_resolve(w, n, g, mat) for _, w in plist)
            quals = tuple(q for q, _ in plist)
            writes = side_effects or any(q != "in" for q in quals)
            out.append(BuiltinFunction(name, _resolve(ret_word, n, g, mat), params, quals,
                                       category, derivative, writes, legacy))
    return out


# ----------------------------------------------------------------------------- function specs
# (category, flags) -> spec lines. Flags: "d" derivative, "s" side effects, "l" legacy.

_SPECS: list[tuple[str, str, str]] = [
    ("trig", "", """
        genType radians(genType)        genType degrees(genType)
        genType sin(genType)            genType cos(genType)            genType tan(genType)
        genType asin(genType)           genType acos(genType)
        genType atan(genType, genType)  genType atan(genType)
        genType sinh(genType)           genType cosh(genType)           genType tanh(genType)
        genType asinh(genType)          genType acosh(genType)          genType atanh(genType)
    """),
    ("exponential", "", """
        genType pow(genType, genType)   genType exp(genType)            genType log(genType)
        genType exp2(genType)           genType log2(genType)
        genType sqrt(genType)           genDType sqrt(genDType)
        genType inversesqrt(genType)    genDType inversesqrt(genDType)
    """),
    ("common", "", """
        genType abs(genType)    genIType abs(genIType)    genDType abs(genDType)
        genType sign(genType)   genIType sign(genIType)   genDType sign(genDType)
        genType floor(genType)  genDType floor(genDType)  genType trunc(genType)
        genDType trunc(genDType)  genType round(genType)  genDType round(genDType)
        genType roundEven(genType)  genDType roundEven(genDType)
        genType ceil(genType)   genDType ceil(genDType)   genType fract(genType)
        genDType fract(genDType)
        genType mod(genType, float)  genType mod(genType, genType)
        genDType mod(genDType, double)  genDType mod(genDType, genDType)
        genType modf(genType, out genType)  genDType modf(genDType, out genDType)
        genType min(genType, genType)  genType min(genType, float)
        genDType min(genDType, genDType)  genDType min(genDType, double)
        genIType min(genIType, genIType)  genIType min(genIType, int)
        genUType min(genUType, genUType)  genUType min(genUType, uint)
        genType max(genType, genType)  genType max(genType, float)
        genDType max(genDType, genDType)  genDType max(genDType, double)
        genIType max(genIType, genIType)  genIType max(genIType, int)
        genUType max(genUType, genUType)  genUType max(genUType, uint)
        genType clamp(genType, genType, genType)  genType clamp(genType, float, float)
        genDType clamp(genDType, genDType, genDType)  genDType clamp(genDType, double, double)
        genIType clamp(genIType, genIType, genIType)  genIType clamp(genIType, int, int)
        genUType clamp(genUType, genUType, genUType)  genUType clamp(genUType, uint, uint)
        genType mix(genType, genType, genType)  genType mix(genType, genType, float)
        genDType mix(genDType, genDType, genDType)  genDType mix(genDType, genDType, double)
        genType mix(genType, genType, genBType)  genDType mix(genDType, genDType, genBType)
        genIType mix(genIType, genIType, genBType)  genUType mix(genUType, genUType, genBType)
        genBType mix(genBType, genBType, genBType)
        genType step(genType, genType)  genType step(float, genType)
        genDType step(genDType, genDType)  genDType step(double, genDType)
        genType smoothstep(genType, genType, genType)  genType smoothstep(float, float, genType)
        genDType smoothstep(genDType, genDType, genDType)
        genDType smoothstep(double, double, genDType)
        genBType isnan(genType)  genBType isnan(genDType)
        genBType isinf(genType)  genBType isinf(genDType)
        genIType floatBitsToInt(genType)  genUType floatBitsToUint(genType)
        genType intBitsToFloat(genIType)  genType uintBitsToFloat(genUType)
        genType fma(genType, genType, genType)  genDType fma(genDType, genDType, genDType)
        genType frexp(genType, out genIType)  genDType frexp(genDType, out genIType)
        genType ldexp(genType, genIType)  genDType ldexp(genDType, genIType)
    """),
    ("packing", "", """
        uint packUnorm2x16(vec2)  uint packSnorm2x16(vec2)  uint packUnorm4x8(vec4)
        uint packSnorm4x8(vec4)  vec2 unpackUnorm2x16(uint)  vec2 unpackSnorm2x16(uint)
        vec4 unpackUnorm4x8(uint)  vec4 unpackSnorm4x8(uint)  uint packHalf2x16(vec2)
        vec2 unpackHalf2x16(uint)  double packDouble2x32(uvec2)  uvec2 unpackDouble2x32(double)
    """),
    ("geometric", "", """
        float length(genType)  double length(genDType)
        float distance(genType, genType)  double distance(genDType, genDType)
        float dot(genType, genType)  double dot(genDType, genDType)
        vec3 cross(vec3, vec3)  dvec3 cross(dvec3, dvec3)
        genType normalize(genType)  genDType normalize(genDType)
        genType faceforward(genType, genType, genType)
        genDType faceforward(genDType, genDType, genDType)
        genType reflect(genType, genType)  genDType reflect(genDType, genDType)
        genType refract(genType, genType, float)  genDType refract(genDType, genDType, double)
    """),
    ("matrix", "", """
        mat matrixCompMult(mat, mat)  dmat matrixCompMult(dmat, dmat)
        float determinant(mat2)  float determinant(mat3)  float determinant(mat4)
        double determinant(dmat2)  double determinant(dmat3)  double determinant(dmat4)
        mat2 inverse(mat2)  mat3 inverse(mat3)  mat4 inverse(mat4)
        dmat2 inverse(dmat2)  dmat3 inverse(dmat3)  dmat4 inverse(dmat4)
    """),
    ("relational", "", """
        bvec lessThan(vec, vec)  bvec lessThan(ivec, ivec)  bvec lessThan(uvec, uvec)
        bvec lessThan(dvec, dvec)
        bvec lessThanEqual(vec, vec)  bvec lessThanEqual(ivec, ivec)
        bvec lessThanEqual(uvec, uvec)  bvec lessThanEqual(dvec, dvec)
        bvec greaterThan(vec, vec)  bvec greaterThan(ivec, ivec)  bvec greaterThan(uvec, uvec)
        bvec greaterThan(dvec, dvec)
        bvec greaterThanEqual(vec, vec)  bvec greaterThanEqual(ivec, ivec)
        bvec greaterThanEqual(uvec, uvec)  bvec greaterThanEqual(dvec, dvec)
        bvec equal(vec, vec)  bvec equal(ivec, ivec)  bvec equal(uvec, uvec)
        bvec equal(bvec, bvec)  bvec equal(dvec, dvec)
        bvec notEqual(vec, vec)  bvec notEqual(ivec, ivec)  bvec notEqual(uvec, uvec)
        bvec notEqual(bvec, bvec)  bvec notEqual(dvec, dvec)
        bool any(bvec)  bool all(bvec)  bvec not(bvec)
    """),
    ("integer", "", """
        genUType uaddCarry(genUType, genUType, out genUType)
        genUType usubBorrow(genUType, genUType, out genUType)
        void umulExtended(genUType, genUType, out genUType, out genUType)
        void imulExtended(genIType, genIType, out genIType, out genIType)
        genIType bitfieldExtract(genIType, int, int)  genUType bitfieldExtract(genUType, int, int)
        genIType bitfieldInsert(genIType, genIType, int, int)
        genUType bitfieldInsert(genUType, genUType, int, int)
        genIType bitfieldReverse(genIType)  genUType bitfieldReverse(genUType)
        genIType bitCount(genIType)  genIType bitCount(genUType)
        genIType findLSB(genIType)  genIType findLSB(genUType)
        genIType findMSB(genIType)  genIType findMSB(genUType)
    """),
    ("derivative", "d", """
        genType dFdx(genType)  genType dFdy(genType)  genType fwidth(genType)
        genType dFdxFine(genType)  genType dFdyFine(genType)  genType fwidthFine(genType)
        genType dFdxCoarse(genType)  genType dFdyCoarse(genType)  genType fwidthCoarse(genType)
    """),
    ("interpolation", "", """
        genType interpolateAtCentroid(genType)  genType interpolateAtSample(genType, int)
        genType interpolateAtOffset(genType, vec2)
    """),
    ("noise", "l", """
        float noise1(genType)  vec2 noise2(genType)  vec3 noise3(genType)  vec4 noise4(genType)
    """),
    ("vote", "", """
        bool anyInvocation(bool)  bool allInvocations(bool)  bool allInvocationsEqual(bool)
    """),
    ("atomic-counter", "s", """
        uint atomicCounterIncrement(atomic_uint)  uint atomicCounterDecrement(atomic_uint)
        uint atomicCounter(atomic_uint)  uint atomicCounterAdd(atomic_uint, uint)
        uint atomicCounterSubtract(atomic_uint, uint)  uint atomicCounterMin(atomic_uint, uint)
        uint atomicCounterMax(atomic_uint, uint)  uint atomicCounterAnd(atomic_uint, uint)
        uint atomicCounterOr(atomic_uint, uint)  uint atomicCounterXor(atomic_uint, uint)
        uint atomicCounterExchange(atomic_uint, uint)
        uint atomicCounterCompSwap(atomic_uint, uint, uint)
    """),
    ("atomic", "s", """
        uint atomicAdd(inout uint, uint)  int atomicAdd(inout int, int)
        uint atomicMin(inout uint, uint)  int atomicMin(inout int, int)
        uint atomicMax(inout uint, uint)  int atomicMax(inout int, int)
        uint atomicAnd(inout uint, uint)  int atomicAnd(inout int, int)
        uint atomicOr(inout uint, uint)  int atomicOr(inout int, int)
        uint atomicXor(inout uint, uint)  int atomicXor(inout int, int)
        uint atomicExchange(inout uint, uint)  int atomicExchange(inout int, int)
        uint atomicCompSwap(inout uint, uint, uint)  int atomicCompSwap(inout int, int, int)
    """),
    ("barrier", "s", """
        void memoryBarrier()  void memoryBarrierAtomicCounter()  void memoryBarrierBuffer()
        void memoryBarrierImage()
    """),
    # Texture lookups. Implicit-LOD functions (no lod/grad argument) take derivatives.
    ("texture", "d", """
        gvec4 texture(gsampler1D, float [, float])  gvec4 texture(gsampler2D, vec2 [, float])
        gvec4 texture(gsampler3D, vec3 [, float])  gvec4 texture(gsamplerCube, vec3 [, float])
        float texture(sampler1DShadow, vec3 [, float])
        float texture(sampler2DShadow, vec3 [, float])
        float texture(samplerCubeShadow, vec4 [, float])
        gvec4 texture(gsampler1DArray, vec2 [, float])
        gvec4 texture(gsampler2DArray, vec3 [, float])
        gvec4 texture(gsamplerCubeArray, vec4 [, float])
        float texture(sampler1DArrayShadow, vec3 [, float])
        float texture(sampler2DArrayShadow, vec4)
        float texture(samplerCubeArrayShadow, vec4, float)
        vec4 texture(samplerExternalOES, vec2 [, float])
        gvec4 textureProj(gsampler1D, vec2 [, float])  gvec4 textureProj(gsampler1D, vec4 [, float])
        gvec4 textureProj(gsampler2D, vec3 [, float])  gvec4 textureProj(gsampler2D, vec4 [, float])
        gvec4 textureProj(gsampler3D, vec4 [, float])
        float textureProj(sampler1DShadow, vec4 [, float])
        float textureProj(sampler2DShadow, vec4 [, float])
        vec4 textureProj(samplerExternalOES, vec3 [, float])
        vec4 textureProj(samplerExternalOES, vec4 [, float])
        gvec4 textureOffset(gsampler1D, float, int [, float])
        gvec4 textureOffset(gsampler2D, vec2, ivec2 [, float])
        gvec4 textureOffset(gsampler3D, vec3, ivec3 [, float])
        float textureOffset(sampler1DShadow, vec3, int [, float])
        float textureOffset(sampler2DShadow, vec3, ivec2 [, float])
        gvec4 textureOffset(gsampler1DArray, vec2, int [, float])
        gvec4 textureOffset(gsampler2DArray, vec3, ivec2 [, float])
        float textureOffset(sampler1DArrayShadow, vec3, int [, float])
        float textureOffset(sampler2DArrayShadow, vec4, ivec2)
        gvec4 textureProjOffset(gsampler1D, vec2, int [, float])
        gvec4 textureProjOffset(gsampler1D, vec4, int [, float])
        gvec4 textureProjOffset(gsampler2D, vec3, ivec2 [, float])
        gvec4 textureProjOffset(gsampler2D, vec4, ivec2 [, float])
        gvec4 textureProjOffset(gsampler3D, vec4, ivec3 [, float])
        float textureProjOffset(sampler1DShadow, vec4, int [, float])
        float textureProjOffset(sampler2DShadow, vec4, ivec2 [, float])
        vec2 textureQueryLod(gsampler1D, float)  vec2 textureQueryLod(gsampler2D, vec2)
        vec2 textureQueryLod(gsampler3D, vec3)  vec2 textureQueryLod(gsamplerCube, vec3)
        vec2 textureQueryLod(gsampler1DArray, float)  vec2 textureQueryLod(gsampler2DArray, vec2)
        vec2 textureQueryLod(gsamplerCubeArray, vec3)
        vec2 textureQueryLod(sampler1DShadow, float)  vec2 textureQueryLod(sampler2DShadow, vec2)
        vec2 textureQueryLod(samplerCubeShadow, vec3)
        vec2 textureQueryLod(sampler1DArrayShadow, float)
        vec2 textureQueryLod(sampler2DArrayShadow, vec2)
        vec2 textureQueryLod(samplerCubeArrayShadow, vec3)
        vec2 textureQueryLOD(gsampler1D, float)  vec2 textureQueryLOD(gsampler2D, vec2)
        vec2 textureQueryLOD(gsampler3D, vec3)  vec2 textureQueryLOD(gsamplerCube, vec3)
        vec2 textureQueryLOD(gsampler1DArray, float)  vec2 textureQueryLOD(gsampler2DArray, vec2)
        vec2 textureQueryLOD(gsamplerCubeArray, vec3)
        vec2 textureQueryLOD(sampler1DShadow, float)  vec2 textureQueryLOD(sampler2DShadow, vec2)
        vec2 textureQueryLOD(samplerCubeShadow, vec3)
        vec2 textureQueryLOD(sampler1DArrayShadow, float)
        vec2 textureQueryLOD(sampler2DArrayShadow, vec2)
        vec2 textureQueryLOD(samplerCubeArrayShadow, vec3)
    """),
    # Rectangle textures have no mipmaps: implicit lookups on them take no derivatives.
    ("texture", "", """
        gvec4 texture(gsampler2DRect, vec2)  float texture(sampler2DRectShadow, vec3)
        gvec4 textureProj(gsampler2DRect, vec3)  gvec4 textureProj(gsampler2DRect, vec4)
        float textureProj(sampler2DRectShadow, vec4)
        gvec4 textureOffset(gsampler2DRect, vec2, ivec2)
        float textureOffset(sampler2DRectShadow, vec3, ivec2)
        gvec4 textureProjOffset(gsampler2DRect, vec3, ivec2)
        gvec4 textureProjOffset(gsampler2DRect, vec4, ivec2)
        float textureProjOffset(sampler2DRectShadow, vec4, ivec2)
        gvec4 textureLod(gsampler1D, float, float)  gvec4 textureLod(gsampler2D, vec2, float)
        gvec4 textureLod(gsampler3D, vec3, float)  gvec4 textureLod(gsamplerCube, vec3, float)
        float textureLod(sampler1DShadow, vec3, float)
        float textureLod(sampler2DShadow, vec3, float)
        gvec4 textureLod(gsampler1DArray, vec2, float)
        gvec4 textureLod(gsampler2DArray, vec3, float)
        float textureLod(sampler1DArrayShadow, vec3, float)
        gvec4 textureLod(gsamplerCubeArray, vec4, float)
        gvec4 textureLodOffset(gsampler1D, float, float, int)
        gvec4 textureLodOffset(gsampler2D, vec2, float, ivec2)
        gvec4 textureLodOffset(gsampler3D, vec3, float, ivec3)
        float textureLodOffset(sampler1DShadow, vec3, float, int)
        float textureLodOffset(sampler2DShadow, vec3, float, ivec2)
        gvec4 textureLodOffset(gsampler1DArray, vec2, float, int)
        gvec4 textureLodOffset(gsampler2DArray, vec3, float, ivec2)
        float textureLodOffset(sampler1DArrayShadow, vec3, float, int)
        gvec4 textureProjLod(gsampler1D, vec2, float)  gvec4 textureProjLod(gsampler1D, vec4, float)
        gvec4 textureProjLod(gsampler2D, vec3, float)  gvec4 textureProjLod(gsampler2D, vec4, float)
        gvec4 textureProjLod(gsampler3D, vec4, float)
        float textureProjLod(sampler1DShadow, vec4, float)
        float textureProjLod(sampler2DShadow, vec4, float)
        gvec4 textureProjLodOffset(gsampler1D, vec2, float, int)
        gvec4 textureProjLodOffset(gsampler1D, vec4, float, int)
        gvec4 textureProjLodOffset(gsampler2D, vec3, float, ivec2)
        gvec4 textureProjLodOffset(gsampler2D, vec4, float, ivec2)
        gvec4 textureProjLodOffset(gsampler3D, vec4, float, ivec3)
        float textureProjLodOffset(sampler1DShadow, vec4, float, int)
        float textureProjLodOffset(sampler2DShadow, vec4, float, ivec2)
        gvec4 texelFetch(gsampler1D, int, int)  gvec4 texelFetch(gsampler2D, ivec2, int)
        gvec4 texelFetch(gsampler3D, ivec3, int)  gvec4 texelFetch(gsampler2DRect, ivec2)
        gvec4 texelFetch(gsampler1DArray, ivec2, int)
        gvec4 texelFetch(gsampler2DArray, ivec3, int)  gvec4 texelFetch(gsamplerBuffer, int)
        gvec4 texelFetch(gsampler2DMS, ivec2, int)  gvec4 texelFetch(gsampler2DMSArray, ivec3, int)
        gvec4 texelFetchOffset(gsampler1D, int, int, int)
        gvec4 texelFetchOffset(gsampler2D, ivec2, int, ivec2)
        gvec4 texelFetchOffset(gsampler3D, ivec3, int, ivec3)
        gvec4 texelFetchOffset(gsampler2DRect, ivec2, ivec2)
        gvec4 texelFetchOffset(gsampler1DArray, ivec2, int, int)
        gvec4 texelFetchOffset(gsampler2DArray, ivec3, int, ivec2)
        gvec4 textureGrad(gsampler1D, float, float, float)
        gvec4 textureGrad(gsampler2D, vec2, vec2, vec2)
        gvec4 textureGrad(gsampler3D, vec3, vec3, vec3)
        gvec4 textureGrad(gsamplerCube, vec3, vec3, vec3)
        gvec4 textureGrad(gsampler2DRect, vec2, vec2, vec2)
        float textureGrad(sampler2DRectShadow, vec3, vec2, vec2)
        float textureGrad(sampler1DShadow, vec3, float, float)
        float textureGrad(sampler2DShadow, vec3, vec2, vec2)
        float textureGrad(samplerCubeShadow, vec4, vec3, vec3)
        gvec4 textureGrad(gsampler1DArray, vec2, float, float)
        gvec4 textureGrad(gsampler2DArray, vec3, vec2, vec2)
        float textureGrad(sampler1DArrayShadow, vec3, float, float)
        float textureGrad(sampler2DArrayShadow, vec4, vec2, vec2)
        gvec4 textureGrad(gsamplerCubeArray, vec4, vec3, vec3)
        gvec4 textureGradOffset(gsampler1D, float, float, float, int)
        gvec4 textureGradOffset(gsampler2D, vec2, vec2, vec2, ivec2)
        gvec4 textureGradOffset(gsampler3D, vec3, vec3, vec3, ivec3)
        gvec4 textureGradOffset(gsampler2DRect, vec2, vec2, vec2, ivec2)
        float textureGradOffset(sampler2DRectShadow, vec3, vec2, vec2, ivec2)
        float textureGradOffset(sampler1DShadow, vec3, float, float, int)
        float textureGradOffset(sampler2DShadow, vec3, vec2, vec2, ivec2)
        gvec4 textureGradOffset(gsampler1DArray, vec2, float, float, int)
        gvec4 textureGradOffset(gsampler2DArray, vec3, vec2, vec2, ivec2)
        float textureGradOffset(sampler1DArrayShadow, vec3, float, float, int)
        float textureGradOffset(sampler2DArrayShadow, vec4, vec2, vec2, ivec2)
        gvec4 textureProjGrad(gsampler1D, vec2, float, float)
        gvec4 textureProjGrad(gsampler1D, vec4, float, float)
        gvec4 textureProjGrad(gsampler2D, vec3, vec2, vec2)
        gvec4 textureProjGrad(gsampler2D, vec4, vec2, vec2)
        gvec4 textureProjGrad(gsampler3D, vec4, vec3, vec3)
        gvec4 textureProjGrad(gsampler2DRect, vec3, vec2, vec2)
        gvec4 textureProjGrad(gsampler2DRect, vec4, vec2, vec2)
        float textureProjGrad(sampler2DRectShadow, vec4, vec2, vec2)
        float textureProjGrad(sampler1DShadow, vec4, float, float)
        float textureProjGrad(sampler2DShadow, vec4, vec2, vec2)
        gvec4 textureProjGradOffset(gsampler1D, vec2, float, float, int)
        gvec4 textureProjGradOffset(gsampler1D, vec4, float, float, int)
        gvec4 textureProjGradOffset(gsampler2D, vec3, vec2, vec2, ivec2)
        gvec4 textureProjGradOffset(gsampler2D, vec4, vec2, vec2, ivec2)
        gvec4 textureProjGradOffset(gsampler3D, vec4, vec3, vec3, ivec3)
        gvec4 textureProjGradOffset(gsampler2DRect, vec3, vec2, vec2, ivec2)
        gvec4 textureProjGradOffset(gsampler2DRect, vec4, vec2, vec2, ivec2)
        float textureProjGradOffset(sampler2DRectShadow, vec4, vec2, vec2, ivec2)
        float textureProjGradOffset(sampler1DShadow, vec4, float, float, int)
        float textureProjGradOffset(sampler2DShadow, vec4, vec2, vec2, ivec2)
        gvec4 textureGather(gsampler2D, vec2 [, int])
        gvec4 textureGather(gsampler2DArray, vec3 [, int])
        gvec4 textureGather(gsamplerCube, vec3 [, int])
        gvec4 textureGather(gsamplerCubeArray, vec4 [, int])
        gvec4 textureGather(gsampler2DRect, vec2 [, int])
        vec4 textureGather(sampler2DShadow, vec2, float)
        vec4 textureGather(sampler2DArrayShadow, vec3, float)
        vec4 textureGather(samplerCubeShadow, vec3, float)
        vec4 textureGather(samplerCubeArrayShadow, vec4, float)
        vec4 textureGather(sampler2DRectShadow, vec2, float)
        gvec4 textureGatherOffset(gsampler2D, vec2, ivec2 [, int])
        gvec4 textureGatherOffset(gsampler2DArray, vec3, ivec2 [, int])
        gvec4 textureGatherOffset(gsampler2DRect, vec2, ivec2 [, int])
        vec4 textureGatherOffset(sampler2DShadow, vec2, float, ivec2)
        vec4 textureGatherOffset(sampler2DArrayShadow, vec3, float, ivec2)
        vec4 textureGatherOffset(sampler2DRectShadow, vec2, float, ivec2)
        gvec4 textureGatherOffsets(gsampler2D, vec2, ivec2[4] [, int])
        gvec4 textureGatherOffsets(gsampler2DArray, vec3, ivec2[4] [, int])
        gvec4 textureGatherOffsets(gsampler2DRect, vec2, ivec2[4] [, int])
        vec4 textureGatherOffsets(sampler2DShadow, vec2, float, ivec2[4])
        vec4 textureGatherOffsets(sampler2DArrayShadow, vec3, float, ivec2[4])
        vec4 textureGatherOffsets(sampler2DRectShadow, vec2, float, ivec2[4])
        int textureSize(gsampler1D, int)  ivec2 textureSize(gsampler2D, int)
        ivec3 textureSize(gsampler3D, int)  ivec2 textureSize(gsamplerCube, int)
        int textureSize(sampler1DShadow, int)  ivec2 textureSize(sampler2DShadow, int)
        ivec2 textureSize(samplerCubeShadow, int)  ivec3 textureSize(gsamplerCubeArray, int)
        ivec3 textureSize(samplerCubeArrayShadow, int)  ivec2 textureSize(gsampler2DRect)
        ivec2 textureSize(sampler2DRectShadow)  ivec2 textureSize(gsampler1DArray, int)
        ivec2 textureSize(sampler1DArrayShadow, int)  ivec3 textureSize(gsampler2DArray, int)
        ivec3 textureSize(sampler2DArrayShadow, int)  int textureSize(gsamplerBuffer)
        ivec2 textureSize(gsampler2DMS)  ivec3 textureSize(gsampler2DMSArray)
        ivec2 textureSize(samplerExternalOES, int)
        int textureQueryLevels(gsampler1D)  int textureQueryLevels(gsampler2D)
        int textureQueryLevels(gsampler3D)  int textureQueryLevels(gsamplerCube)
        int textureQueryLevels(gsampler1DArray)  int textureQueryLevels(gsampler2DArray)
        int textureQueryLevels(gsamplerCubeArray)  int textureQueryLevels(sampler1DShadow)
        int textureQueryLevels(sampler2DShadow)  int textureQueryLevels(samplerCubeShadow)
        int textureQueryLevels(sampler1DArrayShadow)
        int textureQueryLevels(sampler2DArrayShadow)
        int textureQueryLevels(samplerCubeArrayShadow)
        int textureSamples(gsampler2DMS)  int textureSamples(gsampler2DMSArray)
    """),
    # Legacy (GLSL 1.10-1.40, compatibility, ES 1.00 and their extensions).
    ("texture", "dl", """
        vec4 texture1D(sampler1D, float [, float])  vec4 texture1DProj(sampler1D, vec2 [, float])
        vec4 texture1DProj(sampler1D, vec4 [, float])  vec4 texture2D(sampler2D, vec2 [, float])
        vec4 texture2DProj(sampler2D, vec3 [, float])  vec4 texture2DProj(sampler2D, vec4 [, float])
        vec4 texture3D(sampler3D, vec3 [, float])  vec4 texture3DProj(sampler3D, vec4 [, float])
        vec4 textureCube(samplerCube, vec3 [, float])
        vec4 shadow1D(sampler1DShadow, vec3 [, float])
        vec4 shadow2D(sampler2DShadow, vec3 [, float])
        vec4 shadow1DProj(sampler1DShadow, vec4 [, float])
        vec4 shadow2DProj(sampler2DShadow, vec4 [, float])
        float shadow2DEXT(sampler2DShadow, vec3)  float shadow2DProjEXT(sampler2DShadow, vec4)
        vec4 texture2D(samplerExternalOES, vec2 [, float])
        vec4 texture2DProj(samplerExternalOES, vec3 [, float])
        vec4 texture2DProj(samplerExternalOES, vec4 [, float])
        vec4 texture1DArray(sampler1DArray, vec2 [, float])
        vec4 texture2DArray(sampler2DArray, vec3 [, float])
        vec4 shadow1DArray(sampler1DArrayShadow, vec3 [, float])
        vec4 shadow2DArray(sampler2DArrayShadow, vec4)
    """),
    ("texture", "l", """
        vec4 texture1DLod(sampler1D, float, float)  vec4 texture1DProjLod(sampler1D, vec2, float)
        vec4 texture1DProjLod(sampler1D, vec4, float)  vec4 texture2DLod(sampler2D, vec2, float)
        vec4 texture2DProjLod(sampler2D, vec3, float)
        vec4 texture2DProjLod(sampler2D, vec4, float)  vec4 texture3DLod(sampler3D, vec3, float)
        vec4 texture3DProjLod(sampler3D, vec4, float)
        vec4 textureCubeLod(samplerCube, vec3, float)
        vec4 shadow1DLod(sampler1DShadow, vec3, float)
        vec4 shadow2DLod(sampler2DShadow, vec3, float)
        vec4 shadow1DProjLod(sampler1DShadow, vec4, float)
        vec4 shadow2DProjLod(sampler2DShadow, vec4, float)
        vec4 texture2DRect(sampler2DRect, vec2)  vec4 texture2DRectProj(sampler2DRect, vec3)
        vec4 texture2DRectProj(sampler2DRect, vec4)
        vec4 shadow2DRect(sampler2DRectShadow, vec3)
        vec4 shadow2DRectProj(sampler2DRectShadow, vec4)
        vec4 texture1DArrayLod(sampler1DArray, vec2, float)
        vec4 texture2DArrayLod(sampler2DArray, vec3, float)
        vec4 shadow1DArrayLod(sampler1DArrayShadow, vec3, float)
        vec4 texture2DLodEXT(sampler2D, vec2, float)
        vec4 texture2DProjLodEXT(sampler2D, vec3, float)
        vec4 texture2DProjLodEXT(sampler2D, vec4, float)
        vec4 textureCubeLodEXT(samplerCube, vec3, float)
        vec4 texture2DGradEXT(sampler2D, vec2, vec2, vec2)
        vec4 texture2DProjGradEXT(sampler2D, vec3, vec2, vec2)
        vec4 texture2DProjGradEXT(sampler2D, vec4, vec2, vec2)
        vec4 textureCubeGradEXT(samplerCube, vec3, vec3, vec3)
        vec4 texture1DGradARB(sampler1D, float, float, float)
        vec4 texture2DGradARB(sampler2D, vec2, vec2, vec2)
        vec4 texture2DProjGradARB(sampler2D, vec3, vec2, vec2)
        vec4 texture2DProjGradARB(sampler2D, vec4, vec2, vec2)
        vec4 texture3DGradARB(sampler3D, vec3, vec3, vec3)
        vec4 textureCubeGradARB(samplerCube, vec3, vec3, vec3)
        vec4 shadow2DGradARB(sampler2DShadow, vec3, vec2, vec2)
    """),
]

# Images: (shape, coordinate type, imageSize result).
_IMAGE_SHAPES = [("1D", "int", "int"), ("2D", "ivec2", "ivec2"), ("3D", "ivec3", "ivec3"),
                 ("2DRect", "ivec2", "ivec2"), ("Cube", "ivec3", "ivec2"),
                 ("Buffer", "int", "int"), ("1DArray", "ivec2", "ivec2"),
                 ("2DArray", "ivec3", "ivec3"), ("CubeArray", "ivec3", "ivec3"),
                 ("2DMS", "ivec2", "ivec2"), ("2DMSArray", "ivec3", "ivec3")]
_IMAGE_ATOMICS = ("Add", "Min", "Max", "And", "Or", "Xor", "Exchange")


def _image_specs() -> list[tuple[str, str, str]]:
    pure, writes = [], []
    for shape, coord, size in _IMAGE_SHAPES:
        img = f"gimage{shape}"
        c = f"{coord}, int" if shape.endswith("MS") or shape.endswith("MSArray") else coord
        pure.append(f"{size} imageSize({img})")
        if "MS" in shape:
            pure.append(f"int imageSamples({img})")
        pure.append(f"gvec4 imageLoad({img}, {c})")
        writes.append(f"void imageStore({img}, {c}, gvec4)")
        for op in _IMAGE_ATOMICS:
            for scalar in ("int", "uint"):
                prefix = "i" if scalar == "int" else "u"
                writes.append(f"{scalar} imageAtomic{op}({prefix}image{shape}, {c}, {scalar})")
            if op == "Exchange":
                writes.append(f"float imageAtomicExchange(image{shape}, {c}, float)")
        for scalar in ("int", "uint"):
            prefix = "i" if scalar == "int" else "u"
            writes.append(
                f"{scalar} imageAtomicCompSwap({prefix}image{shape}, {c}, {scalar}, {scalar})")
    return [("image", "", "\n".join(pure)), ("image", "s", "\n".join(writes))]


# Vulkan GLSL (GL_KHR_vulkan_glsl) subpass inputs.
_VULKAN_SPECS = [("texture", "", """
        gvec4 subpassLoad(gsubpassInput)  gvec4 subpassLoad(gsubpassInputMS, int)
"""), ("common", "", """
        genI64Type doubleBitsToInt64(genDType)  genU64Type doubleBitsToUint64(genDType)
        genDType int64BitsToDouble(genI64Type)  genDType uint64BitsToDouble(genU64Type)
"""), ("packing", "", """
        int64_t packInt2x32(ivec2)  ivec2 unpackInt2x32(int64_t)
        uint64_t packUint2x32(uvec2)  uvec2 unpackUint2x32(uint64_t)
        uint packFloat2x16(f16vec2)  f16vec2 unpackFloat2x16(uint)
"""), ("common", "", """
        genType nonuniformEXT(genType)  genIType nonuniformEXT(genIType)
        genUType nonuniformEXT(genUType)  genBType nonuniformEXT(genBType)
        genDType nonuniformEXT(genDType)
""")]

_SPLIT_RE = re.compile(r"\S+\s+\w+\s*\([^()]*\)")

# GL_ARB_sparse_texture2 / GL_ARB_sparse_texture_clamp, derived from the core lookups: the sparse
# form returns a residency code and writes the texel to an ``out`` argument placed before the
# optional bias or component; the clamp forms take a ``float lodClamp`` at the same place.
_SPARSE_BASES = ("texture", "textureLod", "textureOffset", "textureLodOffset", "textureGrad",
                 "textureGradOffset", "texelFetch", "texelFetchOffset", "textureGather",
                 "textureGatherOffset", "textureGatherOffsets")
_CLAMP_BASES = ("texture", "textureOffset", "textureGrad", "textureGradOffset")


def _with_extra(params: str, extra: str) -> str:
    """``params`` with ``extra`` inserted before the optional ``[, ...]`` tail (or appended)."""
    m = re.search(r"\[\s*,", params)
    return f"{params[:m.start()].rstrip()}, {extra} {params[m.start():]}" if m else \
        f"{params}, {extra}"


def _sparse_specs() -> list[tuple[str, str, str]]:
    out = [("texture", "", "bool sparseTexelsResidentARB(int)")]
    for category, flags, text in _SPECS:
        if category != "texture" or "l" in flags:
            continue
        lines = []
        for spec in _SPLIT_RE.findall(text):
            ret, name, params = _SPEC_RE.match(spec).groups()
            if "samplerExternalOES" in params or "Buffer" in params or "1D" in params:
                continue
            cap = name[0].upper() + name[1:]
            if name in _SPARSE_BASES:
                lines.append(f"int sparse{cap}ARB({_with_extra(params, 'out ' + ret)})")
            if name in _CLAMP_BASES:
                lines.append(f"{ret} {name}ClampARB({_with_extra(params, 'float')})")
                lines.append(f"int sparse{cap}ClampARB({_with_extra(params, 'float, out ' + ret)})")
        out.append((category, flags, "\n".join(lines)))
    return out



# Explicit arithmetic types: the float built-ins also take float16_t values, and the integer
# arithmetic and comparisons 64-bit integers (GL_AMD_gpu_shader_half_float,
# GL_ARB_gpu_shader_int64, GL_EXT_shader_explicit_arithmetic_types). Derived from the float and
# int overloads; interpolateAtOffset keeps its vec2 offset.
_FLOAT16_CATEGORIES = frozenset({"trig", "exponential", "common", "geometric", "matrix",
                                 "relational", "derivative", "interpolation"})
_INT64_NAMES = frozenset({"abs", "sign", "min", "max", "clamp", "mix", "lessThan",
                          "lessThanEqual", "greaterThan", "greaterThanEqual", "equal",
                          "notEqual", "nonuniformEXT"})
_FLOAT16_BASES = {"float": "float16_t"}
_INT64_BASES = {"int": "int64_t", "uint": "uint64_t"}


def _rebase(t: Type, bases: dict[str, str]) -> Type:
    if t.base not in bases:
        return t
    return Type(bases[t.base], t.size, t.cols, t.rows, t.dims)


def _retyped(f: BuiltinFunction, bases: dict[str, str]) -> Optional[BuiltinFunction]:
    """``f`` with the base types in ``bases`` replaced, or None when nothing changes."""
    keep = (1,) if f.name == "interpolateAtOffset" else ()
    params = tuple(p if i in keep else _rebase(p, bases) for i, p in enumerate(f.params))
    if params == f.params or any(p.is_opaque for p in params):
        return None
    return BuiltinFunction(f.name, _rebase(f.return_type, bases), params, f.qualifiers,
                           f.category, f.derivative, f.side_effects, f.legacy)


def _retyped_all(overloads: list[BuiltinFunction], bases: dict[str, str]
                 ) -> list[BuiltinFunction]:
    out = [_retyped(f, bases) for f in overloads]
    return [f for f in out if f is not None]


def _add_explicit_type_overloads(table: dict[str, list[BuiltinFunction]],
                                 seen: set[tuple[str, tuple[Type, ...]]]) -> None:
    for name, overloads in list(table.items()):
        derived: list[BuiltinFunction] = []
        if name in _INT64_NAMES:
            derived += _retyped_all(overloads, _INT64_BASES)
        derived += _retyped_all([f for f in overloads if f.category in _FLOAT16_CATEGORIES],
                                _FLOAT16_BASES)
        for f in derived:
            if (f.name, f.params) not in seen:
                seen.add((f.name, f.params))
                overloads.append(f)


def _build() -> dict[str, list[BuiltinFunction]]:
    table: dict[str, list[BuiltinFunction]] = {}
    seen: set[tuple[str, tuple[Type, ...]]] = set()
    for category, flags, text in _SPECS + _image_specs() + _VULKAN_SPECS + _sparse_specs():
        for spec in _SPLIT_RE.findall(text):
            for f in _expand(spec, category, "d" in flags, "s" in flags, "l" in flags):
                # genType specs overlap at size 1 (mod(genType, float) and mod(genType, genType))
                if (f.name, f.params) not in seen:
                    seen.add((f.name, f.params))
                    table.setdefault(f.name, []).append(f)
    # outerProduct and transpose relate two independent sizes: generated here.
    for base, prefix in (("float", ""), ("double", "d")):
        for c, r in _MAT_SHAPES:
            mat = Type(base, 1, c, r)
            table.setdefault("outerProduct", []).append(BuiltinFunction(
                "outerProduct", mat, (Type(base, r), Type(base, c)), ("in", "in"), "matrix"))
            table.setdefault("transpose", []).append(BuiltinFunction(
                "transpose", Type(base, 1, r, c), (mat,), ("in",), "matrix"))
    _add_explicit_type_overloads(table, {(f.name, f.params) for fs in table.values() for f in fs})
    return table


BUILTIN_FUNCTIONS: dict[str, list[BuiltinFunction]] = _build()


def lookup(name: str) -> list[BuiltinFunction]:
    """Every overload of built-in function ``name`` (empty when there is none).

    >>> len(lookup("sin")), len(lookup("no_such_function"))  # float and float16_t, sizes 1-4
    (8, 0)
    """
    return BUILTIN_FUNCTIONS.get(name, [])


def is_builtin_function(name: str) -> bool:
    """Whether ``name`` names a built-in function."""
    return name in BUILTIN_FUNCTIONS


def all_functions() -> Iterable[BuiltinFunction]:
    """Every built-in overload, grouped by name."""
    for overloads in BUILTIN_FUNCTIONS.values():
        yield from overloads


DERIVATIVE_FUNCTIONS = frozenset(
    f.name for f in all_functions() if f.derivative)
"""Names of built-ins that take screen-space derivatives in at least one overload."""

SIDE_EFFECT_FUNCTIONS = frozenset(f.name for f in all_functions() if f.side_effects)
"""Names of built-ins that write memory or an ``out`` argument in at least one overload."""


# ----------------------------------------------------------------------------- variables

# Minimum maxima guaranteed by GL 4.x; enough to size gl_FragData and friends.
_CONSTANTS = {
    "gl_MaxDrawBuffers": 8, "gl_MaxTextureUnits": 2, "gl_MaxTextureCoords": 8,
    "gl_MaxTextureImageUnits": 16, "gl_MaxCombinedTextureImageUnits": 80,
    "gl_MaxVertexTextureImageUnits": 16, "gl_MaxVertexAttribs": 16,
    "gl_MaxVertexUniformComponents": 1024, "gl_MaxFragmentUniformComponents": 1024,
    "gl_MaxVaryingFloats": 60, "gl_MaxVaryingComponents": 60, "gl_MaxVaryingVectors": 15,
    "gl_MaxVertexUniformVectors": 256, "gl_MaxFragmentUniformVectors": 224,
    "gl_MaxVertexOutputVectors": 16, "gl_MaxFragmentInputVectors": 15,
    "gl_MaxFragmentInputComponents": 128, "gl_MaxVertexOutputComponents": 64,
    "gl_MaxClipDistances": 8, "gl_MaxClipPlanes": 8, "gl_MaxCullDistances": 8,
    "gl_MaxCombinedClipAndCullDistances": 8, "gl_MaxLights": 8,
    "gl_MinProgramTexelOffset": -8, "gl_MaxProgramTexelOffset": 7,
    "gl_MaxImageUnits": 8, "gl_MaxFragmentImageUniforms": 8,
    "gl_MaxCombinedImageUniforms": 8, "gl_MaxCombinedImageUnitsAndFragmentOutputs": 8,
    "gl_MaxImageSamples": 0, "gl_MaxFragmentAtomicCounters": 8,
    "gl_MaxCombinedAtomicCounters": 8, "gl_MaxAtomicCounterBindings": 1,
    "gl_MaxFragmentAtomicCounterBuffers": 1, "gl_MaxCombinedAtomicCounterBuffers": 1,
    "gl_MaxAtomicCounterBufferSize": 32, "gl_MaxViewports": 16, "gl_MaxSamples": 4,
    "gl_MaxInputAttachments": 1,
}

DEPTH_RANGE_TYPE = Type.struct("gl_DepthRangeParameters",
                               (("near", Type("float")), ("far", Type("float")),
                                ("diff", Type("float"))))


def _variables() -> dict[str, BuiltinVariable]:
    f, v2, v4, i, b = Type("float"), Type("float", 2), Type("float", 4), Type("int"), Type("bool")
    mat4, mat3 = Type("float", 1, 4, 4), Type("float", 1, 3, 3)
    draw = _CONSTANTS["gl_MaxDrawBuffers"]
    table = [
        BuiltinVariable("gl_FragCoord", v4, "in", True),
        BuiltinVariable("gl_FrontFacing", b, "in", True),
        BuiltinVariable("gl_PointCoord", v2, "in", True),
        BuiltinVariable("gl_SampleID", i, "in", True),
        BuiltinVariable("gl_SamplePosition", v2, "in", True),
        BuiltinVariable("gl_SampleMaskIn", i.array_of(1), "in", True),
        BuiltinVariable("gl_PrimitiveID", i, "in", True),
        BuiltinVariable("gl_Layer", i, "in", True),
        BuiltinVariable("gl_ViewportIndex", i, "in", True),
        # GL_EXT_device_group / GL_EXT_multiview (and the GL_KHX_ experimental spellings).
        BuiltinVariable("gl_DeviceIndex", i, "in", True),
        BuiltinVariable("gl_ViewIndex", i, "in", True),
        BuiltinVariable("gl_DeviceIndexKHR", i, "in", True),
        BuiltinVariable("gl_ViewIndexKHR", i, "in", True),
        BuiltinVariable("gl_ClipDistance", f.array_of(_CONSTANTS["gl_MaxClipDistances"]),
                        "in", True),
        BuiltinVariable("gl_CullDistance", f.array_of(_CONSTANTS["gl_MaxCullDistances"]),
                        "in", True),
        BuiltinVariable("gl_HelperInvocation", b, "in", True),
        BuiltinVariable("gl_NumSamples", i, "uniform", True),
        BuiltinVariable("gl_FragColor", v4, "out", False, legacy=True),
        BuiltinVariable("gl_FragData", v4.array_of(draw), "out", False, legacy=True),
        BuiltinVariable("gl_FragDepth", f, "out", False),
        BuiltinVariable("gl_FragDepthEXT", f, "out", False, legacy=True),
        BuiltinVariable("gl_SampleMask", i.array_of(1), "out", False),
        BuiltinVariable("gl_DepthRange", DEPTH_RANGE_TYPE, "uniform", True),
        # Compatibility-profile inputs and state.
        BuiltinVariable("gl_Color", v4, "in", True, legacy=True),
        BuiltinVariable("gl_SecondaryColor", v4, "in", True, legacy=True),
        BuiltinVariable("gl_TexCoord", v4.array_of(_CONSTANTS["gl_MaxTextureCoords"]), "in",
                        True, legacy=True),
        BuiltinVariable("gl_FogFragCoord", f, "in", True, legacy=True),
        BuiltinVariable("gl_ModelViewMatrix", mat4, "uniform", True, legacy=True),
        BuiltinVariable("gl_ProjectionMatrix", mat4, "uniform", True, legacy=True),
        BuiltinVariable("gl_ModelViewProjectionMatrix", mat4, "uniform", True, legacy=True),
        BuiltinVariable("gl_ModelViewMatrixInverse", mat4, "uniform", True, legacy=True),
        BuiltinVariable("gl_ProjectionMatrixInverse", mat4, "uniform", True, legacy=True),
        BuiltinVariable("gl_NormalMatrix", mat3, "uniform", True, legacy=True),
        BuiltinVariable("gl_TextureMatrix",
                        mat4.array_of(_CONSTANTS["gl_MaxTextureCoords"]), "uniform", True,
                        legacy=True),
        BuiltinVariable("gl_NormalScale", f, "uniform", True, legacy=True),
    ]
    table += [BuiltinVariable(name, i, "const", True, value) for name, value in _CONSTANTS.items()]
    return {var.name: var for var in table}


BUILTIN_VARIABLES: dict[str, BuiltinVariable] = _variables()

# Names that only a non-fragment stage may use: their presence marks another shader stage.
NON_FRAGMENT_VARIABLES = frozenset([
    "gl_Position", "gl_PointSize", "gl_VertexID", "gl_InstanceID", "gl_VertexIndex",
    "gl_InstanceIndex", "gl_Vertex", "gl_Normal", "gl_MultiTexCoord0", "gl_ClipVertex",
    "gl_FrontColor", "gl_BackColor", "gl_in", "gl_out", "gl_InvocationID",
    "gl_TessCoord", "gl_TessLevelOuter", "gl_TessLevelInner", "gl_PatchVerticesIn",
    "gl_GlobalInvocationID", "gl_LocalInvocationID", "gl_WorkGroupID", "gl_NumWorkGroups",
    "gl_LocalInvocationIndex", "gl_WorkGroupSize", "gl_BaseVertex", "gl_BaseInstance",
    "gl_DrawID",
])
