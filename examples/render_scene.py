#!/usr/bin/env python3
"""Render camera images of a known box, to try ``deformctl measure --images`` without a camera.

Usage: render_scene.py OUTDIR [--size-cm X Y Z] [--marker-size-cm S] [--tilt-deg T] [--seed N]

Writes OUTDIR/top.png (camera above the table, tilted T degrees, a 5 cm ArUco marker of
DICT_4X4_50, id 0, lying beside the box) and OUTDIR/side.png (camera in front, the same marker
standing upright in the plane of the box's front face), plus OUTDIR/top_bg.png and
OUTDIR/side_bg.png (the same scenes without the box, for --background). The images have noise
and a lighting gradient; the camera has a 60-degree horizontal field of view. The true size is
printed on stderr, so the measurement can be compared with it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2

from deformctl.vision.synth import box_views


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--size-cm", type=float, nargs=3, default=(12.0, 7.0, 5.0))
    parser.add_argument("--marker-size-cm", type=float, default=5.0)
    parser.add_argument("--tilt-deg", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    size = tuple(args.size_cm)
    setup = {"marker_size_cm": args.marker_size_cm, "tilt_deg": args.tilt_deg, "yaw_deg": 8.0}
    top, side = box_views(size, (40, 40, 200), seed=args.seed, **setup)
    top_bg, side_bg = box_views(size, seed=args.seed + 10, with_box=False, **setup)
    args.outdir.mkdir(parents=True, exist_ok=True)
    for name, img in (("top", top), ("side", side), ("top_bg", top_bg), ("side_bg", side_bg)):
        cv2.imwrite(str(args.outdir / f"{name}.png"), img)
    print(
        f"{args.outdir}: top.png, side.png (+ _bg) of a {size[0]:g} x {size[1]:g} x {size[2]:g} cm "
        f"box, marker {args.marker_size_cm:g} cm",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
