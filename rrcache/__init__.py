"""rrcache: automated reverse-reprojection-cache optimisation of GLSL pixel shaders.

The public API; the CLI and the notebooks use nothing else.

>>> import rrcache
>>> shader = rrcache.load_shader("shaders/glslviewer_basic.glsl")
>>> session = rrcache.load_session("sessions/marble.json")
>>> result = rrcache.render(shader, session, frames=[0, 1], resolution=(64, 48))
>>> [f.index for f in result.frames], result.frames[1].image.shape
([0, 1], (48, 64, 4))

Names are imported lazily so that ``import rrcache`` stays cheap.
"""
from __future__ import annotations

import importlib

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

# public name -> module that defines it
_LAZY = {
    "load_shader": "rrcache.glsl.frontend",
    "parse_shader": "rrcache.glsl.frontend",
    "Shader": "rrcache.glsl.frontend",
    "cacheable_nodes": "rrcache.analysis",
    "find_node": "rrcache.analysis",
    "analyse": "rrcache.analysis",
    "load_session": "rrcache.session",
    "Session": "rrcache.session",
    "render": "rrcache.harness",
    "Renderer": "rrcache.harness",
    "ReferenceCache": "rrcache.harness",
    "mean_l2": "rrcache.harness",
    "psnr": "rrcache.harness",
    "CacheRuntime": "rrcache.runtime",
    "profile": "rrcache.profiler",
    "load_profile": "rrcache.profiles",
    "select": "rrcache.profiles",
    "TrainingSettings": "rrcache.profiles",
    "held_out": "rrcache.profiler.accuracy",
    "get_context": "rrcache.gl",
}


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'rrcache' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(list(globals()) + list(_LAZY))
