"""The fourth paper scene: PCF shadows in a temple of columns (shaders/pcf_shadows.glsl,
sessions/temple.json; Nehab et al. 2007 §7.3). Tiny renders only."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rrcache.harness import render
from rrcache.session import load_session

ROOT = Path(__file__).resolve().parent.parent
SHADER = str(ROOT / "shaders" / "pcf_shadows.glsl")
TINY = (80, 60)


def test_the_session_is_a_150_frame_flyby_with_a_shadow_map():
    session = load_session(ROOT / "sessions" / "temple.json")
    assert tuple(session.resolution) == (640, 480) and session.frames == 150
    assert session.shadow_map is not None and session.shadow_map.size == 1024
    assert not np.allclose(session.camera_at(0).eye, session.camera_at(149).eye)
    names = [o.name for o in session.objects]
    assert sum(n.startswith("column") for n in names) >= 8 and "floor" in names
    assert all(o.source.startswith("procedural:") for o in session.objects)


def test_more_taps_converge_to_the_reference(gl_ctx):
    """1, 16 and 64 taps against 256: the error shrinks as taps are added (the shadows are there
    and the reference is what the estimates approach)."""
    session = load_session(ROOT / "sessions" / "temple.json")
    images = {n: render(SHADER, session, frames=[40], resolution=TINY, defines={"PCF_SAMPLES": str(n)}).frames[0]
              for n in (1, 16, 64, 256)}
    ref = images[256]
    assert ref.covered_pixels > 0.5 * TINY[0] * TINY[1]
    errors = {n: float(np.abs(images[n].image - ref.image)[ref.mask].mean()) for n in (1, 16, 64)}
    assert errors[1] > errors[16] > errors[64] > 0
    # some pixels are in shadow, some lit
    luminance = ref.image[..., :3].mean(axis=-1)[ref.mask]
    assert luminance.min() < 0.5 * luminance.max()
