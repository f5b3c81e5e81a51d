"""The report's frames, rendered by the profiler into the profile folder: :func:`write_frames`.

For each selection with frames (its kind of choice says: :attr:`rrcache.kinds.base.Kind.has_frames`)
:class:`FrameShots` renders, for real (the harness and the cache runtime, each variant from the
compile cache), the original, the cached variant, the error map, the payload and the hit/miss map
of the frame its kind shows (:meth:`rrcache.kinds.base.Kind.shown_frame`: Δn + 2 frames into the
session for a cached node, long enough for the cache's steady state; an amortized loop after its
cycle of subsets and its blend's memory), at a modest resolution. :func:`write_frames` writes them
as PNG files under ``frames/`` with ``frames/frames.json``, which the report reads
(:func:`rrcache.report.images.read_frames`): the report itself renders nothing and needs no GL
context.

>>> shots = FrameShots(load_profile("demo.rrprofile"))                     # doctest: +SKIP
>>> shots.images("n932", 16).png("hit_map")[:4]                            # doctest: +SKIP
b'\\x89PNG'
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

from rrcache.atomic import OutputFolder
from rrcache.report.images import (CAPTIONS, FRAMES_DIR, FRAMES_JSON, MAX_WIDTH, ChoiceImages, error_map,
                                   hit_map_image, image_size, payload_image)


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
                                    getattr(profile, "include_dirs", ()), vertex=profile.vertex,
                                    term_scores=getattr(profile, "term_scores", None))
            work.filter = getattr(profile, "filter", work.filter)
        self.work = work
        self.size = image_size(self.session.resolution, max_width)
        self._originals: dict = {}
        self._images: dict = {}
        self._variants: dict = {}

    def variant(self, node: str):
        """The compiled variant caching ``node`` (one per node: the refresh period is the runtime's)."""
        from rrcache.pipeline import variant_for

        return variant_for(self.work, node, self.profile.algorithm)

    def selection_variant(self, selection):
        """``(variant, period)`` of any selection with parts (its ``algorithm``, else the profile's;
        :func:`rrcache.pipeline.variant_for_selection`, compiled once: :func:`rrcache.kinds.compile`)."""
        from rrcache.pipeline import variant_for_selection

        algorithm = selection.algorithm or self.profile.algorithm
        return variant_for_selection(self.work, selection.replace(algorithm=algorithm),
                                     **self.profile.settings.cache_options())

    def selection_images(self, selection) -> ChoiceImages:
        """The images of a selection: the original (no part), else of its kind of choice at the
        frame the kind shows (:meth:`rrcache.kinds.base.Kind.shown_frame`). A kind without frames
        (several nodes at once) has none here: RRCacheError."""
        if not selection.parts:
            return self.images(None, None)
        kind = selection.choice
        if not kind.has_frames:
            from rrcache.errors import RRCacheError

            raise RRCacheError(f"no frames for a selection of {kind.title} ({selection.describe()})", "selection",
                               hint="show one node's frames with FrameShots.images(node, period)")
        key = (selection.key, selection.algorithm or self.profile.algorithm)
        if key not in self._images:
            self._images[key] = self._render_selection(selection)
        return self._images[key]

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
        if node is None:
            key = (None, None)
            if key not in self._images:
                frame = self.frame_for(None)
                out = ChoiceImages(None, None, frame, self.size)
                out.arrays["original"] = self.original(frame).image[..., :3]
                self._images[key] = out
            return self._images[key]
        from rrcache.selection import CachedNode, Selection

        return self.selection_images(Selection((CachedNode(node, int(period)),), 0.0, float("nan"), 1.0))

    def _render_selection(self, selection) -> ChoiceImages:
        kind = selection.choice
        variant, period = self.selection_variant(selection)
        frame = kind.shown_frame(selection, variant, self.session.frames)
        single = selection.node if len(selection.parts) == 1 and hasattr(selection.parts[0], "node") else None
        part = None if single is not None else selection.parts[0]
        out = ChoiceImages(single, selection.period if single is not None else None, frame, self.size, part=part)
        out.captions.update(kind.payload_captions(selection, variant))
        ref = self.original(frame)
        out.arrays["original"] = ref.image[..., :3]
        return self._cached_run(out, variant, ref)

    def _cached_run(self, out: ChoiceImages, variant, ref) -> ChoiceImages:
        """Render ``variant`` (its spec: the selection's, whole) from frame 0 to ``out.frame`` and
        fill in ``out``'s cached images."""
        from rrcache.harness.cached import CachedRenderer
        from rrcache.harness.metrics import mean_l2

        frame = out.frame
        with CachedRenderer(variant, self.session, self.work.prepared, self.size, variant.spec,
                            hit_maps=True, keep_payload=True) as cached:
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


def write_frames(profile, out_dir, work=None, shots: Optional[FrameShots] = None) -> list[str]:
    """Render the frames of every selection of ``profile`` with frames (see the module docstring)
    into ``out_dir/frames/<label>/<image>.png`` and ``frames/frames.json``; returns the paths
    written. ``work``: the profiled shader already loaded."""
    shots = shots or FrameShots(profile, work)
    record, written = {}, []
    # by rrcache.atomic's rule: inside the profile folder, links refused, each file whole
    with OutputFolder(out_dir) as root, root.folder(FRAMES_DIR) as frames:
        for sel in profile.selections:
            if sel.parts and not sel.choice.has_frames:
                continue
            images = shots.selection_images(sel)
            files = {}
            with frames.folder(sel.label) as folder:
                folder.remove_files()
                for name in CAPTIONS:
                    if name in images.arrays:
                        written.append(folder.write_bytes(f"{name}.png", images.png(name)))
                        files[name] = f"{FRAMES_DIR}/{sel.label}/{name}.png"
            record[sel.label] = images.to_json(files)
        written.append(frames.write_text(FRAMES_JSON, json.dumps({"rrcache_frames": 1, "selections": record},
                                                                 indent=2) + "\n"))
    return written
