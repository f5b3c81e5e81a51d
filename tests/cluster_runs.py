"""Contexts for the cluster tests (pickled by value, so that the workers need not import tests/).

``Sleepy.run(seconds)`` draws and reads back a real 8×8 frame on the worker's GL context, then
sleeps: a run long enough for runs on two workers to overlap. ``Dies.run(_)`` ends its worker
process, as a driver crash would.
"""
from __future__ import annotations

import os
import time


class Sleepy:
    def __init__(self):
        self.released = False

    def run(self, seconds):
        import numpy as np

        from rrcache.gl.context import get_context

        ctx = get_context()
        fbo = ctx.simple_framebuffer((8, 8))
        fbo.use()
        ctx.clear(0.25, 0.5, 0.75, 1.0)
        pixel = np.frombuffer(fbo.read(components=4), dtype=np.uint8)[:4].tolist()
        fbo.release()
        time.sleep(seconds)
        return {"pixel": pixel, "pid": os.getpid()}

    def release(self):
        self.released = True


class Dies:
    def run(self, _):
        os._exit(3)
