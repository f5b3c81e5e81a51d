"""Adaptive refresh: each cache entry decides at run time whether to be recomputed.

The fixed schedule (:mod:`rrcache.runtime.refresh`) recomputes every entry once every Δn frames,
calm and volatile alike. An adaptive variant (compiled with ``adaptive=True``) keeps one more
value per entry, its **volatility** ``v``: how much the entry had changed when it was last
recomputed, ``max |fresh − reprojected|`` over the payload's components (measured where the
recomputation replaces an entry that still reprojected: a refresh; a new surface, a
disocclusion, gets ``v = 0``). ``v`` travels with the entry like the payload (reprojected,
bilinear) in a third cache target (``R32F``, double-buffered, written by every pass that writes
the cache). A hit pixel is refreshed when

    the fixed rule at Δn says so (the **max age**: every entry is recomputed within Δn frames), or
    v ≥ threshold and the fixed rule at the **fast period** Δf says so (the **budget**).

So volatile entries (those that changed by at least the threshold) are recomputed every Δf
frames and calm ones every Δn; an entry's class is measured again at each of its refreshes
(where the king moves away from a square, its next refresh finds little change and the square
falls back to Δn). The refreshes per frame are bounded whatever the scene does: at most
1/Δn + 1/Δf of the entries (two hash phases of the same aligned pixel blocks; both rules are
:mod:`rrcache.runtime.refresh`'s, with the same block size and seed), so the frame time stays
predictable; the rest of the misses are disocclusions, as with the fixed rule.

``threshold = 0`` makes every entry volatile (v ≥ 0): the fast rule alone, and with Δf = 1
every pixel is recomputed every frame, exactly the original (tested on the corpus). A threshold
above every change makes it the fixed rule at Δn. The profiler sweeps the threshold like Δn
(:mod:`rrcache.profiler.adaptive`).

``spread`` (pixels, 0 = off) widens what an entry sees of its neighbours' volatility: the
maximum of ``v`` at the reprojected position and at four points ``spread`` pixels away, so a
volatile region grows into calm neighbours by ``spread`` pixels per fast period (a moving
occluder's influence moves into them); four more texture reads per hit.
"""
from __future__ import annotations

from rrcache.runtime.refresh import refresh_uniforms

#: the fast period Δf by default: volatile entries are recomputed every 4 frames
DEFAULT_FAST_PERIOD = 4
#: the volatility spread by default (pixels; 0: each entry sees its own volatility only)
DEFAULT_SPREAD = 0.0

PREV_STATE = "rr_prevState"
OUT_STATE = "rr_outState"

#: what a pass that reads the previous frame's cache adds: rr_refreshNow() becomes the adaptive
#: rule (the fixed one, renamed rr_fixedRefreshNow, is the max age); rr_carried is the
#: reprojected volatility (set by rr_refreshNow when it did not refresh at max age)
LOOKUP_GLSL = """
// ---- adaptive refresh (rrcache.runtime.adaptive) ----
uniform sampler2D rr_prevState;
uniform float rr_threshold;
uniform int rr_fastPeriod;
uniform int rr_fastPhase;
uniform float rr_fastScale;
uniform float rr_spread;
uniform vec4 rr_stateMask;
float rr_carried = 0.0;

bool rr_fastRefreshNow() {  // the fixed rule's block ranks (runtime/refresh.py) at the fast period
    return min(int(rr_blockRank() * rr_fastScale), rr_fastPeriod - 1) == rr_fastPhase;
}

bool rr_refreshNow() {
    if (rr_fixedRefreshNow()) return true;
    rr_carried = texture(rr_prevState, rr_uv).r;
    if (rr_spread > 0.0) {
        vec2 d = rr_spread / vec2(textureSize(rr_prevState, 0));
        rr_carried = max(rr_carried, max(max(texture(rr_prevState, rr_uv + vec2(d.x, 0.0)).r,
                                             texture(rr_prevState, rr_uv - vec2(d.x, 0.0)).r),
                                         max(texture(rr_prevState, rr_uv + vec2(0.0, d.y)).r,
                                             texture(rr_prevState, rr_uv - vec2(0.0, d.y)).r)));
    }
    return rr_carried >= rr_threshold && rr_fastRefreshNow();
}

float rr_freshState(vec4 fresh) {
    if (!rr_hit()) return 0.0;
    vec4 d = abs(fresh - rr_previous()) * rr_stateMask;
    return max(max(d.x, d.y), max(d.z, d.w));
}
"""


def lookup_glsl(base: str) -> str:
    """``base`` (the one-node runtime's lookup GLSL, :func:`rrcache.runtime.glsl.lookup_glsl`)
    with its refresh rule renamed ``rr_fixedRefreshNow`` and the adaptive rule added."""
    return base.replace("bool rr_refreshNow()", "bool rr_fixedRefreshNow()") + LOOKUP_GLSL


def output_glsl(location: int) -> str:
    """The volatility output of a pass that writes the cache (after its inverse depth)."""
    return f"layout(location = {location}) out float {OUT_STATE};\n"


def adaptive_uniforms(size: tuple[int, int], block: int, mode: str, seed: int, fast_period: int,
                      clock: int, threshold: float, spread: float, components: int = 4) -> dict:
    """The adaptive rule's uniforms at frame ``clock`` (the fixed rule's come from
    :func:`rrcache.runtime.refresh.refresh_uniforms`); ``components``: the payload's (a texture
    of fewer channels reads back 0, 0, 1 in the others, which must not count as a change)."""
    fast = refresh_uniforms(size, block, mode, seed, fast_period, clock)
    return {"rr_fastPeriod": fast["rr_period"], "rr_fastPhase": fast["rr_refreshPhase"],
            "rr_fastScale": fast["rr_refreshScale"], "rr_threshold": float(threshold),
            "rr_spread": float(spread),
            "rr_stateMask": tuple(1.0 if i < components else 0.0 for i in range(4))}
