"""rrcache: automated reverse-reprojection-cache optimisation of GLSL pixel shaders.

The public API (see README.md). The CLI and the notebooks use nothing else.
"""
from __future__ import annotations

__version__ = "0.1.0"

from rrcache.errors import (  # noqa: F401
    AssetError,
    GLError,
    GLSLError,
    ParseError,
    PreprocessorError,
    RRCacheError,
    SemanticError,
    SessionError,
    SourceLoc,
    UnsupportedShaderError,
)
