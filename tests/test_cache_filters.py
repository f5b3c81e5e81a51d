"""The cache's reconstruction filters (``rr_previous()`` of :func:`rrcache.runtime.glsl.lookup_glsl`)
on a known payload, through real GL at 32×32: every filter returns the texel itself at texel
centres; bilinear and Catmull-Rom reproduce a linear ramp at a fractional offset; Catmull-Rom
follows a smooth pattern closer than bilinear (it blurs less, why the amortized PCF scene uses
it) and, clamped to its taps' range, does not overshoot a step edge.
"""
from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("LP_NUM_THREADS", "1")

from rrcache.gl.context import bind_default_framebuffer, get_context  # noqa: E402
from rrcache.runtime import glsl as G  # noqa: E402

N = 32
pytestmark = pytest.mark.usefixtures("gl_ctx")  # and the GL error flag is checked after each

VERTEX = """#version 330 core
in vec2 a_position;
out vec4 rr_prevClip;
void main() { rr_prevClip = vec4(0.0); gl_Position = vec4(a_position, 0.0, 1.0); }
"""


def _fragment(filter_name: str) -> str:
    return ("#version 330 core\n" + G.lookup_glsl(filter_name) + """
uniform vec2 u_shift;
out vec4 fragColor;
void main() {
    rr_uv = (gl_FragCoord.xy + u_shift) / vec2(textureSize(rr_prevPayload, 0));
    fragColor = rr_previous();
}
""")


def _reconstruct(filter_name: str, payload: np.ndarray, shift) -> np.ndarray:
    """``rr_previous()`` at every pixel centre moved by ``shift`` texels, read back (N×N×4)."""
    import moderngl

    ctx = get_context()
    tex = ctx.texture((N, N), 4, np.ascontiguousarray(payload, dtype="f4").tobytes(), dtype="f4")
    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    tex.repeat_x = tex.repeat_y = False
    out = ctx.texture((N, N), 4, dtype="f4")
    fbo = ctx.framebuffer([out])
    prog = ctx.program(vertex_shader=VERTEX, fragment_shader=_fragment(filter_name))
    quad = ctx.buffer(np.array([-1, -1, 1, -1, -1, 1, 1, 1], dtype="f4").tobytes())
    vao = ctx.vertex_array(prog, [(quad, "2f", "a_position")])
    try:
        tex.use(0)
        prog["rr_prevPayload"].value = 0
        prog["u_shift"].value = tuple(float(s) for s in shift)
        fbo.use()
        vao.render(mode=moderngl.TRIANGLE_STRIP)
        return np.frombuffer(fbo.read(components=4, dtype="f4"), dtype="f4").reshape(N, N, 4).copy()
    finally:
        bind_default_framebuffer(ctx)  # before the framebuffer is released (see its doc)
        for obj in (vao, quad, prog, fbo, out, tex):
            obj.release()


def _grid():
    y, x = np.mgrid[0:N, 0:N].astype(np.float64)
    return x, y


def _payload(values: np.ndarray) -> np.ndarray:
    return np.repeat(values[:, :, None], 4, axis=2)


@pytest.mark.parametrize("name", ["nearest", "bilinear", "catmull-rom", "catmull-rom-y"])
def test_texel_centres_are_returned_exactly(name):
    x, y = _grid()
    values = _payload(np.sin(x * 0.7) * np.cos(y * 0.45))
    got = _reconstruct(name, values, (0.0, 0.0))
    assert np.max(np.abs(got - values)) < 1e-5


@pytest.mark.parametrize("name", ["bilinear", "catmull-rom"])
def test_a_ramp_is_reproduced_between_texels(name):
    x, _ = _grid()
    got = _reconstruct(name, _payload(0.05 * x), (0.3, 0.0))
    inner = (slice(2, N - 3), slice(2, N - 3))  # away from the clamped border
    assert np.max(np.abs(got[inner][..., 0] - 0.05 * (x[inner] + 0.3))) < 2e-3


def test_catmull_rom_blurs_less_than_bilinear_and_does_not_overshoot():
    x, y = _grid()
    shift = (0.37, 0.61)
    values = _payload(np.sin(x * 0.9) * np.cos(y * 0.8))
    truth = np.sin((x + shift[0]) * 0.9) * np.cos((y + shift[1]) * 0.8)
    inner = (slice(3, N - 3), slice(3, N - 3))
    err = {name: float(np.abs(_reconstruct(name, values, shift)[inner][..., 0] - truth[inner]).mean())
           for name in ("bilinear", "catmull-rom")}
    assert err["catmull-rom"] < 0.6 * err["bilinear"], err
    step = _payload((x >= N // 2).astype(np.float64))
    got = _reconstruct("catmull-rom", step, (0.5, 0.5))
    assert got.min() >= -1e-6 and got.max() <= 1 + 1e-6
    assert 0.0 < got[N // 2, N // 2 - 1, 0] < 1.0  # the edge is still filtered, not snapped


def test_catmull_rom_y_sharpens_down_the_screen_only():
    """Down the screen it follows a pattern as closely as the full Catmull-Rom; across it is
    bilinear (the same values to rounding); a ramp down the screen is reproduced; a step is
    not overshot."""
    x, y = _grid()
    down = _payload(np.sin(y * 0.9))
    across = _payload(np.sin(x * 0.9))
    shift = (0.37, 0.61)
    inner = (slice(3, N - 3), slice(3, N - 3))
    truth = np.sin((y + shift[1]) * 0.9)
    err = {name: float(np.abs(_reconstruct(name, down, shift)[inner][..., 0] - truth[inner]).mean())
           for name in ("bilinear", "catmull-rom", "catmull-rom-y")}
    assert err["catmull-rom-y"] < 0.75 * err["bilinear"] and err["catmull-rom-y"] < 1.1 * err["catmull-rom"], err
    same = np.abs(_reconstruct("catmull-rom-y", across, shift) - _reconstruct("bilinear", across, shift))[inner]
    assert same.max() < 1e-4
    ramp = _reconstruct("catmull-rom-y", _payload(0.05 * y), (0.0, 0.3))
    assert np.max(np.abs(ramp[inner][..., 0] - 0.05 * (y[inner] + 0.3))) < 2e-3
    step = _reconstruct("catmull-rom-y", _payload((y >= N // 2).astype(np.float64)), (0.5, 0.5))
    assert step.min() >= -1e-6 and step.max() <= 1 + 1e-6
