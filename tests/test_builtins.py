"""The built-in function and variable tables, and the GLSL type helpers."""
import pytest

from rrcache.errors import SemanticError
from rrcache.glsl import builtins as B
from rrcache.glsl.types import (
    BOOL, FLOAT, INT, MAT3, UINT, VEC2, VEC3, VEC4, IVEC2, Type, swizzle, swizzle_indices,
)


def sigs(name):
    return {f.signature() for f in B.lookup(name)}


def find(name, *params):
    ps = tuple(Type.from_name(p) if isinstance(p, str) else p for p in params)
    matches = [f for f in B.lookup(name) if f.params == ps]
    assert len(matches) == 1, (name, params, [str(f) for f in B.lookup(name)])
    return matches[0]


# ----------------------------------------------------------------------------- types

def test_type_names_round_trip():
    for name in ["float", "vec3", "ivec4", "uvec2", "bvec3", "dvec4", "mat2x3", "dmat4x2",
                 "sampler2D", "usampler3D", "samplerCubeShadow", "image2D", "atomic_uint"]:
        assert Type.from_name(name).glsl_name() == name
    assert Type.from_name("mat3") == MAT3 and MAT3.glsl_name() == "mat3x3" and str(MAT3) == "mat3"
    with pytest.raises(KeyError):
        Type.from_name("vec5")


def test_type_predicates_and_shapes():
    assert FLOAT.is_scalar and not FLOAT.is_vector and FLOAT.is_float
    assert VEC3.is_vector and VEC3.components == 3 and VEC3.scalar_type() == FLOAT
    m = Type.from_name("mat2x3")
    assert m.is_matrix and m.cols == 2 and m.rows == 3 and m.components == 6
    assert m.column_type() == VEC3
    assert Type.from_name("uvec2").is_integer and BOOL.is_bool and not BOOL.is_numeric
    assert Type.from_name("sampler2D").is_opaque and not VEC4.is_opaque
    arr = FLOAT.array_of(4)
    assert arr.is_array and not arr.is_scalar and arr.element_type() == FLOAT
    assert arr.glsl_name() == "float[4]" and arr.components == 4
    assert VEC3.with_base("int") == Type.from_name("ivec3")
    s = Type.struct("Light", (("pos", VEC3), ("tex", Type.from_name("sampler2D"))))
    assert s.is_struct and s.field_type("pos") == VEC3 and s.field_type("x") is None
    assert s.contains_opaque() and s.glsl_name() == "Light"
    assert hash(VEC3) == hash(Type("float", 3))  # frozen, hashable


def test_swizzles():
    assert swizzle(VEC4, "xyz") == (VEC3, True)
    assert swizzle(VEC2, "yx") == (VEC2, True)
    assert swizzle(VEC3, "rrg") == (VEC3, False)
    assert swizzle(FLOAT, "xxxx") == (VEC4, False)
    assert swizzle(Type.from_name("ivec3"), "stp")[0] == Type.from_name("ivec3")
    assert swizzle_indices("bgr") == (2, 1, 0)
    for bad, msg in [("xr", "mixes"), ("xyzwx", "more than 4"), ("z", "out of range"),
                     ("q", "out of range"), ("k", "not a field")]:
        with pytest.raises(SemanticError, match=msg):
            swizzle(VEC2, bad)
    with pytest.raises(SemanticError):
        swizzle(MAT3, "x")


# ----------------------------------------------------------------------------- function families

def test_gentype_expansion_shares_one_size():
    assert sigs("sin") == {"sin(float)", "sin(vec2)", "sin(vec3)", "sin(vec4)",
                           # explicit half floats (GL_AMD_gpu_shader_half_float)
                           "sin(float16_t)", "sin(f16vec2)", "sin(f16vec3)", "sin(f16vec4)"}
    assert "mix(vec3, vec3, float)" in sigs("mix")
    assert "mix(vec3, vec3, bvec3)" in sigs("mix")
    assert "mix(vec3, vec2, float)" not in sigs("mix")
    assert find("clamp", "ivec2", "int", "int").return_type == IVEC2
    assert find("step", "float", "vec4").return_type == VEC4
    assert find("smoothstep", "float", "float", "vec3").return_type == VEC3
    assert find("length", "vec3").return_type == FLOAT
    assert find("dot", "dvec2", "dvec2").return_type == Type.from_name("double")


@pytest.mark.parametrize("name", [
    # angle and trigonometry
    "radians", "degrees", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh",
    "asinh", "acosh", "atanh",
    # exponential
    "pow", "exp", "log", "exp2", "log2", "sqrt", "inversesqrt",
    # common
    "abs", "sign", "floor", "trunc", "round", "roundEven", "ceil", "fract", "mod", "modf", "min",
    "max", "clamp", "mix", "step", "smoothstep", "isnan", "isinf", "floatBitsToInt",
    "floatBitsToUint", "intBitsToFloat", "uintBitsToFloat", "fma", "frexp", "ldexp",
    # packing
    "packUnorm2x16", "packSnorm2x16", "packUnorm4x8", "packSnorm4x8", "unpackUnorm2x16",
    "unpackSnorm2x16", "unpackUnorm4x8", "unpackSnorm4x8", "packHalf2x16", "unpackHalf2x16",
    "packDouble2x32", "unpackDouble2x32",
    # geometric
    "length", "distance", "dot", "cross", "normalize", "faceforward", "reflect", "refract",
    # matrix
    "matrixCompMult", "outerProduct", "transpose", "determinant", "inverse",
    # vector relational
    "lessThan", "lessThanEqual", "greaterThan", "greaterThanEqual", "equal", "notEqual", "any",
    "all", "not",
    # integer
    "uaddCarry", "usubBorrow", "umulExtended", "imulExtended", "bitfieldExtract",
    "bitfieldInsert", "bitfieldReverse", "bitCount", "findLSB", "findMSB",
    # textures
    "texture", "textureProj", "textureLod", "textureOffset", "texelFetch", "texelFetchOffset",
    "textureProjOffset", "textureLodOffset", "textureProjLod", "textureProjLodOffset",
    "textureGrad", "textureGradOffset", "textureProjGrad", "textureProjGradOffset",
    "textureGather", "textureGatherOffset", "textureGatherOffsets", "textureSize",
    "textureQueryLod", "textureQueryLevels", "textureSamples",
    "texture1D", "texture2D", "texture2DProj", "texture2DLod", "texture2DProjLod", "texture3D",
    "textureCube", "textureCubeLod", "shadow2D", "shadow2DProj", "texture2DLodEXT",
    "texture2DProjLodEXT", "textureCubeLodEXT", "texture2DGradEXT", "texture2DRect",
    # derivatives, interpolation
    "dFdx", "dFdy", "fwidth", "dFdxFine", "dFdyFine", "fwidthFine", "dFdxCoarse", "dFdyCoarse",
    "fwidthCoarse", "interpolateAtCentroid", "interpolateAtSample", "interpolateAtOffset",
    # images, atomics, barriers
    "imageSize", "imageLoad", "imageStore", "imageAtomicAdd", "imageAtomicCompSwap",
    "imageAtomicExchange", "atomicCounterIncrement", "atomicCounterDecrement", "atomicCounter",
    "atomicAdd", "atomicCompSwap", "memoryBarrier", "memoryBarrierImage",
])
def test_every_family_is_present(name):
    assert B.is_builtin_function(name)
    assert B.lookup(name)


def test_matrix_functions():
    assert find("outerProduct", "vec3", "vec2").return_type == Type.from_name("mat2x3")
    assert find("transpose", "mat2x4").return_type == Type.from_name("mat4x2")
    assert find("determinant", "mat3").return_type == FLOAT
    assert find("inverse", "dmat4").return_type == Type.from_name("dmat4")
    assert "inverse(mat2x3)" not in sigs("inverse")
    assert find("matrixCompMult", "mat3x2", "mat3x2").return_type == Type.from_name("mat3x2")


def test_relational_functions_use_vectors_only():
    assert find("lessThan", "ivec3", "ivec3").return_type == Type.from_name("bvec3")
    assert "lessThan(float, float)" not in sigs("lessThan")
    assert find("any", "bvec2").return_type == BOOL
    assert "equal(bvec4, bvec4)" in sigs("equal")


def test_out_parameters_and_side_effects():
    modf = find("modf", "vec3", "vec3")
    assert modf.out_params == (1,) and modf.qualifiers == ("in", "out") and modf.side_effects
    frexp = find("frexp", "vec2", "ivec2")
    assert frexp.out_params == (1,)
    umul = find("umulExtended", "uvec2", "uvec2", "uvec2", "uvec2")
    assert umul.return_type.is_void and umul.out_params == (2, 3)
    atomic = find("atomicAdd", UINT, UINT)
    assert atomic.qualifiers[0] == "inout" and atomic.side_effects
    assert find("imageStore", "image2D", "ivec2", "vec4").side_effects
    assert find("memoryBarrier").side_effects
    assert not find("sin", "float").side_effects
    assert not find("imageLoad", "image2D", "ivec2").side_effects
    assert {"atomicAdd", "imageStore", "modf", "memoryBarrierImage"} <= B.SIDE_EFFECT_FUNCTIONS
    assert "texture" not in B.SIDE_EFFECT_FUNCTIONS


def test_derivative_flags():
    for name in ["dFdx", "dFdy", "fwidth", "dFdxFine", "fwidthCoarse"]:
        assert all(f.derivative for f in B.lookup(name))
    # implicit-LOD lookups take derivatives, explicit LOD/gradient/fetch ones do not
    assert find("texture", "sampler2D", "vec2").derivative
    assert find("texture", "sampler2D", "vec2", "float").derivative  # bias
    assert find("texture2D", "sampler2D", "vec2").derivative
    assert find("textureProj", "sampler2D", "vec4").derivative
    assert find("textureCube", "samplerCube", "vec3").derivative
    assert find("textureOffset", "sampler2D", "vec2", "ivec2").derivative
    assert find("shadow2D", "sampler2DShadow", "vec3").derivative
    for f in ("textureLod", "textureGrad", "texelFetch", "texture2DLod", "textureCubeLod",
              "textureSize", "textureGather", "texture2DLodEXT"):
        assert not any(g.derivative for g in B.lookup(f)), f
    assert not find("texture", "sampler2DRect", "vec2").derivative
    assert {"dFdx", "texture", "texture2D", "textureQueryLod"} <= B.DERIVATIVE_FUNCTIONS
    assert "textureLod" not in B.DERIVATIVE_FUNCTIONS


def test_sampler_families():
    # every flavour: float, int and uint samplers return the matching vec4
    assert find("texture", "isampler2D", "vec2").return_type == Type.from_name("ivec4")
    assert find("texture", "usampler3D", "vec3").return_type == Type.from_name("uvec4")
    assert find("texture", "samplerCubeArray", "vec4").return_type == VEC4
    assert find("texture", "sampler2DShadow", "vec3").return_type == FLOAT
    assert find("texture", "samplerCubeArrayShadow", "vec4", "float").return_type == FLOAT
    assert find("texelFetch", "sampler2DMS", "ivec2", "int").return_type == VEC4
    assert find("texelFetch", "usamplerBuffer", "int").return_type == Type.from_name("uvec4")
    assert find("textureSize", "samplerCube", "int").return_type == IVEC2
    assert find("textureSize", "sampler2DArray", "int").return_type == Type.from_name("ivec3")
    assert find("textureSize", "samplerBuffer").return_type == INT
    assert find("textureQueryLod", "sampler2D", "vec2").return_type == VEC2
    assert find("textureGather", "sampler2D", "vec2", "int").return_type == VEC4
    offsets = find("textureGatherOffsets", "sampler2D", "vec2", IVEC2.array_of(4))
    assert offsets.return_type == VEC4
    assert find("textureGrad", "samplerCube", "vec3", "vec3", "vec3").return_type == VEC4
    assert find("shadow2D", "sampler2DShadow", "vec3").return_type == VEC4
    assert find("imageLoad", "uimage2DMS", "ivec2", "int").return_type == Type.from_name("uvec4")
    assert find("imageSize", "imageCube").return_type == IVEC2
    assert find("imageAtomicAdd", "iimage2D", "ivec2", "int").return_type == INT
    assert find("imageAtomicExchange", "image2D", "ivec2", "float").return_type == FLOAT
    # optional arguments expand to both forms, and only where the spec has them
    assert "textureOffset(sampler2D, vec2, ivec2, float)" in sigs("textureOffset")
    assert "texture(sampler2DRect, vec2, float)" not in sigs("texture")


def test_legacy_names_are_marked():
    assert all(f.legacy for f in B.lookup("texture2D"))
    assert not any(f.legacy for f in B.lookup("texture"))


def test_builtin_variables():
    v = B.BUILTIN_VARIABLES
    assert v["gl_FragCoord"].type == VEC4 and v["gl_FragCoord"].read_only
    assert v["gl_FrontFacing"].type == BOOL
    assert v["gl_FragColor"].kind == "out" and not v["gl_FragColor"].read_only
    assert v["gl_FragData"].type == VEC4.array_of(v["gl_MaxDrawBuffers"].value)
    assert not v["gl_FragDepth"].read_only and not v["gl_SampleMask"].read_only
    assert v["gl_SampleMaskIn"].read_only
    for name in ("gl_PointCoord", "gl_SampleID", "gl_SamplePosition", "gl_PrimitiveID",
                 "gl_Layer", "gl_ViewportIndex", "gl_ClipDistance", "gl_HelperInvocation"):
        assert v[name].read_only and v[name].kind == "in", name
    assert v["gl_MaxDrawBuffers"].kind == "const" and v["gl_MaxDrawBuffers"].value >= 1
    assert v["gl_DepthRange"].type.field_type("far") == FLOAT
    assert "gl_Position" not in v and "gl_Position" in B.NON_FRAGMENT_VARIABLES


def test_table_is_generated_compactly_and_consistently():
    total = sum(len(v) for v in B.BUILTIN_FUNCTIONS.values())
    assert total > 1500
    for f in B.all_functions():
        assert len(f.params) == len(f.qualifiers)
        assert all(q in ("in", "out", "inout") for q in f.qualifiers)
        if f.out_params:
            assert f.side_effects, str(f)
    # no duplicated overloads
    for name, overloads in B.BUILTIN_FUNCTIONS.items():
        keys = [f.params for f in overloads]
        assert len(keys) == len(set(keys)), name
