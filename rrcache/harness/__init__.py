"""The rendering harness: replays a session through a fragment shader and measures each frame.

>>> from rrcache.harness import render, mean_l2, psnr
"""
from rrcache.harness.metrics import mean_l2, nonfinite_count, psnr  # noqa: F401
from rrcache.compiler.prepared import Decl, PreparedShader, prepare, prepare_file  # noqa: F401
from rrcache.harness.reference import ReferenceCache, ReferenceFrame  # noqa: F401
from rrcache.harness.renderer import FrameResult, Renderer, RenderResult, render  # noqa: F401
