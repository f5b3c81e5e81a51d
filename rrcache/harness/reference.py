"""Reference frames: the original shader's images, rendered once and reused.

Every variant is compared with the original shader on the same frames, many times over a
profile. :class:`ReferenceCache` keys a frame by (shader hash, session hash, resolution, frame
index), keeps it in memory and, when given a directory, also as ``.npy`` files (image and coverage
mask) so that a later run reuses them.

>>> import tempfile
>>> from rrcache.compiler.prepared import prepare_file
>>> from rrcache.session import load_session
>>> session = load_session("sessions/marble.json")
>>> prepared = prepare_file("shaders/glslviewer_basic.glsl", session)
>>> refs = tempfile.mkdtemp()
>>> cache = ReferenceCache(refs)
>>> frames = cache.frames(prepared, session, [0, 1, 2], resolution=(32, 24))
>>> cache.rendered, len(frames)
(3, 3)
>>> again = ReferenceCache(refs)          # a later run: read from the files, nothing drawn
>>> _ = again.frames(prepared, session, [0, 1, 2], resolution=(32, 24))
>>> again.rendered
0
"""
from __future__ import annotations

import io
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Optional

import numpy as np

from rrcache.atomic import write_bytes
from rrcache.files import read_bytes
from rrcache.compiler.prepared import PreparedShader
from rrcache.harness.renderer import Renderer


@dataclass(frozen=True)
class ReferenceFrame:
    """A reference image (H×W×4 float32, row 0 = top) and its coverage mask (H×W bool)."""

    index: int
    image: np.ndarray
    mask: np.ndarray

    @property
    def covered_pixels(self) -> int:
        return int(self.mask.sum())


class ReferenceCache:
    """Renders reference frames on demand and keeps them (memory, plus ``directory`` if given).

    ``rendered`` counts the frames actually drawn (not found in memory or on disk).
    """

    def __init__(self, directory: Optional[os.PathLike | str] = None):
        self.directory = Path(directory) if directory is not None else None
        self._memory: dict[tuple, ReferenceFrame] = {}
        self.rendered = 0

    @staticmethod
    def key(prepared: PreparedShader, session, resolution: tuple[int, int], index: int) -> tuple:
        """The cache key of one frame."""
        return (prepared.hash, session.hash, (int(resolution[0]), int(resolution[1])), int(index))

    def _file_stem(self, key: tuple) -> Path:
        shader_hash, session_hash, (w, h), index = key
        return self.directory / f"{shader_hash[:24]}-{session_hash[:24]}-{w}x{h}-{index:05d}"

    def _load(self, key: tuple) -> Optional[ReferenceFrame]:
        if self.directory is None:
            return None
        stem = self._file_stem(key)
        image_path, mask_path = stem.with_suffix(".image.npy"), stem.with_suffix(".mask.npy")
        if not (image_path.exists() and mask_path.exists()):
            return None
        try:  # by rrcache.files' rule, pickles refused: a cache file is data, never code
            image, mask = (np.load(io.BytesIO(read_bytes(p, limit=None)), allow_pickle=False)
                           for p in (image_path, mask_path))
        except (OSError, ValueError):
            return None  # a damaged file: render again and overwrite it
        w, h = key[2]
        if image.shape != (h, w, 4) or mask.shape != (h, w):
            return None
        return ReferenceFrame(key[3], image.astype(np.float32), mask.astype(bool))

    def _store(self, key: tuple, frame: ReferenceFrame) -> None:
        self._memory[key] = frame
        if self.directory is None:
            return
        stem = self._file_stem(key)
        for suffix, array in ((".image.npy", frame.image), (".mask.npy", frame.mask)):
            buffer = io.BytesIO()
            np.save(buffer, array)
            write_bytes(stem.with_suffix(suffix), buffer.getvalue())

    def frames(self, prepared: PreparedShader, session, indices: Iterable[int],
               resolution: Optional[tuple[int, int]] = None) -> list[ReferenceFrame]:
        """The reference frames for ``indices`` (in that order), rendering only the missing ones
        with a single :class:`~rrcache.harness.renderer.Renderer`."""
        size = tuple(int(v) for v in (resolution or session.resolution))
        indices = [int(i) for i in indices]
        found: dict[int, ReferenceFrame] = {}
        for index in indices:
            key = self.key(prepared, session, size, index)
            frame = self._memory.get(key) or self._load(key)
            if frame is not None:
                self._memory[key] = frame
                found[index] = frame
        missing = [i for i in dict.fromkeys(indices) if i not in found]
        if missing:
            with Renderer(prepared, session, size) as renderer:
                for result in renderer.frames(missing):
                    frame = ReferenceFrame(result.index, result.image, result.mask)
                    self._store(self.key(prepared, session, size, result.index), frame)
                    found[result.index] = frame
                    self.rendered += 1
        return [found[i] for i in indices]

    def frame(self, prepared: PreparedShader, session, index: int,
              resolution: Optional[tuple[int, int]] = None) -> ReferenceFrame:
        """One reference frame (see :meth:`frames`)."""
        return self.frames(prepared, session, [index], resolution)[0]

    def clear_memory(self) -> None:
        """Forget the frames held in memory (files on disk stay)."""
        self._memory.clear()
