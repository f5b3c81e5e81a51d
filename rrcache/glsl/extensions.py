"""The extensions the front-end supports, whose macros the preprocessor predefines.

GLSL (4.60 §3.3, ES 3.00 §3.4) has every extension the implementation supports define a macro of
its name as 1, whether or not the shader enables it, so that shaders can write
``#ifdef GL_ARB_texture_query_lod``. The front-end defines the macro of each extension below
whose built-in functions, variables, types or qualifiers it knows (``builtins.py``,
``types.py``, ``semantic.py``, ``lexer.py``); the variants are compiled as ``#version 330 core``
on a driver with OpenGL 4.5 (Mesa llvmpipe supports each desktop one), and ``legacy.to_core``
turns the ES 1.00 ones into core GLSL.

Desktop shaders get :data:`DESKTOP`, GLSL ES shaders :data:`ES` (the ES 1.00 extensions the
ES sketch tools rely on, and external images).

>>> "GL_ARB_texture_query_lod" in DESKTOP, "GL_OES_standard_derivatives" in ES
(True, True)
"""
from __future__ import annotations

#: extension -> what the front-end knows of it
DESKTOP: dict[str, str] = {
    "GL_ARB_texture_query_lod": "textureQueryLOD (the extension's name), textureQueryLod",
    "GL_ARB_texture_query_levels": "textureQueryLevels",
    "GL_ARB_texture_gather": "textureGather",
    "GL_ARB_texture_rectangle": "sampler2DRect and its lookups",
    "GL_ARB_shader_texture_lod": "texture2DLod, texture2DGradARB... in fragment shaders",
    "GL_EXT_texture_array": "sampler2DArray and its lookups",
    "GL_ARB_derivative_control": "dFdxFine, dFdxCoarse...",
    "GL_ARB_gpu_shader5": "fma, bitfield functions, textureGather offsets",
    "GL_ARB_shader_bit_encoding": "floatBitsToInt, intBitsToFloat...",
    "GL_ARB_shading_language_packing": "packHalf2x16, packUnorm4x8...",
    "GL_ARB_shader_image_load_store": "image types, imageLoad, imageStore",
    "GL_ARB_bindless_texture": "samplers made from handles",
    "GL_ARB_sparse_texture2": "sparseTextureARB...",
    "GL_ARB_sparse_texture_clamp": "textureClampARB...",
    "GL_ARB_gpu_shader_int64": "int64_t, uint64_t",
    "GL_AMD_gpu_shader_half_float": "float16_t",
    "GL_EXT_shader_explicit_arithmetic_types": "int64_t, float16_t",
    "GL_ARB_explicit_attrib_location": "layout(location)",
    "GL_ARB_separate_shader_objects": "layout(location) on inputs",
    "GL_ARB_shading_language_420pack": "layout(binding), initialiser lists",
    "GL_ARB_explicit_uniform_location": "layout(location) on uniforms",
    "GL_ARB_fragment_coord_conventions": "layout(origin_upper_left) gl_FragCoord",
    "GL_ARB_conservative_depth": "layout(depth_any) gl_FragDepth",
}

#: the GLSL ES extensions the front-end knows (ES 1.00 sketches test the first ones)
ES: dict[str, str] = {
    "GL_OES_standard_derivatives": "dFdx, dFdy, fwidth in ES 1.00",
    "GL_EXT_shader_texture_lod": "texture2DLodEXT, texture2DGradEXT, textureCubeLodEXT...",
    "GL_EXT_frag_depth": "gl_FragDepthEXT",
    "GL_OES_texture_3D": "sampler3D, texture3D",
    "GL_OES_EGL_image_external": "samplerExternalOES",
}


def predefined(es: bool) -> tuple[str, ...]:
    """The extension macros a shader of this kind sees predefined (as 1)."""
    return tuple(ES if es else DESKTOP)
