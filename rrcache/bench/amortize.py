"""Amortized sampling measured: an estimator at ``m`` of ``N`` samples per frame and blend ``λ``
against the original, both against a many-sample reference (Nehab et al. 2007 §6, §7.3).

:func:`run` renders the session's frames with the original shader and with the amortized
variant, alternating frame by frame so that machine noise touches both alike (the shadow-map
pass, when the session has one, is inside both measured frames), ``repeats`` times over the same
frames. The *reference* is the shader loaded with ``reference_defines`` (for
``shaders/pcf_shadows.glsl``: ``PCF_SAMPLES=256``), rendered untimed every ``error_every``-th
frame of the first repeat (with no defines: the original itself, the error rrcache's profiles
measure); the error of each image against it is the paper's (mean per-pixel RGB
L2 over covered pixels, :func:`rrcache.harness.metrics.mean_l2`). The first frame is left out of
the summary (the cache is empty there, so the amortized frame is the original).

The speed-up of a repeat is the ratio of the median frame times (wall time, and the process's
CPU time over the same span: on a shared machine the wall time of llvmpipe's frames is inflated
by other processes, the CPU time much less); the result gives the median over repeats and their
range.

>>> result = run("shaders/pcf_shadows.glsl", "sessions/temple.json", "e1", samples=4,
...              blend=0.6, reference_defines={"PCF_SAMPLES": "256"}, frames=30)  # doctest: +SKIP
>>> result.summary()["speedup"] > 1                                               # doctest: +SKIP
True
"""
from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Callable, Mapping, Optional

import numpy as np

from rrcache.bench.amortize_sheet import write_sheet
from rrcache.compiler.amortize import instance_amortized
from rrcache.harness.cached import CachedRenderer
from rrcache.harness.metrics import mean_l2, psnr
from rrcache.compiler.prepared import prepare_file
from rrcache.harness.renderer import Renderer, frame_indices
from rrcache.pipeline import load_for_session
from rrcache.session import load_session


@dataclass
class AmortizedRun:
    """Per-frame figures of one run: ``errors`` (frame → (original's, amortized's) error against
    the reference), and per repeat the frame times ``original_ms`` / ``amortized_ms``."""

    estimator: str
    samples: int
    phase: str
    history: str
    total: int
    blend: float
    algorithm: str
    frames: list[int]
    resolution: tuple[int, int]
    errors: dict[int, tuple[float, float]] = field(default_factory=dict)
    psnrs: dict[int, tuple[float, float]] = field(default_factory=dict)
    original_ms: list[list[float]] = field(default_factory=list)
    amortized_ms: list[list[float]] = field(default_factory=list)
    original_cpu_ms: list[list[float]] = field(default_factory=list)
    amortized_cpu_ms: list[list[float]] = field(default_factory=list)
    reference_defines: dict = field(default_factory=dict)
    filter: str = "bilinear"
    #: the payload format the amortized cache used (``u8``: 8-bit, rrcache.compiler.payload_encoding;
    #: a request that did not fit falls back to ``f4``, and ``payload_note`` says why)
    payload: str = "f4"
    payload_note: Optional[str] = None

    def _steady(self, values: list) -> list:
        return values[1:] or values

    def speedups(self) -> list[float]:
        """The speed-up of each repeat: median original ms / median amortized ms (first frame out)."""
        return [statistics.median(self._steady(o)) / statistics.median(self._steady(a))
                for o, a in zip(self.original_ms, self.amortized_ms)]

    def cpu_speedups(self) -> list[float]:
        """As :meth:`speedups` with the process CPU time of the frames (less sensitive to other
        processes on a shared machine than wall time)."""
        return [statistics.median(self._steady(o)) / statistics.median(self._steady(a))
                for o, a in zip(self.original_cpu_ms, self.amortized_cpu_ms)]

    def summary(self) -> dict:
        """Median speed-up over repeats with its range, median frame times, mean errors."""
        rows = [(f, e) for f, e in sorted(self.errors.items()) if f != self.frames[0]] or sorted(self.errors.items())
        speedups = self.speedups()
        cpu = self.cpu_speedups()
        return {
            "estimator": self.estimator, "samples": self.samples, "of": self.total, "lambda": self.blend,
            "phase": self.phase, "history": self.history, "filter": self.filter, "payload": self.payload,
            **({"payload_note": self.payload_note} if self.payload_note else {}), "algorithm": self.algorithm, "frames": len(self.frames), "resolution": list(self.resolution),
            "repeats": len(speedups), "speedup": statistics.median(speedups),
            "speedup_range": [min(speedups), max(speedups)],
            "original_ms": statistics.median(statistics.median(self._steady(o)) for o in self.original_ms),
            "amortized_ms": statistics.median(statistics.median(self._steady(a)) for a in self.amortized_ms),
            "cpu_speedup": statistics.median(cpu), "cpu_speedup_range": [min(cpu), max(cpu)],
            "original_cpu_ms": statistics.median(statistics.median(self._steady(o)) for o in self.original_cpu_ms),
            "amortized_cpu_ms": statistics.median(statistics.median(self._steady(a)) for a in self.amortized_cpu_ms),
            "error_frames": len(rows),
            "original_error": float(np.mean([e[0] for _, e in rows])),
            "amortized_error": float(np.mean([e[1] for _, e in rows])),
            # PSNR against the reference (capped at 100 dB where an image equals it), mean over frames
            "original_psnr": float(np.mean([min(self.psnrs[f][0], 100.0) for f, _ in rows])),
            "amortized_psnr": float(np.mean([min(self.psnrs[f][1], 100.0) for f, _ in rows])),
            "reference_defines": dict(self.reference_defines),
        }


def run(shader, session, estimator: str, samples: int, blend: float, reference_defines: Mapping[str, str],
        frames=None, repeats: int = 3, error_every: int = 5, algorithm: str = "two-pass", phase: str = "frame",
        history: str = "blend", filter: str = "bilinear", payload: str = "f4",
        resolution: Optional[tuple[int, int]] = None, defines: Optional[Mapping[str, str]] = None,
        on_frame: Optional[Callable[[int, int, object, object, object], None]] = None) -> AmortizedRun:
    """Measure (see the module doc). ``session`` is a path or a loaded session; ``frames`` as
    :func:`rrcache.harness.renderer.frame_indices` (consecutive); ``on_frame(repeat, index,
    original, amortized, reference_or_None)`` is called per frame."""
    if isinstance(session, str) or hasattr(session, "__fspath__"):
        session = load_session(session)
    work = load_for_session(shader, session, defines)
    variant = instance_amortized(work.shader, estimator, algorithm, samples=samples, blend=blend, phase=phase,
                                 history=history, filter=filter, payload_dtype=payload, vertex=work.vertex)
    reference = prepare_file(shader, session, {**dict(defines or {}), **dict(reference_defines)})
    indices = frame_indices(session, frames)
    amort = variant.amortized
    out = AmortizedRun(estimator, samples, phase, history, amort["of"], float(blend), algorithm, indices,
                       tuple(resolution or session.resolution), reference_defines=dict(reference_defines),
                       filter=filter)
    for repeat in range(repeats):
        o_ms, a_ms, o_cpu, a_cpu = [], [], [], []
        with Renderer(work.prepared, session, resolution) as original, \
                CachedRenderer(variant, session, work.prepared, resolution, period=2 ** 30) as cached, \
                Renderer(reference, session, resolution) as ref_renderer:
            for k, index in enumerate(indices):
                got_o = original.render_frame(index)
                got_a = cached.render_frame(index)
                o_ms.append(got_o.ms)
                a_ms.append(got_a.ms)
                o_cpu.append(got_o.cpu_ms)
                a_cpu.append(got_a.cpu_ms)
                ref = None
                if repeat == 0 and (k % error_every == 0 or k == len(indices) - 1):
                    ref = ref_renderer.render_frame(index)
                    e_o, _ = mean_l2(got_o.image, ref.image, ref.mask)
                    e_a, _ = mean_l2(got_a.image, ref.image, ref.mask)
                    out.errors[index] = (float(e_o), float(e_a))
                    out.psnrs[index] = (float(psnr(got_o.image, ref.image)), float(psnr(got_a.image, ref.image)))
                if on_frame is not None:
                    on_frame(repeat, index, got_o, got_a, ref)
            out.payload, out.payload_note = cached.payload_dtype, cached.payload_note
        out.original_ms.append(o_ms)
        out.amortized_ms.append(a_ms)
        out.original_cpu_ms.append(o_cpu)
        out.amortized_cpu_ms.append(a_cpu)
    return out


def write_images(out_dir: str, shader, session, result: AmortizedRun, kept: dict,
                 also: Optional[Mapping[str, str]] = None) -> dict:
    """PNGs of the last frame of the first repeat: ``original.png``, ``amortized.png`` (from
    ``kept``), ``reference.png``, ``also.png`` (the shader with the ``also`` defines) and ``comparison.png``
    (all of them labelled with their error against the reference, whole and magnified:
    :func:`rrcache.bench.amortize_sheet.write_sheet`); returns name → path."""
    import os

    from rrcache.harness.images import write_image

    if isinstance(session, str) or hasattr(session, "__fspath__"):
        session = load_session(session)
    index = result.frames[-1]
    paths = {}
    renders = {"reference": result.reference_defines}
    if also:
        renders["also"] = dict(also)
    mask = None
    for name, defines in renders.items():
        with Renderer(prepare_file(shader, session, defines), session, result.resolution) as r:
            got = r.render_frame(index)
            kept[name] = got.image
            mask = got.mask if name == "reference" else mask
    for name, image in kept.items():
        path = os.path.join(out_dir, f"{name}.png")
        write_image(path, image)
        paths[name] = path
    if {"original", "amortized"} <= set(kept):
        panels = [(_defines_label(also), kept["also"])] if "also" in kept else []
        panels += [(f"original ({result.total} of {result.total})", kept["original"]),
                   (f"amortized {result.samples} of {result.total}, λ = {result.blend:g}, {result.history}"
                    + ("" if result.filter == "bilinear" else f", {result.filter}")
                    + (", 8-bit" if result.payload == "u8" else ""),
                    kept["amortized"])]
        path = os.path.join(out_dir, "comparison.png")
        write_sheet(path, panels, kept["reference"], mask, window_of=len(panels) - 2,
                    title=f"frame {index}, against the reference ({_defines_label(result.reference_defines)}); "
                          "below: the window where the original differs most from it")
        paths["comparison"] = path
    return paths


def _defines_label(defines: Mapping[str, str]) -> str:
    return ", ".join(f"{k}={v}" for k, v in sorted(dict(defines).items())) or "the original"
