"""The two Trashcan variants docs/refresh_bound.md measures, made from shaders/trashcan.glsl (each
edit must match, so a changed shader fails here instead of measuring something else):

- ``stale.glsl``: the 24 outer samples shaded from the camera ``STALE_DEG`` degrees earlier on the
  session's orbit (1 degree a frame; ``KEEP_CENTRE`` false makes the centre stale too): their
  staleness, with no reprojection and no resampling.
- ``frozen.glsl``: the view and the key light frozen at frame 0's, so a surface point's colour never
  changes: caching it measures the reprojection's resampling alone.

    PYTHONPATH=. python docs/refresh_bound/variants.py OUT_DIR
"""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
CAMERA_0 = "vec3(0.0, 1.62, 2.5)"  # sessions/trashcan.json's orbit at frame 0
LIGHT_0 = "vec3(2.83, 3.6, 2.83)"

STALE = [
    ("uniform float u_exposure;", """uniform float u_exposure;
#ifndef KEEP_CENTRE
#define KEEP_CENTRE true
#endif
#ifndef STALE_DEG
#define STALE_DEG 0.0
#endif
// the camera STALE_DEG degrees earlier on the orbit about the can's axis
vec3 staleCamera() {
    vec3 c = vec3(0.0, 0.62, 0.0);
    vec3 d = u_camera - c;
    float k = radians(STALE_DEG);
    return c + vec3(d.x * cos(k) - d.z * sin(k), d.y, d.z * cos(k) + d.x * sin(k));
}"""),
    ("            vec3 R = reflect(-V, n);",
     """            vec3 Vs = (i == 2 && j == 2 && KEEP_CENTRE) ? V : normalize(staleCamera() - P);
            vec3 R = reflect(-Vs, n);"""),
]
FROZEN = [
    ("    vec3 V = normalize(u_camera - P);", f"    vec3 V = normalize({CAMERA_0} - P);"),
    ("    vec3 L = normalize(u_light - P);", f"    vec3 L = normalize({LIGHT_0} - P);"),
    ("float footprint = distance(u_camera, position)", f"float footprint = distance({CAMERA_0}, position)"),
]


def variant(edits) -> str:
    text = (ROOT / "shaders" / "trashcan.glsl").read_text()
    for old, new in edits:
        if text.count(old) != 1:
            raise SystemExit(f"shaders/trashcan.glsl: expected one {old.strip()!r}; update {__file__}")
        text = text.replace(old, new)
    return text


def write(out_dir) -> tuple[Path, Path]:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stale, frozen = out / "stale.glsl", out / "frozen.glsl"
    stale.write_text(variant(STALE))
    frozen.write_text(variant(FROZEN))
    return stale, frozen


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    for path in write(sys.argv[1]):
        print(path)
