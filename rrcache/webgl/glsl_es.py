"""GLSL 3.30 core → GLSL ES 3.00, the language of WebGL2, for the sources the compiler emits.

The compiler's passes and the harness's vertex shaders use a small, regular subset of desktop
GLSL: ``#version 330 core``, ``in``/``out``, ``layout(location = N) out`` fragment outputs,
``texture``, ``texelFetch``, ``textureSize``, unsigned integers and bit operations (the refresh
hash), ``invariant gl_Position``. All of it is GLSL ES 3.00 too, so the translation is the
header: ``#version 300 es`` and the precision statements ES needs (highp everywhere, as desktop
GLSL computes: a cache must reproduce the original's values, and the inverse-depth test needs
32-bit floats), placed after the ``#version`` and ``#extension`` lines.

What ES 3.00 does not have is refused here with the line, rather than left to a browser's
compile log: ``noperspective`` interpolation, desktop-only built-ins the user's shader may call
(``textureQueryLod``, ``fma``...). The browser's compiler is the judge of the rest (an implicit
int → float conversion desktop GLSL accepts, for one): the page shows its log, naming the pass.

>>> src = "#version 330 core\\nin vec3 v_n;\\nout vec4 c;\\nvoid main() { c = vec4(v_n, 1.0); }"
>>> print(to_glsl_es(src, "fragment"))
#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp samplerCube;
precision highp sampler3D;
in vec3 v_n;
out vec4 c;
void main() { c = vec4(v_n, 1.0); }
>>> to_glsl_es("#version 330 core\\nnoperspective in vec2 uv;\\nvoid main() {}", "fragment", "hit.frag")
Traceback (most recent call last):
    ...
rrcache.errors.UnsupportedShaderError: hit.frag:2: GLSL ES 3.00 (WebGL2) has no 'noperspective' interpolation (hint: declare the input 'smooth' (the default) for the WebGL2 target)
"""
from __future__ import annotations

import re

from rrcache.errors import UnsupportedShaderError

#: the precision statements every translated shader starts with
PRECISION = ("precision highp float;", "precision highp int;", "precision highp sampler2D;",
             "precision highp samplerCube;", "precision highp sampler3D;")

#: words of desktop GLSL with no GLSL ES 3.00 counterpart -> what to do instead
_DESKTOP_ONLY = {
    "noperspective": ("GLSL ES 3.00 (WebGL2) has no 'noperspective' interpolation",
                      "declare the input 'smooth' (the default) for the WebGL2 target"),
    "textureQueryLod": ("GLSL ES 3.00 (WebGL2) has no textureQueryLod", "compute the level from derivatives"),
    "textureGather": ("GLSL ES 3.00 (WebGL2) has no textureGather", "use four texelFetch calls"),
    "fma": ("GLSL ES 3.00 (WebGL2) has no fma", "write a * b + c"),
    "gl_ClipDistance": ("GLSL ES 3.00 (WebGL2) has no gl_ClipDistance", "discard in the fragment shader"),
    "samplerBuffer": ("GLSL ES 3.00 (WebGL2) has no buffer textures", "use a 2D texture"),
    "sampler1D": ("GLSL ES 3.00 (WebGL2) has no 1D textures", "use a 2D texture of height 1"),
    "origin_upper_left": ("GLSL ES 3.00 (WebGL2) cannot move gl_FragCoord's origin", "use gl_FragCoord as GL defines it"),
    "pixel_center_integer": ("GLSL ES 3.00 (WebGL2) cannot move gl_FragCoord's pixel centres",
                             "use gl_FragCoord as GL defines it"),
}
_WORD = re.compile(r"\b(" + "|".join(_DESKTOP_ONLY) + r")\b")
_COMMENT = re.compile(r"//[^\n]*|/\*.*?\*/", re.S)


def to_glsl_es(source: str, stage: str, name: str = "<shader>") -> str:
    """``source`` (a ``#version 330 core`` or later desktop shader the compiler or harness
    printed) as GLSL ES 3.00; ``stage`` is ``vertex`` or ``fragment``; ``name`` (the file it
    will be) names the place of anything ES cannot express (:class:`UnsupportedShaderError`)."""
    if stage not in ("vertex", "fragment"):
        raise ValueError(f"stage must be 'vertex' or 'fragment', not {stage!r}")
    lines = source.split("\n")
    code = _COMMENT.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), source).split("\n")
    for number, line in enumerate(code, start=1):
        found = _WORD.search(line)
        if found:
            message, hint = _DESKTOP_ONLY[found.group(1)]
            raise UnsupportedShaderError(f"{name}:{number}: {message}", None, hint=hint)
    head = 0
    while head < len(lines) and not lines[head].strip():
        head += 1
    if head == len(lines) or not lines[head].lstrip().startswith("#version"):
        raise UnsupportedShaderError(f"{name}: no #version line: not a shader rrcache emitted", None,
                                     hint="give the sources of a compiled variant")
    out = ["#version 300 es"]
    rest = lines[head + 1:]
    extensions = 0
    while extensions < len(rest) and rest[extensions].lstrip().startswith("#extension"):
        extensions += 1
    out += rest[:extensions] + list(PRECISION) + rest[extensions:]
    return "\n".join(out)
