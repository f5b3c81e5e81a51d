"""Running a side-by-side comparison ``--repeats`` times with progress and ``--out`` images: what
``rrcache render`` does for a cached variant (``--node``, ``--level``) and for the render cache
(``--method render-cache``) alike.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Optional

from rrcache.cli.progress import Reporter
from rrcache.harness.images import write_image
from rrcache.harness.renderer import frame_indices


def frames_and_folder(loaded, frame_count: Optional[int], out_dir) -> tuple[list, Optional[Path]]:
    """The frames a render of the session ``loaded`` runs (its first ``frame_count``; None: all)
    and its ``--out`` folder (made; None when not given)."""
    out = Path(out_dir) if out_dir else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    return frame_indices(loaded, frame_count), out


def run_repeats(compare: Callable, frames: int, repeats: int, out: Optional[Path], label: str, err_console,
                quiet: bool) -> list:
    """``compare(on_frame)`` ``repeats`` times (each a whole side-by-side run over ``frames``
    frames, returning its comparison); the first run's frames are written to ``out``
    (``frame_NNNN.exr/png`` and ``original_NNNN.png``) when given. Returns the comparisons."""
    runs = []
    with Reporter(err_console, quiet=quiet or frames * repeats < 2) as reporter:
        for repeat in range(repeats):
            count = {"n": 0}

            def done(row, got, ref, repeat=repeat):
                if out is not None and repeat == 0:
                    stem = out / f"frame_{row.index:04d}"
                    write_image(stem.with_suffix(".exr"), got.image)
                    write_image(stem.with_suffix(".png"), got.image)
                    write_image(out / f"original_{row.index:04d}.png", ref.image)
                count["n"] += 1
                reporter.update(f"[{repeat + 1}/{repeats}] {label} beside the original", count["n"], frames)

            runs.append(compare(done))
    return runs
