"""The GLSL side of the reprojection cache, shared by every pass the compiler emits.

The cache is two screen-sized textures, double-buffered (one read, one written, swapped each
frame): the payload (``RGBA16F`` or ``RGBA32F``, up to four channels of the cached value) and the
inverse depth ``1/w`` of the visible surface (``R32F``; 0 where nothing was drawn).

Why ``1/w``: it is an affine function of window position over a planar triangle, so the bilinear
reconstruction of the previous frame's depth is exact on flat surfaces and fails (a miss) across
depth edges, where it mixes foreground and background (Nehab 2007 §3.2). Comparing it *relative*
to the expected value keeps the test meaningful for any near/far range (1e-4 to 1e6 included),
unlike window depth, which saturates near 1.

Hit test for a fragment whose previous-frame clip position is ``rr_prevClip`` (docs/design.md §3):

    expected = 1 / rr_prevClip.w;  uv = rr_prevClip.xy / rr_prevClip.w * 0.5 + 0.5
    hit = rr_valid && uv inside [0,1]² && |bilinear(prevInvDepth, uv) - expected| <= ε · expected

and the pixel is refreshed by the rule in :mod:`rrcache.runtime.refresh` (arithmetic on the
block coordinates, no texture).

Packed inverse depth (optional, ``instance(..., pack_depth=True)``): when the payload has a free
channel (a float, vec2 or vec3 value in a 32-bit payload) the inverse depth can be kept in the
payload texture's next channel (``depth_channel`` = the value's component count) instead of a
texture of its own: one render target and one texture fetch fewer in the passes that write and
read the cache. The values stored are the same 32-bit floats and the hits are the same (the
images agree within 2e-4: llvmpipe filters a two- or four-channel float texture with other
rounding). Measured on Marble's all-hit frame it was no faster on llvmpipe, so it is off by
default. :func:`lookup_glsl` and :func:`output_glsl` take ``depth_channel`` (None: the separate
``R32F`` texture).

Payload reconstruction filters: ``nearest``, ``bilinear`` (hardware), ``catmull-rom``,
``catmull-rom-y`` (Catmull-Rom down the screen only, :data:`_CATMULL_ROM_Y`) and ``edge``
(:data:`FILTERS`). ``catmull-rom`` is the bicubic that blurs less under repeated resampling,
computed from five bilinear fetches (the 4×4 Catmull-Rom with each pair of middle weights
merged into one bilinear tap and the four corner taps, whose weights are products of two small
lobes, left out and the rest renormalised): exact at texel centres and on a ramp moved along
its slope, and clamped to the range of its five taps so that its negative lobes cannot overshoot an
edge. The 16 texel fetches in loops it replaced cost more than the filtering saved on llvmpipe
(the temple's amortized PCF at 4 of 16: 1.13x the original's speed with the loop version, 1.7x
with five taps, 2.15x bilinear; its error against the 256-sample reference 0.70x the
original's, bilinear 0.88x: README, "Amortized sampling").
"""
from __future__ import annotations

import re
from typing import Optional

from rrcache.runtime.refresh import REFRESH_GLSL

#: the cache's reconstruction filters (their GLSL below), named by selections and variant specs
FILTERS = ("nearest", "bilinear", "catmull-rom", "catmull-rom-y", "edge", "plane")

# Names the runtime binds. Kept in one place so the compiler and the runtime agree.
PREV_PAYLOAD = "rr_prevPayload"
PREV_INVDEPTH = "rr_prevInvDepth"
CUR_PAYLOAD = "rr_curPayload"
PREV_CLIP = "rr_prevClip"
OUT_PAYLOAD = "rr_outPayload"
OUT_INVDEPTH = "rr_outInvDepth"
OUT_COLOR_TWO_PASS = "rr_outColor"

_COMMON = """\
// ---- rrcache reverse reprojection cache (rrcache.runtime) ----
in vec4 rr_prevClip;
uniform sampler2D rr_prevPayload;
uniform sampler2D rr_prevInvDepth;
uniform bool rr_valid;
uniform float rr_depthEpsilon;
vec2 rr_uv;
""" + REFRESH_GLSL + """

bool rr_hit() {
    if (!rr_valid || rr_prevClip.w <= 0.0) return false;
    rr_uv = rr_prevClip.xy / rr_prevClip.w * 0.5 + 0.5;
    if (any(lessThan(rr_uv, vec2(0.0))) || any(greaterThan(rr_uv, vec2(1.0)))) return false;
    float expected = 1.0 / rr_prevClip.w;
    float stored = texture(rr_prevInvDepth, rr_uv).r;
    return abs(stored - expected) <= rr_depthEpsilon * expected;
}
"""

_NEAREST = """
vec4 rr_previous() {
    ivec2 size = textureSize(rr_prevPayload, 0);
    ivec2 texel = clamp(ivec2(floor(rr_uv * vec2(size))), ivec2(0), size - 1);
    return texelFetch(rr_prevPayload, texel, 0);
}
"""

_BILINEAR = """
vec4 rr_previous() {
    return texture(rr_prevPayload, rr_uv);
}
"""

# The Catmull-Rom weights of the four taps around a texel offset ``f`` in [0, 1) (``T``: float
# or vec2, one per axis), with the middle pair merged (``w12``) for a bilinear tap at ``w2/w12``.
_CATMULL_ROM_WEIGHTS = """
    T w0 = f * (-0.5 + f * (1.0 - 0.5 * f));
    T w1 = 1.0 + f * f * (-2.5 + 1.5 * f);
    T w2 = f * (0.5 + f * (2.0 - 1.5 * f));
    T w3 = f * f * (-0.5 + 0.5 * f);
    T w12 = w1 + w2;
"""


def _catmull_rom_weights(type_name: str) -> str:
    return _CATMULL_ROM_WEIGHTS.replace("T ", f"{type_name} ").lstrip("\n")


_CATMULL_ROM = """
vec4 rr_previous() {
    vec2 size = vec2(textureSize(rr_prevPayload, 0));
    vec2 p = rr_uv * size;
    vec2 t1 = floor(p - 0.5) + 0.5;
    vec2 f = p - t1;
""" + _catmull_rom_weights("vec2") + """    vec2 t0 = (t1 - 1.0) / size;
    vec2 t3 = (t1 + 2.0) / size;
    vec2 t12 = (t1 + w2 / w12) / size;
    vec4 n = texture(rr_prevPayload, vec2(t12.x, t0.y));
    vec4 w = texture(rr_prevPayload, vec2(t0.x, t12.y));
    vec4 c = texture(rr_prevPayload, t12);
    vec4 e = texture(rr_prevPayload, vec2(t3.x, t12.y));
    vec4 s = texture(rr_prevPayload, vec2(t12.x, t3.y));
    vec4 sum = (n * (w12.x * w0.y) + w * (w0.x * w12.y) + c * (w12.x * w12.y) + e * (w3.x * w12.y)
                + s * (w12.x * w3.y))
             / (w12.x * w0.y + w0.x * w12.y + w12.x * w12.y + w3.x * w12.y + w12.x * w3.y);
    return clamp(sum, min(min(min(n, w), min(e, s)), c), max(max(max(n, w), max(e, s)), c));
}
"""

#: Catmull-Rom down the screen, bilinear across: three bilinear taps in one column (the middle
#: pair of weights merged into one tap), clamped to their range. Perspective compresses a floor
#: or a terrain seen at a slant along the screen's vertical, so that is where their shading
#: varies fastest and where repeated bilinear resampling blurs most; on the temple's amortized
#: PCF it kept the full Catmull-Rom's error (0.78x the original's over the session) at less cost
#: (1.87x the original's speed against 1.69x; bilinear 2.13x at 1.11x the error). A surface whose
#: detail runs the other way gains nothing over bilinear from it.
_CATMULL_ROM_Y = """
vec4 rr_previous() {
    float size = float(textureSize(rr_prevPayload, 0).y);
    float p = rr_uv.y * size;
    float t1 = floor(p - 0.5) + 0.5;
    float f = p - t1;
""" + _catmull_rom_weights("float") + """    vec4 a = texture(rr_prevPayload, vec2(rr_uv.x, (t1 - 1.0) / size));
    vec4 b = texture(rr_prevPayload, vec2(rr_uv.x, (t1 + w2 / w12) / size));
    vec4 c = texture(rr_prevPayload, vec2(rr_uv.x, (t1 + 2.0) / size));
    return clamp(a * w0 + b * w12 + c * w3, min(min(a, b), c), max(max(a, b), c));
}
"""

_EDGE = """
vec4 rr_edgeWeights;
ivec2 rr_edgeBase;
bool rr_edgeFull;

bool rr_hit() {
    if (!rr_valid || rr_prevClip.w <= 0.0) return false;
    rr_uv = rr_prevClip.xy / rr_prevClip.w * 0.5 + 0.5;
    if (any(lessThan(rr_uv, vec2(0.0))) || any(greaterThan(rr_uv, vec2(1.0)))) return false;
    float expected = 1.0 / rr_prevClip.w;
    float tolerance = rr_depthEpsilon * expected;
    rr_edgeFull = abs(texture(rr_prevInvDepth, rr_uv).r - expected) <= tolerance;
    if (rr_edgeFull) return true;
    ivec2 size = textureSize(rr_prevInvDepth, 0);
    vec2 p = rr_uv * vec2(size) - 0.5;
    rr_edgeBase = ivec2(floor(p));
    vec2 f = p - vec2(rr_edgeBase);
    ivec2 hi = size - 1;
    vec4 d = vec4(texelFetch(rr_prevInvDepth, clamp(rr_edgeBase, ivec2(0), hi), 0).r,
                  texelFetch(rr_prevInvDepth, clamp(rr_edgeBase + ivec2(1, 0), ivec2(0), hi), 0).r,
                  texelFetch(rr_prevInvDepth, clamp(rr_edgeBase + ivec2(0, 1), ivec2(0), hi), 0).r,
                  texelFetch(rr_prevInvDepth, clamp(rr_edgeBase + ivec2(1, 1), ivec2(0), hi), 0).r);
    vec4 w = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    vec4 ok = vec4(lessThanEqual(abs(d - vec4(expected)), vec4(2.0 * tolerance)));
    rr_edgeWeights = w * ok;
    float total = dot(rr_edgeWeights, vec4(1.0));
    if (total <= 0.0) return false;
    rr_edgeWeights /= total;
    return true;
}

vec4 rr_previous() {
    if (rr_edgeFull) return texture(rr_prevPayload, rr_uv);
    ivec2 hi = textureSize(rr_prevPayload, 0) - 1;
    return rr_edgeWeights.x * texelFetch(rr_prevPayload, clamp(rr_edgeBase, ivec2(0), hi), 0)
         + rr_edgeWeights.y * texelFetch(rr_prevPayload, clamp(rr_edgeBase + ivec2(1, 0), ivec2(0), hi), 0)
         + rr_edgeWeights.z * texelFetch(rr_prevPayload, clamp(rr_edgeBase + ivec2(0, 1), ivec2(0), hi), 0)
         + rr_edgeWeights.w * texelFetch(rr_prevPayload, clamp(rr_edgeBase + ivec2(1, 1), ivec2(0), hi), 0);
}
"""

#: ``plane``: the hit test of ``edge`` made exact on planes. The inverse depth 1/w is an affine
#: function of the previous frame's screen position over a planar surface, so its value at each
#: of the four texels around the reprojected position is predicted from its value here and its
#: gradient, found from the screen-space derivatives of the reprojected position and depth
#: (taken first, in the caller's control flow). A texel holds this surface when its stored
#: inverse depth is within the tolerance of the prediction. All four: the hardware bilinear
#: payload; some (the band along a depth edge): the bilinear mix of those alone, weights
#: renormalised; none, or less than 1% of the bilinear weight: a miss. ``bilinear`` misses the band (its mix of foreground and
#: background depths matches neither) and accepts a texel of another surface at a similar depth
#: (where a piece stands on the board) into the payload; ``edge`` serves the band but compares
#: every texel with the depth *here* at twice the tolerance, which takes the board for the piece
#: and misses a surface seen at a grazing angle. Three more texel fetches than ``bilinear`` per
#: reprojected pixel.
#: the texel test of ``plane``, shared with the miss classifier (rrcache.runtime.misses): which of
#: the four texels around ``p`` (this fragment's place in the previous frame's texels) hold the
#: surface whose inverse depth is ``expected`` here, with screen-space derivatives ``dpx``,
#: ``dpy`` (of ``p``) and ``de`` (of ``expected``): 1 or 0 per texel; ``base`` the lower-left
#: texel and ``weights`` the four bilinear weights
PLANE_TEXELS = """
vec4 rr_planeTexels(vec2 p, float expected, vec2 dpx, vec2 dpy, vec2 de, float tolerance,
                    out ivec2 base, out vec4 weights) {
    // the gradient g of the inverse depth over previous-frame texels: g . dpx = de.x, g . dpy = de.y
    float det = dpx.x * dpy.y - dpx.y * dpy.x;
    vec2 g = abs(det) > 1e-6 * (dot(dpx, dpx) + dot(dpy, dpy))
        ? vec2(dpy.y * de.x - dpx.y * de.y, dpx.x * de.y - dpy.x * de.x) / det : vec2(0.0);
    base = ivec2(floor(p));
    vec2 f = p - vec2(base);
    ivec2 hi = textureSize(rr_prevInvDepth, 0) - 1;
    ivec2 t0 = clamp(base, ivec2(0), hi);
    ivec2 t1 = clamp(base + ivec2(1, 0), ivec2(0), hi);
    ivec2 t2 = clamp(base + ivec2(0, 1), ivec2(0), hi);
    ivec2 t3 = clamp(base + ivec2(1, 1), ivec2(0), hi);
    vec4 d = vec4(texelFetch(rr_prevInvDepth, t0, 0).r, texelFetch(rr_prevInvDepth, t1, 0).r,
                  texelFetch(rr_prevInvDepth, t2, 0).r, texelFetch(rr_prevInvDepth, t3, 0).r);
    vec4 e = expected + vec4(dot(g, vec2(t0) - p), dot(g, vec2(t1) - p), dot(g, vec2(t2) - p), dot(g, vec2(t3) - p));
    weights = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
    return vec4(lessThanEqual(abs(d - e), vec4(tolerance)));
}
"""

#: the inputs of ``rr_planeTexels`` (statements of a function body): this fragment's place ``p``
#: and inverse depth ``expected`` in the previous frame's texels, and their screen-space
#: derivatives, taken in uniform control flow (shared with the miss classifier)
PLANE_INPUTS = """    ivec2 size = textureSize(rr_prevInvDepth, 0);
    vec2 p = (rr_prevClip.xy / rr_prevClip.w * 0.5 + 0.5) * vec2(size) - 0.5;
    float expected = 1.0 / rr_prevClip.w;
    vec2 dpx = dFdx(p);
    vec2 dpy = dFdy(p);
    vec2 de = vec2(dFdx(expected), dFdy(expected));
"""

_PLANE = PLANE_TEXELS + """
vec4 rr_edgeWeights;
ivec2 rr_edgeBase;
bool rr_edgeFull;

bool rr_hit() {
""" + PLANE_INPUTS + """    if (!rr_valid || rr_prevClip.w <= 0.0) return false;
    rr_uv = (p + 0.5) / vec2(size);
    if (any(lessThan(rr_uv, vec2(0.0))) || any(greaterThan(rr_uv, vec2(1.0)))) return false;
    vec4 weights;
    vec4 ok = rr_planeTexels(p, expected, dpx, dpy, de, rr_depthEpsilon * expected, rr_edgeBase, weights);
    rr_edgeFull = all(greaterThan(ok, vec4(0.5)));
    if (rr_edgeFull) return true;
    rr_edgeWeights = weights * ok;
    float total = dot(rr_edgeWeights, vec4(1.0));
    // a sample point this surface's texels carry (next to) no weight at is another surface's
    if (total < 0.01) return false;
    rr_edgeWeights /= total;
    return true;
}
""" + _EDGE[_EDGE.index("vec4 rr_previous()"):]

_CURRENT = """
vec4 rr_current() {
    return texelFetch(rr_curPayload, ivec2(gl_FragCoord.xy), 0);
}
"""


AMORTIZE_GLSL = """
// ---- amortized sampling (rrcache.compiler.amortize) ----
uniform float rr_lambda;
"""

#: the "pixel" phase of amortized sampling: the subset's phase from the frame and the pixel
AMORTIZE_PIXEL_GLSL = """uniform int rr_amortFrame;
int rr_amortPhase(int period) {
    ivec2 p = ivec2(gl_FragCoord.xy);
    return (rr_amortFrame + p.x + 2 * p.y) % period;
}
"""


_CHANNELS = "xyzw"


def lookup_glsl(filter: str = "bilinear", depth_channel: Optional[int] = None) -> str:
    """Declarations and functions for a pass that reads the *previous* frame's cache:
    ``rr_hit()``, ``rr_refreshNow()`` and ``rr_previous()`` (valid after ``rr_hit()`` returned
    true). Include it after the ``#version`` line of a fragment shader. ``depth_channel``: the
    payload channel holding the inverse depth (None: the texture ``rr_prevInvDepth``).

    >>> "rr_prevInvDepth" in lookup_glsl(depth_channel=1), "texture(rr_prevPayload, rr_uv).y" in lookup_glsl(depth_channel=1)
    (False, True)
    >>> "rr_prevInvDepth" in lookup_glsl("plane", depth_channel=3), "texelFetch(rr_prevPayload, t0, 0).w" in lookup_glsl("plane", 3)
    (False, True)
    """
    if filter not in FILTERS:
        raise ValueError(f"cache filter must be one of {FILTERS}, not {filter!r}")
    if filter in ("edge", "plane"):  # its own hit test (and the common one's declarations before it)
        text = _COMMON.split("\nbool rr_hit()")[0] + "\n" + (_EDGE if filter == "edge" else _PLANE)
    else:
        text = _COMMON + {"nearest": _NEAREST, "bilinear": _BILINEAR, "catmull-rom": _CATMULL_ROM,
                          "catmull-rom-y": _CATMULL_ROM_Y}[filter]
    return packed_depth(text, depth_channel)  # every read of the inverse depth: the payload's channel


def packed_depth(text: str, depth_channel: Optional[int]) -> str:
    """``text`` with every read of ``rr_prevInvDepth`` reading the payload's channel
    ``depth_channel`` instead (None: unchanged)."""
    if depth_channel is None:
        return text
    text = text.replace("uniform sampler2D rr_prevInvDepth;\n", "")
    text = re.sub(r"(texture|texelFetch)\(rr_prevInvDepth, ([^;]*?)\)\.r\b",
                  lambda m: f"{m.group(1)}(rr_prevPayload, {m.group(2)}).{_CHANNELS[depth_channel]}", text)
    return text.replace("textureSize(rr_prevInvDepth, 0)", "textureSize(rr_prevPayload, 0)")


def current_glsl() -> str:
    """Declarations for the final pass of the three-pass algorithm: ``rr_current()`` reads this
    frame's payload at this pixel."""
    return "uniform sampler2D rr_curPayload;\n" + _CURRENT


def output_glsl(first_location: int = 0, depth_channel: Optional[int] = None) -> str:
    """The cache outputs of a pass that writes the cache: payload and inverse depth (with a
    ``depth_channel``, the payload alone: the inverse depth is written into that channel)."""
    out = f"layout(location = {first_location}) out vec4 rr_outPayload;\n"
    if depth_channel is None:
        out += f"layout(location = {first_location + 1}) out float rr_outInvDepth;\n"
    return out


def depth_channel_for(components: int, payload_dtype: str) -> Optional[int]:
    """The payload channel the inverse depth is packed into for a value of ``components``
    components: the next free one in a 32-bit payload, None when there is none (a vec4) or the
    payload is 16-bit (the inverse depth needs 32 bits for the relative hit test).

    >>> depth_channel_for(1, "f4"), depth_channel_for(3, "f4"), depth_channel_for(4, "f4"), depth_channel_for(1, "f2")
    (1, 3, None, None)
    """
    return int(components) if int(components) < 4 and payload_dtype == "f4" else None


def vertex_glsl() -> str:
    """What a vertex shader adds for the cache: the previous-frame clip position ``rr_prevClip``,
    computed from ``u_prevModelViewProjectionMatrix`` (the application supplies it per object)."""
    return "uniform mat4 u_prevModelViewProjectionMatrix;\nout vec4 rr_prevClip;\n"
