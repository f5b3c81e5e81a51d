"""Write the README's picture: one level's frames from a profile folder, side by side (the
original shader, the cached shader, the error map, the hits and misses), as the profile rendered
them for its report (``PROFILE/frames/<level>/``; this script renders nothing)::

    python docs/make_readme_figure.py marble-marble.rrprofile e3 docs/readme_marble_e3.png
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from PIL import Image, ImageDraw

#: the images shown, left to right, with their captions
SHOWN = (("original", "the original shader"), ("cached", "the cached shader"),
         ("error_map", "the error, amplified"), ("hit_map", "hits (green), misses (red)"))
GAP = 6           # pixels between images
CAPTION = 22      # pixels of caption under each image


def figure(profile: Path, level: str) -> Image.Image:
    """The strip of ``level``'s images from the profile folder ``profile``."""
    record = json.loads((profile / "frames" / "frames.json").read_text(encoding="utf-8"))["selections"][level]
    images = [Image.open(profile / record["images"][name]).convert("RGB") for name, _ in SHOWN]
    width, height = images[0].size
    out = Image.new("RGB", (len(images) * width + (len(images) - 1) * GAP, height + CAPTION), "white")
    draw = ImageDraw.Draw(out)
    for i, (image, (_, caption)) in enumerate(zip(images, SHOWN)):
        x = i * (width + GAP)
        out.paste(image, (x, 0))
        draw.text((x + 4, height + 5), caption, fill=(40, 40, 40))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("profile", type=Path, help="a profile folder (rrcache profile wrote it)")
    parser.add_argument("level", help="the level whose frames to show (e1..e4)")
    parser.add_argument("out", type=Path, help="the PNG to write")
    args = parser.parse_args()
    figure(args.profile, args.level).save(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
