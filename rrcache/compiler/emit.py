"""Pass: print an assembled pass as shader sources.

The fragment shader is the pass's unit printed as ``#version 330 core`` (or the shader's own
core version when higher) with the runtime's GLSL inserted verbatim after the ``#version`` and
``#extension`` lines; its line map (printed line → original place, None for generated lines)
maps driver errors back to the user's file.

The vertex shader is the user's own when one was given (:mod:`rrcache.compiler.user_vertex`:
``rr_prevClip`` and ``invariant gl_Position`` added, the user's varyings passed through every
pass), else it comes from the harness generator (:func:`rrcache.compiler.vertex.
vertex_for`), asked for exactly the varyings the fragment shader declares (plus
``rr_prevClip`` when the pass reads the previous frame's cache), with ``gl_Position`` declared
``invariant``: every pass must produce bit-identical depths, or the depth tests between passes
(``<`` at hits, ``<=`` in the final pass) would fail at random pixels.

>>> vs = vertex_shader({"v_normal": "vec3"}, prev_clip=True)
>>> "invariant gl_Position;" in vs and "out vec4 rr_prevClip;" in vs
True
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Optional

from rrcache.errors import SourceLoc
from rrcache.glsl import ast as A
from rrcache.glsl.printer import print_with_map
from rrcache.glsl.types import OPAQUE_NAMES
from rrcache.compiler.vertex import vertex_for
from rrcache.runtime import glsl as G

_UNIFORM_LINE = re.compile(r"^\s*uniform\s+\w+\s+(\w+)\s*;", re.MULTILINE)


_BUILTIN_REDECLARATION = re.compile(r"^\s*(layout\s*\([^)]*\)\s*)?(in|out)\s+\w+\s+gl_Frag(Coord|Depth)\s*;")


_CURRENT_READ = re.compile(r"texelFetch\((rr_curPayload\w*), ivec2\(gl_FragCoord\.xy\), 0\)")


def _window_convention(runtime_glsl: str, redeclarations: str) -> str:
    """The runtime's reads of the current frame's cache at this pixel, with a user's
    ``layout(origin_upper_left, pixel_center_integer) in vec4 gl_FragCoord;`` undone (the
    snippets assume GL's default: origin at the bottom left, centres at +0.5). Only those reads
    need the true texel; the other uses hash the coordinate the same way in every pass.

    >>> _window_convention("texelFetch(rr_curPayload_1, ivec2(gl_FragCoord.xy), 0)",
    ...                    "layout(origin_upper_left) in vec4 gl_FragCoord;")
    'texelFetch(rr_curPayload_1, ivec2(gl_FragCoord.x, float(textureSize(rr_curPayload_1, 0).y) - gl_FragCoord.y), 0)'
    """
    upper = "origin_upper_left" in redeclarations
    shift = " + 0.5" if "pixel_center_integer" in redeclarations else ""
    if not upper and not shift:
        return runtime_glsl

    def read(m: re.Match) -> str:
        name = m.group(1)
        y = f"gl_FragCoord.y{shift}"
        if upper:
            y = f"float(textureSize({name}, 0).y) - " + (f"({y})" if shift else y)
        return f"texelFetch({name}, ivec2(gl_FragCoord.x{shift}, {y}), 0)"

    return _CURRENT_READ.sub(read, runtime_glsl)


def fragment_shader(unit: A.TranslationUnit, runtime_glsl: str) -> tuple[str, list[Optional[SourceLoc]]]:
    """The fragment source and its line map."""
    text, line_map = print_with_map(unit)
    lines = text.split("\n")
    line_map = list(line_map) + [None] * (len(lines) - len(line_map))
    head = 0
    while head < len(lines) and lines[head].startswith("#"):
        head += 1
    # A redeclared built-in (``layout(origin_upper_left) in vec4 gl_FragCoord;``) must come
    # before the runtime's first use of it (GLSL 4.60 §7.1.2): move it above the snippets.
    moved = [i for i in range(head, len(lines)) if _BUILTIN_REDECLARATION.match(lines[i])]
    for i in moved:
        lines.insert(head, lines.pop(i))
        line_map.insert(head, line_map.pop(i))
        head += 1
    runtime_glsl = _window_convention(runtime_glsl, " ".join(lines[head - len(moved):head]))
    extra = runtime_glsl.rstrip("\n").split("\n") if runtime_glsl else []
    lines[head:head] = extra
    line_map = list(line_map[:head]) + [None] * len(extra) + list(line_map[head:])
    return "\n".join(lines), line_map


def _qualifier_words(decl: A.VariableDecl) -> set[str]:
    return {q for q in decl.type.qualifiers if isinstance(q, str)}


def interface(unit: A.TranslationUnit) -> dict[str, dict[str, str]]:
    """The shader's own globals by storage: ``{"in": {name: type}, "uniform": {...},
    "sampler": {...}}`` (uniform blocks are listed under ``uniform`` by block name)."""
    found: dict[str, dict[str, str]] = {"in": {}, "uniform": {}, "sampler": {}}
    for d in unit.decls:
        if isinstance(d, A.VariableDecl) and d.declarators:
            quals = _qualifier_words(d)
            type_name = d.type.spec.name or (d.type.spec.struct.name if d.type.spec.struct else "struct")
            for x in d.declarators:
                if ("in" in quals or "varying" in quals) and not x.name.startswith("gl_"):
                    # not ``layout(origin_upper_left) in vec4 gl_FragCoord;`` (a built-in)
                    found["in"][x.name] = type_name
                elif "uniform" in quals:
                    kind = "sampler" if type_name in OPAQUE_NAMES else "uniform"
                    found[kind][x.name] = type_name
        elif isinstance(d, A.InterfaceBlock):
            quals = {q for q in d.qualifiers if isinstance(q, str)}
            if "uniform" in quals:
                found["uniform"][d.block_name] = "block"
    return found


def input_locations(unit: A.TranslationUnit) -> dict[str, Optional[SourceLoc]]:
    """Where each ``in`` variable is declared (for the harness' error messages)."""
    out: dict[str, Optional[SourceLoc]] = {}
    for d in unit.decls:
        if isinstance(d, A.VariableDecl) and "in" in _qualifier_words(d):
            for x in d.declarators:
                out[x.name] = x.loc or d.loc
    return out


def vertex_shader(inputs: dict[str, str], prev_clip: bool,
                  locs: Optional[dict[str, Optional[SourceLoc]]] = None, user=None) -> str:
    """The vertex shader writing ``inputs`` (and ``rr_prevClip``), with an invariant
    ``gl_Position``: generated, or the user's own (``user``, a
    :class:`rrcache.compiler.user_vertex.UserVertex`) with the cache's additions."""
    return vertex_for(inputs, locs, user, prev_clip=prev_clip, invariant=True)


def vertex_uniforms(vertex_text: str) -> list[str]:
    """The uniforms a generated vertex shader declares (the application sets them per object)."""
    return _UNIFORM_LINE.findall(vertex_text)


def runtime_uniforms(runtime_glsl: str) -> list[str]:
    """The ``rr_`` uniforms and samplers the runtime sets, as declared in its snippets."""
    return _UNIFORM_LINE.findall(runtime_glsl)


@dataclass
class EmittedPass:
    """One pass as text: its vertex and fragment shaders (``line_map`` maps the fragment's lines
    to the original shader), the uniforms and samplers the application binds (the vertex
    shader's per-object ones included) and the ``rr_`` uniforms the runtime sets."""

    vertex: str
    fragment: str
    line_map: list
    uniforms: list
    samplers: list
    runtime: list


def emit_pass(unit: A.TranslationUnit, runtime_glsl: str, prev_clip: bool, user=None) -> EmittedPass:
    """Print a built pass (its ``unit`` and the runtime snippets it uses) with its vertex shader:
    generated, or the user's (``user``) with the cache's additions."""
    iface = interface(unit)
    vertex = vertex_shader(iface["in"], prev_clip, input_locations(unit), user)
    fragment, line_map = fragment_shader(unit, runtime_glsl)
    vertex_names = user.uniform_names(prev_clip) if user is not None else vertex_uniforms(vertex)
    return EmittedPass(vertex, fragment, line_map, sorted(set(iface["uniform"]) | set(vertex_names)),
                       list(iface["sampler"]), runtime_uniforms(runtime_glsl))
