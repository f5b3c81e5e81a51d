"""Compiling and linking GL programs, with driver errors mapped back to the original source.

The fragment source the driver sees is printed from the AST (after the legacy-to-core rewrite), so
its line numbers are not the user's. :func:`build_program` takes the printer's line map
(``line_map[i]`` is the :class:`~rrcache.errors.SourceLoc` of printed line ``i + 1``) and turns the
driver's log (Mesa: ``0:12(5): error: ...``; NVIDIA: ``0(12) : error C1008: ...``) into a
:class:`~rrcache.errors.GLError` that names the original ``file:line``.

>>> from rrcache.gl.context import get_context
>>> vs = "#version 330\\nin vec2 p; void main() { gl_Position = vec4(p, 0, 1); }"
>>> fs = "#version 330\\nout vec4 c;\\nvoid main() { c = vec4(1); }"
>>> prog = build_program(get_context(), vs, fs)
>>> prog.release()
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Optional, Sequence

import moderngl

from rrcache.errors import GLError, SourceLoc

# Mesa: "0:12(5): error: message"; NVIDIA: "0(12) : error C0000: message"
_MESA = re.compile(r"^\s*(\d+):(\d+)\((\d+)\):\s*(error|warning)\s*:\s*(.*)$")
_NVIDIA = re.compile(r"^\s*(\d+)\((\d+)\)\s*:\s*(error|warning)\s*(?:[A-Z]\d+)?\s*:\s*(.*)$")


@dataclass(frozen=True)
class Diagnostic:
    """One line of a driver log: the printed-source line/column (0 when unknown) and the text."""

    severity: str
    line: int
    col: int
    message: str


def parse_log(log: str) -> list[Diagnostic]:
    """The errors and warnings of a driver compile log, in order.

    >>> parse_log("0:3(7): error: `x' undeclared")
    [Diagnostic(severity='error', line=3, col=7, message="`x' undeclared")]
    >>> parse_log("0(4) : error C1008: undefined variable \\"y\\"")[0].line
    4
    """
    found = []
    for raw in log.splitlines():
        m = _MESA.match(raw)
        if m:
            found.append(Diagnostic(m.group(4), int(m.group(2)), int(m.group(3)), m.group(5).strip()))
            continue
        m = _NVIDIA.match(raw)
        if m:
            found.append(Diagnostic(m.group(3), int(m.group(2)), 0, m.group(4).strip()))
            continue
        text = raw.strip()
        if text.lower().startswith("error:"):
            found.append(Diagnostic("error", 0, 0, text[6:].strip()))
    return found


def map_location(diag: Diagnostic, line_map: Optional[Sequence[Optional[SourceLoc]]], name: str) -> SourceLoc:
    """The original place of a diagnostic: through ``line_map`` when it covers the line, else ``name:line``."""
    if line_map is not None and 1 <= diag.line <= len(line_map):
        loc = line_map[diag.line - 1]
        if loc is not None:  # the driver's column counts in the printed text: keep the map's
            return SourceLoc(loc.file, loc.line, loc.col)
        # a line rrcache generated (no original place): do not pass it off as the user's line
        return SourceLoc(f"{name} (generated line)", diag.line, max(diag.col, 1))
    return SourceLoc(name, diag.line, max(diag.col, 1) if diag.line else 0)


def _stage_section(log: str) -> tuple[str, str]:
    """Split moderngl's message ("GLSL Compiler failed\\n\\nfragment_shader\\n====\\n<log>") into (stage, log)."""
    m = re.search(r"^(vertex_shader|fragment_shader|geometry_shader|tess_control_shader|"
                  r"tess_evaluation_shader|Program)\s*\n=+\s*\n", log, re.MULTILINE)
    if not m:
        return "", log
    return m.group(1), log[m.end():]


def fullscreen_vertex(depth: float = 0.0) -> str:
    """The vertex shader of one triangle covering the viewport (three vertices, no attributes) at
    NDC depth ``depth`` (-1: window depth 0, the nearest): for full-screen passes.

    >>> "gl_VertexID" in fullscreen_vertex() and "-1.0, 1.0)" in fullscreen_vertex(-1.0)
    True
    """
    return ("#version 330 core\nvoid main() {\n"
            "    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n"
            f"    gl_Position = vec4(p * 2.0 - 1.0, {float(depth)!r}, 1.0);\n}}\n")


def build_program(
    ctx: moderngl.Context,
    vertex_src: str,
    fragment_src: str,
    fragment_line_map: Optional[Sequence[Optional[SourceLoc]]] = None,
    fragment_name: str = "<fragment shader>",
    vertex_name: str = "<generated vertex shader>",
) -> moderngl.Program:
    """Compile and link a program; the caller owns it and calls ``release()``.

    A compile error in the fragment shader raises :class:`GLError` at the original place (through
    ``fragment_line_map``, else ``fragment_name:line``) with the driver's message; an error in the
    vertex shader names ``vertex_name``; a link error names the fragment file.

    >>> from rrcache.gl.context import get_context
    >>> try:
    ...     build_program(get_context(), "#version 330\\nvoid main(){gl_Position=vec4(0);}",
    ...                   "#version 330\\nout vec4 c;\\nvoid main(){ c = 1; }", fragment_name="a.frag")
    ... except GLError as err:
    ...     print(err.where)
    a.frag:3:14
    """
    try:
        return ctx.program(vertex_shader=vertex_src, fragment_shader=fragment_src)
    except moderngl.Error as err:
        raise _to_gl_error(str(err), fragment_line_map, fragment_name, vertex_name) from None


def _to_gl_error(text: str, line_map, fragment_name: str, vertex_name: str) -> GLError:
    stage, log = _stage_section(text)
    diags = [d for d in parse_log(log) if d.severity == "error"] or parse_log(log)
    if stage == "Program":
        detail = diags[0].message if diags else log.strip()
        more = f" (and {len(diags) - 1} more)" if len(diags) > 1 else ""
        err = GLError(f"the driver could not link the program: {detail}{more}", where=fragment_name,
                      hint="a varying or uniform is declared with a type the harness does not supply")
        err.loc = None
        err.diagnostics = diags
        return err
    name = vertex_name if stage == "vertex_shader" else fragment_name
    lmap = None if stage == "vertex_shader" else line_map
    if not diags:
        err = GLError(f"the driver rejected the {stage.replace('_', ' ') or 'program'}: {log.strip()}", where=name)
        err.loc = None
        err.diagnostics = []
        return err
    first = diags[0]
    loc = map_location(first, lmap, name)
    more = f" (and {len(diags) - 1} more)" if len(diags) > 1 else ""
    hint = None
    if stage == "vertex_shader" and vertex_name.startswith("<"):
        hint = "the generated vertex shader failed: this is a bug in rrcache, please report it"
    elif stage == "vertex_shader":  # the user's own (--vert): rewritten to core GLSL, lines kept
        hint = ("fix the vertex shader (rrcache compiles it as #version 330 core: attribute/varying "
                "become in/out)")
    err = GLError(f"driver error: {first.message}{more}", where=str(loc) if loc.line else name, hint=hint)
    err.loc = loc if loc.line else None
    err.diagnostics = diags
    return err
