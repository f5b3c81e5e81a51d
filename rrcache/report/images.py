"""Frames of a profile's choices: the original, the cached variant, the error map, the payload and
the hit/miss map of one frame, rendered for real (the harness and the cache runtime) at a modest
resolution, and encoded as PNG for the report and the notebooks.

The cached frame is the last of a run of consecutive frames from frame 0, long enough for the
cache to be in its steady state (Δn + 2 frames, at most the session's), so its hits and its
refreshes look as they do while the application runs. The original is rendered at the same frame.

An amortized selection (an estimator's m of N terms per frame, blend λ, history ``blend`` or
``slots``; :class:`rrcache.selection.AmortizedLoop`) is rendered the same way with its variant
(:func:`rrcache.pipeline.variant_for_selection`): the run is long enough for its history to settle
(:func:`settle_frame`: the N/m-frame cycle of subsets plus the frames the blend's memory λ^k needs
to fall below 5 %), and its payload image is the running estimate (``blend``) or the N/m subset
sums (``slots``). :meth:`FrameShots.selection_images` renders any selection with frames.

>>> shots = FrameShots(load_profile("demo.rrprofile"))                     # doctest: +SKIP
>>> images = shots.images("n932", 16)                                      # doctest: +SKIP
>>> images.png("hit_map")[:4]                                              # doctest: +SKIP
b'\\x89PNG'
>>> shots.selection_images(prof.select(0.02)).what                         # doctest: +SKIP
'e1 m=4 λ=0.6'
"""
from __future__ import annotations

import base64
import io
import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

#: the widest image the report and the notebooks render (pixels)
MAX_WIDTH = 320

#: hit / miss / background colours of the hit map (RGB in [0, 1])
HIT_COLOR = (0.18, 0.72, 0.35)
MISS_COLOR = (0.90, 0.30, 0.20)
EMPTY_COLOR = (0.12, 0.12, 0.14)

#: what each image shows, in the order the report lays them out
CAPTIONS = {
    "original": "original shader",
    "cached": "with the cache",
    "error_map": "error |cached − original|",
    "payload": "cache payload",
    "hit_map": "hits (green) and misses (red)",
}


#: how far the blend's memory λ^k must fall before an amortized frame is shown
SETTLED = 0.05


def settle_frame(frames: int, cycle: int, blend: float) -> int:
    """The frame shown for an amortized selection: after its ``cycle`` (N/m frames, every subset
    once) and the frames its blend's memory needs (λ^k ≤ 5 %), plus one; at most the session's
    last frame (``frames`` - 1).

    >>> settle_frame(150, 4, 0.6), settle_frame(150, 4, 0.0), settle_frame(12, 2, 0.9)
    (11, 5, 11)
    """
    memory = math.ceil(math.log(SETTLED) / math.log(blend)) if 0.0 < blend < 1.0 else 0
    return min(int(frames) - 1, int(cycle) + memory + 1)


def image_size(resolution, max_width: int = MAX_WIDTH) -> tuple[int, int]:
    """The session's resolution scaled down to at most ``max_width`` pixels wide (aspect kept).

    >>> image_size((640, 480)), image_size((160, 120)), image_size((1000, 10))
    ((320, 240), (160, 120), (320, 3))
    """
    w, h = (int(v) for v in resolution)
    if w <= max_width:
        return w, h
    return max_width, max(1, round(h * max_width / w))


def png_bytes(image: np.ndarray) -> bytes:
    """An H×W×3 (or ×4, or H×W grey) float image in [0, 1], row 0 = top, as PNG bytes."""
    from PIL import Image

    pixels = np.nan_to_num(np.asarray(image, dtype=np.float64), nan=0.0)
    pixels = (np.clip(pixels, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[..., 0]
    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, format="PNG")
    return buffer.getvalue()


def data_uri(data: bytes, mime: str = "image/png") -> str:
    """``data:<mime>;base64,...`` for inlining a file into HTML."""
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


def error_map(image: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, float]:
    """``(RGB image, scale)``: the per-pixel RGB L2 distance through matplotlib's *magma*
    colour map, black = 0 and white = ``scale`` (the 99th percentile over covered pixels, at
    least 1e-4); uncovered pixels stay black."""
    from matplotlib import colormaps

    dist = np.linalg.norm(np.nan_to_num(image[..., :3] - reference[..., :3]), axis=-1)
    dist = np.where(mask, dist, 0.0)
    scale = float(max(np.percentile(dist[mask], 99), 1e-4)) if mask.any() else 1e-4
    rgb = colormaps["magma"](np.clip(dist / scale, 0.0, 1.0))[..., :3]
    return np.where(mask[..., None], rgb, 0.0), scale


def payload_image(payload: np.ndarray, components: int, mask: np.ndarray) -> tuple[np.ndarray, list]:
    """``(RGB image, ranges)``: the payload's channels stretched to [0, 1] over the covered pixels
    (one component grey, two as red and green, three or four as RGB with the fourth left out);
    ``ranges`` lists each shown channel's (min, max)."""
    shown = max(1, min(int(components), 3))
    channels, ranges = [], []
    for c in range(shown):
        values = np.nan_to_num(payload[..., c].astype(np.float64))
        lo, hi = (float(values[mask].min()), float(values[mask].max())) if mask.any() else (0.0, 1.0)
        ranges.append((lo, hi))
        channels.append((values - lo) / (hi - lo) if hi > lo else np.full_like(values, 0.5))
    if shown == 1:
        channels = channels * 3
    elif shown == 2:
        channels.append(np.zeros_like(channels[0]))
    rgb = np.stack(channels, axis=-1)
    return np.where(mask[..., None], rgb, np.array(EMPTY_COLOR)), ranges


def hit_map_image(hits: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Hits green, misses (refreshes and disocclusions) red, nothing drawn dark grey."""
    out = np.empty(mask.shape + (3,))
    out[:] = EMPTY_COLOR
    out[mask & hits] = HIT_COLOR
    out[mask & ~hits] = MISS_COLOR
    return out


@dataclass
class ChoiceImages:
    """The images of one choice (``node`` None and ``part`` None: the original shader, nothing
    cached; ``part`` an :class:`~rrcache.selection.AmortizedLoop`: an amortized estimator) at
    frame ``frame``, ``size`` (w, h): float RGB arrays in ``arrays`` keyed as :data:`CAPTIONS`
    (the cached ones absent for the original), the frame's measured ``error`` (mean RGB L2 over
    covered pixels), its ``hit_rate``, the error map's ``error_scale`` and the payload's channel
    ``payload_ranges``; ``captions`` overrides :data:`CAPTIONS` where this choice's image shows
    something else (an amortized payload)."""

    node: Optional[str]
    period: Optional[int]
    frame: int
    size: tuple
    arrays: dict = field(default_factory=dict)
    error: float = 0.0
    hit_rate: Optional[float] = None
    error_scale: Optional[float] = None
    payload_ranges: list = field(default_factory=list)
    part: object = None
    captions: dict = field(default_factory=dict)

    @property
    def cached(self) -> bool:
        """Whether these are a variant's images (not the original shader's alone)."""
        return self.node is not None or self.part is not None

    @property
    def what(self) -> str:
        """``n12 Δn=16``, ``e1 m=4 λ=0.6`` or ``the original shader``."""
        if self.part is not None:
            return self.part.describe()
        return f"{self.node} Δn={self.period}" if self.node is not None else "the original shader"

    def png(self, name: str) -> bytes:
        """One image as PNG bytes (``KeyError`` for an image this choice does not have)."""
        return png_bytes(self.arrays[name])

    def uri(self, name: str) -> str:
        return data_uri(self.png(name))

    def caption(self, name: str) -> str:
        base = self.captions.get(name, CAPTIONS[name])
        if name == "error_map" and self.error_scale is not None:
            return f"{base} (white = {self.error_scale:.3g})"
        if name == "payload" and self.payload_ranges:
            lo = min(r[0] for r in self.payload_ranges)
            hi = max(r[1] for r in self.payload_ranges)
            return f"{base} ({lo:.3g}…{hi:.3g}, stretched)"
        return base


class FrameShots:
    """Renders :class:`ChoiceImages` for a profile's choices; the shader is loaded and analysed
    once (pass ``work``, a :class:`~rrcache.pipeline.ShaderWork`, when you have it), the original
    frames and the images of each (node, Δn) and each amortized option are kept."""

    def __init__(self, profile, work=None, max_width: int = MAX_WIDTH):
        from rrcache.session import load_session

        self.profile = profile
        if work is None:  # a profile read from its folder: what it names is checked first
            from rrcache.profiles.inputs import load_session_of

            self.session = load_session_of(profile)
        else:
            self.session = load_session(profile.session)
        if work is None:
            from rrcache.pipeline import load_for_session

            work = load_for_session(profile.shader, self.session, profile.defines,
                                    getattr(profile, "include_dirs", ()), vertex=profile.vertex)
            work.filter = getattr(profile, "filter", work.filter)
        self.work = work
        self.size = image_size(self.session.resolution, max_width)
        self._originals: dict = {}
        self._images: dict = {}
        self._variants: dict = {}

    def variant(self, node: str):
        """The compiled variant caching ``node`` (one per node: the refresh period is the runtime's)."""
        if node not in self._variants:
            from rrcache.pipeline import variant_for

            self._variants[node] = variant_for(self.work, node, self.profile.algorithm)
        return self._variants[node]

    def selection_variant(self, selection):
        """``(variant, period)`` of any selection with parts (its ``algorithm``, else the profile's;
        :func:`rrcache.pipeline.variant_for_selection`), compiled once per kind of choice."""
        algorithm = selection.algorithm or self.profile.algorithm
        key = (selection.key, algorithm)
        if key not in self._variants:
            if selection.kind == "cache":
                self._variants[key] = (self.variant(selection.node), int(selection.period))
            else:
                from rrcache.pipeline import variant_for_selection

                self._variants[key] = variant_for_selection(self.work, selection.replace(algorithm=algorithm))
        return self._variants[key]

    def selection_images(self, selection) -> ChoiceImages:
        """The images of a selection: the original (no part), one cached node (kind ``cache`` or
        ``adaptive``, as :meth:`images`) or an amortized estimator (kind ``amortize``). Several
        nodes at once have no images here: RRCacheError."""
        if not selection.parts:
            return self.images(None, None)
        if selection.kind == "amortize":
            key = (selection.key, selection.algorithm or self.profile.algorithm)
            if key not in self._images:
                self._images[key] = self._render_amortized(selection)
            return self._images[key]
        if selection.multi:
            from rrcache.errors import RRCacheError

            raise RRCacheError(f"no frames for a selection of several nodes ({selection.describe()})", "selection",
                               hint="show one node's frames with FrameShots.images(node, period)")
        return self.images(selection.node, selection.period)

    def frame_for(self, period: Optional[int]) -> int:
        """The frame shown for a refresh period: Δn + 2 frames into the session (at most its last)."""
        return min(int(self.session.frames) - 1, int(period or 0) + 2)

    def original(self, frame: int):
        """The original shader's :class:`~rrcache.harness.renderer.FrameResult` at ``frame``."""
        if frame not in self._originals:
            from rrcache.harness.renderer import Renderer

            with Renderer(self.work.prepared, self.session, self.size) as renderer:
                self._originals[frame] = renderer.render_frame(frame)
        return self._originals[frame]

    def images(self, node: Optional[str], period: Optional[int]) -> ChoiceImages:
        """The images of caching ``node`` every ``period`` frames (node None: the original)."""
        key = (node, None if node is None else int(period))
        if key not in self._images:
            self._images[key] = self._render(*key)
        return self._images[key]

    def _render(self, node: Optional[str], period: Optional[int]) -> ChoiceImages:
        frame = self.frame_for(period)
        ref = self.original(frame)
        out = ChoiceImages(node, period, frame, self.size)
        out.arrays["original"] = ref.image[..., :3]
        if node is None:
            return out
        return self._cached_run(out, self.variant(node), period, ref)

    def _render_amortized(self, selection) -> ChoiceImages:
        part = selection.parts[0]
        variant, period = self.selection_variant(selection)
        info = getattr(variant, "amortized", None) or {}
        frame = settle_frame(self.session.frames, info.get("cycle", 1), part.blend)
        out = ChoiceImages(None, None, frame, self.size, part=part)
        n, m = info.get("of"), part.samples
        out.captions["cached"] = f"amortized: {m} of {n} terms per frame"
        if part.history == "slots":
            shown = min(3, variant.components)
            sums = f"{n // m} subset sums" if n else "subset sums"
            out.captions["payload"] = f"the {sums} (slots; {shown} channel(s) shown)"
        else:
            out.captions["payload"] = "running estimate (blend)"
        ref = self.original(frame)
        out.arrays["original"] = ref.image[..., :3]
        return self._cached_run(out, variant, period, ref)

    def _cached_run(self, out: ChoiceImages, variant, period, ref) -> ChoiceImages:
        """Render ``variant`` from frame 0 to ``out.frame`` and fill in ``out``'s cached images."""
        from rrcache.harness.cached import CachedRenderer
        from rrcache.harness.metrics import mean_l2

        frame = out.frame
        with CachedRenderer(variant, self.session, self.work.prepared, self.size, period=period,
                            hit_maps=True, keep_payload=True, **self.profile.settings.cache_options()) as cached:
            for index in range(frame + 1):
                got = cached.render_frame(index)
        mask = ref.mask
        out.arrays["cached"] = got.image[..., :3]
        out.arrays["error_map"], out.error_scale = error_map(got.image, ref.image, mask)
        out.error = float(mean_l2(got.image, ref.image, mask)[0])
        out.arrays["payload"], out.payload_ranges = payload_image(got.payload, variant.components, got.mask)
        if got.hit_map is not None:
            out.arrays["hit_map"] = hit_map_image(got.hit_map, got.mask)
            out.hit_rate = got.hits / got.covered_pixels if got.covered_pixels else 0.0
        return out
