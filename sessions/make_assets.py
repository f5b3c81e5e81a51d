"""Generate the textures of the three example sessions (marble, trashcan, chess).

Run from anywhere: ``python sessions/make_assets.py``. The output is deterministic (fixed seeds,
no timestamps), so re-running it reproduces the committed files byte for byte. Written into
``sessions/textures/``:

- ``trashcan_normal.png``: 512x512 tangent-space normal map of the trashcan, tileable in both
  directions: embossed panels, horizontal ridges, a few dents and fine brushed-metal noise.
- ``studio_env.exr``: a 6x128x128 HDR studio environment (half-float EXR) as a 6:1 horizontal
  strip of cube faces in OpenGL order (+X -X +Y -Y +Z -Z) and orientation (row 0 of a face is
  its top, t = 0).
- ``chess_board.png``: 512x512 diffuse texture of the chess board (8x8 squares plus a border,
  wood grain), spanning the board's top face.
- ``perlin_permutation.exr`` / ``perlin_gradients.exr``: the tables of Perlin's improved noise
  for the marble shader (GPU Gems 2 ch. 26): a random permutation of 0..255 (256x1, one float
  channel) and Perlin's 12 cube-edge gradient directions padded to 16 (16x1 RGB), read exactly
  with ``texelFetch``.
- ``chess_discs.exr`` / ``chess_king_discs.exr``: Bunnell disc sets (RGBA32F, two texels per
  disc on one row: (position, area), (normal, 0)) for the board with the static pieces (world
  space) and for the king (king object space). They are built from ``chess.json`` itself: each
  ``revolve`` piece is re-tessellated coarsely (one disc per vertex, area one third of the
  adjacent triangles), the board's top face becomes a grid of discs. The disc counts are written
  back into ``chess.json`` (``u_numDiscs``, ``u_numKingDiscs``), and the script checks that
  ``u_kingOffset`` has the same keyframes as the king's translation.
"""
from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

SESSIONS = Path(__file__).resolve().parent
TEXTURES = SESSIONS / "textures"

NORMAL_MAP_SIZE = 512
ENV_FACE_SIZE = 128
BOARD_TEXTURE_SIZE = 512
# Slope scale of the trashcan's height field.
NORMAL_STRENGTH = 1.5
# Written into the EXR headers instead of the current time, so the files are reproducible.
FIXED_DATETIME = "2008:08:11 00:00:00"
# Coarse tessellation of the pieces for the disc sets.
DISC_SEGMENTS = 12
# Profile points closer than this (along the profile) to the last kept one are merged.
DISC_PROFILE_SPACING = 0.09
# The board's top face as a grid of BOARD_DISC_GRID^2 discs.
BOARD_DISC_GRID = 12
# The one piece that moves; its discs go into their own texture.
KING_NAME = "white_king"
# Pieces' bottom faces rest on the board and are never seen: no discs for them.
BOTTOM_EPSILON = 0.01


# --------------------------------------------------------------------------------------------
# Image output

def write_image(path: Path, pixels: np.ndarray, pixel_type: str) -> None:
    """Write an H x W x C array with OpenImageIO (``uint8``, ``half`` or ``float``)."""
    height, width, channels = pixels.shape
    spec = oiio.ImageSpec(width, height, channels, pixel_type)
    if path.suffix == ".exr":
        spec.attribute("compression", "zip")
        # A fixed date: the EXR writer would otherwise stamp the current time.
        spec.attribute("DateTime", FIXED_DATETIME)
    out = oiio.ImageOutput.create(str(path))
    if out is None or not out.open(str(path), spec):
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    data = pixels.astype(np.uint8 if pixel_type == "uint8" else np.float32)
    if not out.write_image(data):
        raise RuntimeError(f"cannot write {path}: {out.geterror()}")
    out.close()


# --------------------------------------------------------------------------------------------
# Periodic noise helpers

def periodic_value_noise(rng: np.random.Generator, size: int, cells: tuple[int, int]) -> np.ndarray:
    """Smooth value noise on a size x size grid, periodic, with cells[0] x cells[1] lattice cells
    (cells along x, cells along y)."""
    cx, cy = cells
    lattice = rng.random((cy, cx))
    x = np.arange(size) * cx / size
    y = np.arange(size) * cy / size
    x0 = np.floor(x).astype(int)
    y0 = np.floor(y).astype(int)
    fx = x - x0
    fy = y - y0
    fx = fx * fx * (3 - 2 * fx)
    fy = fy * fy * (3 - 2 * fy)
    x1 = (x0 + 1) % cx
    y1 = (y0 + 1) % cy
    a = lattice[np.ix_(y0, x0)]
    b = lattice[np.ix_(y0, x1)]
    c = lattice[np.ix_(y1, x0)]
    d = lattice[np.ix_(y1, x1)]
    top = a + (b - a) * fx[None, :]
    bottom = c + (d - c) * fx[None, :]
    return top + (bottom - top) * fy[:, None]


def periodic_fbm(rng: np.random.Generator, size: int, base_cells: tuple[int, int],
                 octaves: int) -> np.ndarray:
    """Sum of octaves of periodic value noise, centred on zero, roughly in [-1, 1]."""
    total = np.zeros((size, size))
    amplitude = 1.0
    norm = 0.0
    for octave in range(octaves):
        scale = 2 ** octave
        cells = (base_cells[0] * scale, base_cells[1] * scale)
        total += amplitude * (periodic_value_noise(rng, size, cells) * 2 - 1)
        norm += amplitude
        amplitude *= 0.5
    return total / norm


def smooth_box(t: np.ndarray, lo: float, hi: float, edge: float) -> np.ndarray:
    """1 inside [lo, hi], 0 outside, with smoothstep edges of width `edge`."""
    def smoothstep(e0, e1, x):
        s = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
        return s * s * (3 - 2 * s)
    return smoothstep(lo - edge, lo, t) * (1 - smoothstep(hi, hi + edge, t))


# --------------------------------------------------------------------------------------------
# Trashcan normal map

def trashcan_height(size: int, rng: np.random.Generator) -> np.ndarray:
    """Height field of one tile of the can's surface (x around the can, y along it)."""
    u = (np.arange(size) + 0.5) / size
    v = (np.arange(size) + 0.5) / size
    U, V = np.meshgrid(u, v)

    # Two embossed vertical panels per tile, rounded edges.
    panel_u = smooth_box((U * 2.0) % 1.0, 0.12, 0.88, 0.06)
    panel_v = smooth_box(V, 0.16, 0.84, 0.06)
    panels = 0.8 * panel_u * panel_v

    # Corrugation ridges between the panels (horizontal bands).
    ridges = 0.35 * (1 - panel_v) * np.cos(2 * math.pi * V * 6) ** 2

    # A few dents: periodic Gaussian pits of random size and depth.
    dents = np.zeros_like(U)
    for _ in range(10):
        cu, cv = rng.random(2)
        radius = 0.03 + 0.07 * rng.random()
        depth = 0.3 + 0.6 * rng.random()
        du = (U - cu + 0.5) % 1.0 - 0.5
        dv = (V - cv + 0.5) % 1.0 - 0.5
        dents -= depth * np.exp(-(du * du + dv * dv) / (2 * radius * radius))

    # Brushed metal: fine noise stretched along x (brushed around the can).
    brushed = 0.012 * periodic_fbm(rng, size, (4, 128), 2)
    # Broad, gentle waviness of thin sheet metal.
    waviness = 0.3 * periodic_fbm(rng, size, (3, 3), 3)
    return panels + ridges + dents + brushed + waviness


def normal_map_from_height(height: np.ndarray, strength: float) -> np.ndarray:
    """Tangent-space normals (encoded to [0, 255]) from a periodic height field."""
    size = height.shape[0]
    dhdx = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) * 0.5 * size / 64.0
    dhdy = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) * 0.5 * size / 64.0
    n = np.stack([-strength * dhdx, -strength * dhdy, np.ones_like(height)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.clip(np.round((n * 0.5 + 0.5) * 255.0), 0, 255)


def make_trashcan_normal_map() -> None:
    rng = np.random.default_rng(20080811)
    height = trashcan_height(NORMAL_MAP_SIZE, rng)
    write_image(TEXTURES / "trashcan_normal.png", normal_map_from_height(height, NORMAL_STRENGTH), "uint8")


# --------------------------------------------------------------------------------------------
# Studio environment cube map

# (name, direction for face texel (sc, tc) in [-1, 1]^2), OpenGL cube-map conventions.
CUBE_FACES = [
    ("px", lambda s, t: (np.ones_like(s), -t, -s)),
    ("nx", lambda s, t: (-np.ones_like(s), -t, s)),
    ("py", lambda s, t: (s, np.ones_like(s), t)),
    ("ny", lambda s, t: (s, -np.ones_like(s), -t)),
    ("pz", lambda s, t: (s, -t, np.ones_like(s))),
    ("nz", lambda s, t: (-s, -t, -np.ones_like(s))),
]

# Soft boxes: (azimuth deg, elevation deg, half width deg, half height deg, RGB radiance).
# The tall strips give a cylinder its vertical highlights; the rest are reflected by the rim,
# the dents and the inside of the can.
STUDIO_LIGHTS = [
    (35.0, 28.0, 16.0, 10.0, (14.0, 13.0, 12.0)),     # key soft box
    (70.0, 20.0, 5.0, 32.0, (9.0, 9.0, 8.5)),         # tall strip, right
    (-75.0, 15.0, 7.0, 30.0, (5.0, 6.0, 7.5)),        # tall strip, left, cool
    (150.0, 25.0, 4.0, 35.0, (7.0, 6.5, 6.0)),        # tall strip, behind
    (-125.0, 18.0, 22.0, 8.0, (2.5, 3.2, 4.5)),       # cool fill
    (0.0, 80.0, 40.0, 6.0, (6.0, 6.0, 6.0)),          # overhead strip
    (170.0, 6.0, 5.0, 12.0, (20.0, 11.0, 5.0)),       # warm rim light
    (-40.0, 40.0, 4.0, 4.0, (30.0, 30.0, 28.0)),      # small bright spot
    (-10.0, -25.0, 30.0, 12.0, (1.2, 1.1, 1.0)),      # bounce card on the floor
]


def studio_radiance(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Linear RGB radiance of the studio for unit directions (x, y, z)."""
    elevation = np.degrees(np.arcsin(np.clip(y, -1, 1)))
    azimuth = np.degrees(np.arctan2(x, z))
    # Backdrop: graded grey walls, a darker warm floor, a soft glow at the horizon.
    sky = 0.04 + 0.12 * np.clip(y, 0, 1) ** 0.7
    floor = 0.08 + 0.05 * np.clip(-y, 0, 1)
    wall = np.where(y >= 0, sky, floor)
    horizon = 0.3 * np.exp(-(elevation / 4.0) ** 2)
    rgb = np.stack([wall * 0.95 + horizon, wall + horizon, wall * 1.08 + horizon * 0.9], axis=-1)
    # Floor tiles seen faintly in reflections.
    tiles = (np.floor(x / np.maximum(-y, 0.05) * 2) + np.floor(z / np.maximum(-y, 0.05) * 2)) % 2
    rgb += np.where(y < -0.05, 0.05 * tiles, 0.0)[..., None]
    for az, el, half_w, half_h, color in STUDIO_LIGHTS:
        d_az = (azimuth - az + 180.0) % 360.0 - 180.0
        box = smooth_box(d_az, -half_w, half_w, 2.0) * smooth_box(elevation - el, -half_h, half_h, 2.0)
        rgb += box[..., None] * np.array(color)
    return rgb


def make_environment() -> None:
    size = ENV_FACE_SIZE
    coords = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    sc, tc = np.meshgrid(coords, coords)   # row index = t
    faces = []
    for _name, direction in CUBE_FACES:
        x, y, z = direction(sc, tc)
        length = np.sqrt(x * x + y * y + z * z)
        faces.append(studio_radiance(x / length, y / length, z / length))
    strip = np.concatenate(faces, axis=1)
    write_image(TEXTURES / "studio_env.exr", strip.astype(np.float32), "half")


# --------------------------------------------------------------------------------------------
# Chess board texture

def wood(rng: np.random.Generator, size: int, light: tuple, dark: tuple, rings: float,
         along_x: bool) -> np.ndarray:
    """A size x size wood-grain swatch: wavy growth rings with fine fibre noise."""
    wobble = periodic_fbm(rng, size, (2, 2), 3)
    fibres = periodic_fbm(rng, size, (2, 64) if along_x else (64, 2), 2)
    coord = np.linspace(0, 1, size, endpoint=False)
    across = coord[:, None] if along_x else coord[None, :]
    grain = 0.5 + 0.5 * np.sin(2 * math.pi * (across * rings + 1.5 * wobble))
    t = np.clip(0.65 * grain ** 3 + 0.35 * (0.5 + 0.5 * fibres), 0, 1)
    light = np.array(light)
    dark = np.array(dark)
    return light + (dark - light) * t[..., None]


def make_board_texture() -> None:
    """8x8 squares inside a border; the texture spans the board's 9x9 top face."""
    rng = np.random.default_rng(1851)
    size = BOARD_TEXTURE_SIZE
    maple = wood(rng, size, (0.90, 0.76, 0.55), (0.74, 0.56, 0.34), 9.0, True)
    walnut = wood(rng, size, (0.42, 0.26, 0.15), (0.24, 0.13, 0.07), 11.0, False)
    frame = wood(rng, size, (0.30, 0.17, 0.09), (0.16, 0.08, 0.04), 23.0, True)
    # Board units: [-4.5, 4.5]; squares cover [-4, 4].
    world = (np.arange(size) + 0.5) / size * 9.0 - 4.5
    # Column = x; row 0 is the image's top, which the GL puts at t = 1, i.e. z = +4.5.
    X, Z = np.meshgrid(world, world[::-1])
    inside = (np.abs(X) < 4.0) & (np.abs(Z) < 4.0)
    square_dark = (np.floor(X + 4.0) + np.floor(Z + 4.0)) % 2 == 0
    image = np.where(square_dark[..., None], walnut, maple)
    # Alternate the grain direction of the squares for a parquet look.
    image = np.where(((np.floor(X + 4.0) % 2) == 0)[..., None], image, np.transpose(image, (1, 0, 2)))
    image = np.where(inside[..., None], image, frame)
    # A thin dark inlay line around the playing field.
    edge = np.maximum(np.abs(X), np.abs(Z))
    image = np.where(((edge > 4.0) & (edge < 4.06))[..., None], np.array([0.12, 0.07, 0.04]), image)
    write_image(TEXTURES / "chess_board.png", np.clip(image, 0, 1) * 255.0, "uint8")


# --------------------------------------------------------------------------------------------
# Chess disc sets (Bunnell 2005)

def rotation_matrix(degrees: float, axis) -> np.ndarray:
    """3x3 rotation about `axis` by `degrees` (right-handed)."""
    axis = np.asarray(axis, dtype=float)
    norm = np.linalg.norm(axis)
    if norm == 0.0 or degrees == 0.0:
        return np.eye(3)
    x, y, z = axis / norm
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    return np.array([
        [c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
        [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
        [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)],
    ])


def decimate_profile(profile, spacing: float) -> np.ndarray:
    """The profile with points closer than `spacing` to the previously kept point dropped
    (the two end points are always kept)."""
    profile = np.asarray(profile, dtype=float)
    kept = [profile[0]]
    for point in profile[1:-1]:
        if np.linalg.norm(point - kept[-1]) >= spacing and np.linalg.norm(point - profile[-1]) >= spacing:
            kept.append(point)
    kept.append(profile[-1])
    return np.array(kept)


def revolve_discs(profile, segments: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Discs (positions, normals, areas) of a coarse surface of revolution about +Y.

    One disc per vertex: rings at every profile point with r > 0, single poles where r = 0.
    Each disc gets a third of the area of its adjacent triangles and the average outward normal
    of its adjacent profile segments.
    """
    profile = np.asarray(profile, dtype=float)
    angles = np.arange(segments) * 2 * math.pi / segments
    # Outward 2D normals of the profile segments: direction (dr, dh) -> (dh, -dr).
    seg = np.diff(profile, axis=0)
    seg_normals = np.stack([seg[:, 1], -seg[:, 0]], axis=1)
    seg_normals /= np.linalg.norm(seg_normals, axis=1, keepdims=True)

    positions, normals, index = [], [], []
    for k, (r, h) in enumerate(profile):
        adjacent = [seg_normals[j] for j in (k - 1, k) if 0 <= j < len(seg_normals)]
        n2 = np.sum(adjacent, axis=0)
        n2 /= np.linalg.norm(n2)
        if r <= 1e-9:
            index.append([len(positions)] * segments)
            positions.append([0.0, h, 0.0])
            normals.append([0.0, math.copysign(1.0, n2[1]), 0.0])
        else:
            ring = []
            for a in angles:
                ring.append(len(positions))
                positions.append([r * math.sin(a), h, r * math.cos(a)])
                normals.append([n2[0] * math.sin(a), n2[1], n2[0] * math.cos(a)])
            index.append(ring)
    positions = np.array(positions)
    areas = np.zeros(len(positions))
    for k in range(len(profile) - 1):
        for s in range(segments):
            s1 = (s + 1) % segments
            a, b, c, d = index[k][s], index[k][s1], index[k + 1][s], index[k + 1][s1]
            for tri in ((a, b, d), (a, d, c)):
                if len(set(tri)) < 3:
                    continue
                p0, p1, p2 = positions[list(tri)]
                area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0))
                areas[list(tri)] += area / 3.0
    return positions, np.array(normals), areas


def board_discs(size, grid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A grid of upward discs covering the top face of a box of `size` centred at the origin."""
    sx, sy, sz = size
    xs = (np.arange(grid) + 0.5) / grid * sx - sx / 2
    zs = (np.arange(grid) + 0.5) / grid * sz - sz / 2
    X, Z = np.meshgrid(xs, zs)
    positions = np.stack([X.ravel(), np.full(X.size, sy / 2), Z.ravel()], axis=1)
    normals = np.tile([0.0, 1.0, 0.0], (X.size, 1))
    areas = np.full(X.size, (sx / grid) * (sz / grid))
    return positions, normals, areas


def transform_discs(discs, keyframe: dict, with_translation: bool):
    """Apply a session keyframe's scale, rotation and (optionally) translation to discs."""
    positions, normals, areas = discs
    scale = float(keyframe.get("scale", 1.0))
    rotate = keyframe.get("rotate", [0, 0, 1, 0])
    rot = rotation_matrix(rotate[0], rotate[1:])
    positions = (positions * scale) @ rot.T
    normals = normals @ rot.T
    areas = areas * scale * scale
    if with_translation:
        positions = positions + np.asarray(keyframe.get("translate", [0, 0, 0]), dtype=float)
    return positions, normals, areas


def object_discs(spec: dict):
    """The object-space disc set of a session object's procedural mesh."""
    procedural = spec["procedural"]
    if procedural["type"] == "revolve":
        profile = decimate_profile(procedural["profile"], DISC_PROFILE_SPACING)
        discs = revolve_discs(profile, DISC_SEGMENTS)
        keep = ~((discs[1][:, 1] < -0.99) & (discs[0][:, 1] < BOTTOM_EPSILON))
        return tuple(a[keep] for a in discs)
    if procedural["type"] == "box":
        return board_discs(procedural["size"], BOARD_DISC_GRID)
    raise ValueError(f"no disc set for procedural type {procedural['type']!r}")


def disc_texture(discs) -> np.ndarray:
    """N x 2 x 4 float32: texel 0 = (position, area), texel 1 = (normal, 0)."""
    positions, normals, areas = discs
    texels = np.zeros((len(areas), 2, 4), dtype=np.float32)
    texels[:, 0, :3] = positions
    texels[:, 0, 3] = areas
    texels[:, 1, :3] = normals
    return texels


def make_chess_discs(session_path: Path) -> tuple[int, int]:
    """Write the static and king disc textures; return their disc counts."""
    session = json.loads(session_path.read_text())
    kings = [o for o in session["objects"] if o.get("name") == KING_NAME]
    if len(kings) != 1:
        raise ValueError(f"{session_path}: expected one object named {KING_NAME!r}")
    king = kings[0]
    moving = [o.get("name") for o in session["objects"] if o is not king and len(o["keyframes"]) > 1]
    if moving:
        raise ValueError(f"{session_path}: only the king may move, not {', '.join(map(str, moving))}")
    king_translations = [(k["frame"], k.get("translate")) for k in king["keyframes"]]
    offset = session["uniforms"]["u_kingOffset"]["keyframes"]
    if [(k["frame"], k["value"]) for k in offset] != king_translations:
        raise ValueError(f"{session_path}: u_kingOffset keyframes differ from the king's translate")
    for k in king["keyframes"]:
        if k.get("rotate", [0]) [0] != 0 or k.get("scale", 1) != 1:
            raise ValueError(f"{session_path}: the king may only translate")

    static = []
    for obj in session["objects"]:
        if obj is king:
            continue
        static.append(transform_discs(object_discs(obj), obj["keyframes"][0], True))
    static_discs = tuple(np.concatenate([d[i] for d in static]) for i in range(3))
    king_discs = transform_discs(object_discs(king), king["keyframes"][0], False)

    write_image(TEXTURES / "chess_discs.exr", disc_texture(static_discs), "float")
    write_image(TEXTURES / "chess_king_discs.exr", disc_texture(king_discs), "float")
    return len(static_discs[2]), len(king_discs[2])


def patch_disc_counts(session_path: Path, num_discs: int, num_king_discs: int) -> None:
    """Write the disc counts into the session's uniforms, keeping the file's layout."""
    text = session_path.read_text()
    for name, value in (("u_numDiscs", num_discs), ("u_numKingDiscs", num_king_discs)):
        text, count = re.subn(rf'("{name}":\s*)-?\d+', rf"\g<1>{value}", text)
        if count != 1:
            raise ValueError(f"{session_path}: cannot find the uniform {name}")
    session_path.write_text(text)


def make_perlin_tables() -> None:
    """Permutation and gradient tables of Perlin's improved noise (Perlin 2002)."""
    rng = np.random.default_rng(2002)
    permutation = rng.permutation(256).astype(np.float32).reshape(1, 256, 1)
    gradients = np.array([[1, 1, 0], [-1, 1, 0], [1, -1, 0], [-1, -1, 0],
                          [1, 0, 1], [-1, 0, 1], [1, 0, -1], [-1, 0, -1],
                          [0, 1, 1], [0, -1, 1], [0, 1, -1], [0, -1, -1],
                          # Perlin pads the 12 directions to 16 with these four repeats
                          [1, 1, 0], [0, -1, 1], [-1, 1, 0], [0, -1, -1]], np.float32).reshape(1, 16, 3)
    write_image(TEXTURES / "perlin_permutation.exr", permutation, "float")
    write_image(TEXTURES / "perlin_gradients.exr", gradients, "float")


def main() -> int:
    TEXTURES.mkdir(parents=True, exist_ok=True)
    make_perlin_tables()
    make_trashcan_normal_map()
    make_environment()
    make_board_texture()
    chess = SESSIONS / "chess.json"
    num_discs, num_king_discs = make_chess_discs(chess)
    patch_disc_counts(chess, num_discs, num_king_discs)
    print(f"wrote {TEXTURES}: {num_discs} static discs, {num_king_discs} king discs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
