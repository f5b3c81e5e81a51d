"""Frames of a profile's choices as the report and the notebooks show them: the original, the cached
variant, the error map, the payload and the hit/miss map of one frame (:class:`ChoiceImages`),
the image helpers, and :func:`read_frames`, which reads the frames the profiler rendered into the
profile folder (:mod:`rrcache.profiler.frames` renders them: the report renders nothing).

>>> frames = read_frames("demo.rrprofile")                                 # doctest: +SKIP
>>> frames["e1"].png("hit_map")[:4], frames["e1"].what                     # doctest: +SKIP
(b'\\x89PNG', 'n932 Δn=16')
"""
from __future__ import annotations

import base64
import io
import json
import os
from pathlib import Path
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from rrcache.budgets import budget
from rrcache.errors import RRCacheError
from rrcache.files import Refused, read_file

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


from rrcache.kinds.amortize import SETTLED, settle_frame  # noqa: F401,E402 (re-exported: the amortize kind's frame)


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
    #: what the images show, in words (from a profile folder, where there is no part to ask)
    description: Optional[str] = None
    #: image name -> its PNG file (from a profile folder: :func:`read_frames`)
    files: dict = field(default_factory=dict)
    #: image name -> the PNG bytes read from that file (by :mod:`rrcache.files`' rule)
    blobs: dict = field(default_factory=dict)

    @property
    def cached(self) -> bool:
        """Whether these are a variant's images (not the original shader's alone)."""
        return self.node is not None or self.part is not None or getattr(self, "was_cached", False)

    @property
    def what(self) -> str:
        """``n12 Δn=16``, ``e1 m=4 λ=0.6`` or ``the original shader``."""
        if self.description is not None:
            return self.description
        if self.part is not None:
            return self.part.describe()
        return f"{self.node} Δn={self.period}" if self.node is not None else "the original shader"

    def png(self, name: str) -> bytes:
        """One image as PNG bytes (``KeyError`` for an image this choice does not have): its file
        as written, or the array encoded."""
        if name in self.blobs:
            return self.blobs[name]
        return png_bytes(self.arrays[name])

    def to_json(self, files: dict) -> dict:
        """The record ``frames.json`` keeps (``files``: image name → path relative to the folder)."""
        return {"node": self.node, "period": self.period, "frame": int(self.frame), "size": list(self.size),
                "error": float(self.error), "hit_rate": None if self.hit_rate is None else float(self.hit_rate),
                "error_scale": None if self.error_scale is None else float(self.error_scale),
                "payload_ranges": [list(map(float, r)) for r in self.payload_ranges], "captions": dict(self.captions),
                "cached": self.cached, "what": self.what, "images": dict(files)}

    @classmethod
    def from_json(cls, record: dict, folder) -> "ChoiceImages":
        """The images of a ``frames.json`` record, their PNG files in ``folder``, each read by
        :mod:`rrcache.files`' rule inside the profile folder (``frames.json`` may have been
        edited: a file it names elsewhere, or through a link out, is refused, never read)."""
        from PIL import Image

        files = {name: Path(folder) / rel for name, rel in record.get("images", {}).items()}
        arrays, blobs = {}, {}
        for name, path in files.items():
            blobs[name] = _folder_file(folder, path, budget.asset_bytes)
            with Image.open(io.BytesIO(blobs[name])) as im:
                arrays[name] = np.asarray(im.convert("RGB"), dtype=np.float32) / 255.0
        out = cls(record.get("node"), record.get("period"), int(record["frame"]), tuple(record["size"]), arrays,
                  float(record.get("error") or 0.0), record.get("hit_rate"), record.get("error_scale"),
                  [tuple(r) for r in record.get("payload_ranges", [])], None, dict(record.get("captions", {})),
                  record.get("what"), files, blobs)
        out.was_cached = bool(record.get("cached"))
        return out

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


def _folder_file(folder, path, limit: int) -> bytes:
    """The bytes of ``path``, a file of the profile folder ``folder``, read by :mod:`rrcache.files`'
    rule confined to that folder; a refusal is an :class:`RRCacheError` naming the file."""
    try:
        return read_file(path, limit, [os.path.realpath(folder)]).data
    except Refused as err:
        said = f"resolves to {err.real}, outside the profile's folder" if err.kind == "outside" else err.reason
        raise RRCacheError(f"a frame file of the profile {said}; nothing of it was read", str(path),
                           hint="frames/frames.json was damaged or edited; run 'rrcache profile' again") from None


#: where the profiler keeps the report's frames in a profile folder, and their record
FRAMES_DIR = "frames"
FRAMES_JSON = "frames.json"


def read_frames(folder) -> dict:
    """Label → :class:`ChoiceImages` of the frames the profiler rendered into the profile folder
    ``folder`` (:func:`rrcache.profiler.frames.write_frames`); empty when it has none."""
    path = Path(folder) / FRAMES_DIR / FRAMES_JSON
    if not path.exists():
        return {}
    data = json.loads(_folder_file(folder, path, budget.document_bytes))
    return {label: ChoiceImages.from_json(record, Path(folder)) for label, record in data.get("selections", {}).items()}
