"""The rendering harness: replays a session through a fragment shader and measures each frame.

Its names are imported when first used (importing :mod:`rrcache.harness.timing`, say, loads no
renderer).

>>> from rrcache.harness import render, mean_l2, psnr
"""
import importlib

#: public name -> the module that defines it
_NAMES = {
    "mean_l2": "rrcache.harness.metrics", "nonfinite_count": "rrcache.harness.metrics",
    "psnr": "rrcache.harness.metrics",
    "Decl": "rrcache.compiler.prepared", "PreparedShader": "rrcache.compiler.prepared",
    "prepare": "rrcache.compiler.prepared", "prepare_file": "rrcache.compiler.prepared",
    "ReferenceCache": "rrcache.harness.reference", "ReferenceFrame": "rrcache.harness.reference",
    "FrameResult": "rrcache.harness.renderer", "Renderer": "rrcache.harness.renderer",
    "RenderResult": "rrcache.harness.renderer", "render": "rrcache.harness.renderer",
}


def __getattr__(name):
    if name in _NAMES:
        return getattr(importlib.import_module(_NAMES[name]), name)
    raise AttributeError(f"module 'rrcache.harness' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_NAMES))
