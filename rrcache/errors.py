"""The project's own exception types.

Every error rrcache raises on bad input is an :class:`RRCacheError`. Each carries the file and the
place (line and column for source files, a JSON path for sessions) and, where one helps, a hint on
what to do. ``str(err)`` is the one-line message the CLI prints, in the usual
``file:line:col: message`` form.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\ud800-\udfff]")


def printable(text: str) -> str:
    """``text`` with control characters (NUL, escape, newline...) and lone surrogates escaped as ``\\x00``
    or ``\\ud800``: an error message never carries raw bytes of a file to the terminal.

    >>> printable("a\\x00b\\udc80")
    'a\\\\x00b\\\\udc80'
    """
    return _CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}" if ord(m.group()) < 0x100
                        else f"\\u{ord(m.group()):04x}", text)


@dataclass(frozen=True)
class SourceLoc:
    """A place in a source file: 1-based line and column."""

    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


class RRCacheError(Exception):
    """Base class of every error rrcache reports to its users.

    ``where`` is a human-readable place (``shader.glsl:12:5`` or ``session.json: camera.fov``),
    ``hint`` an optional sentence saying what to do.
    """

    def __init__(self, message: str, where: str | None = None, hint: str | None = None):
        self.message = message
        self.where = where
        self.hint = hint
        super().__init__(self.__str__())

    def __str__(self) -> str:
        text = f"{self.where}: {self.message}" if self.where else self.message
        if self.hint:
            text += f" (hint: {self.hint})"
        return text


class GLSLError(RRCacheError):
    """A shader source problem: preprocessing, lexing, parsing or type checking."""

    def __init__(self, message: str, loc: SourceLoc | None = None, hint: str | None = None):
        self.loc = loc
        super().__init__(message, str(loc) if loc else None, hint)


class PreprocessorError(GLSLError):
    pass


class ParseError(GLSLError):
    pass


class SemanticError(GLSLError):
    pass


class UnsupportedShaderError(GLSLError):
    """Valid GLSL that rrcache does not handle (a vertex shader, several colour outputs...)."""


class SessionError(RRCacheError):
    """A session file problem. ``path`` is the session file, ``json_path`` e.g. ``camera.keyframes[2].eye``."""

    def __init__(self, message: str, path: str, json_path: str | None = None, hint: str | None = None):
        self.path = path
        self.json_path = json_path
        where = f"{path}: {json_path}" if json_path else path
        super().__init__(message, where, hint)


class AssetError(SessionError):
    """A mesh or texture file named by a session is missing or unreadable."""


class GLError(RRCacheError):
    """The OpenGL side: no EGL, an unusable GL version, a program the driver refuses."""
