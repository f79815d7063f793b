#!/usr/bin/env python3
"""Render camera images of a known box, to try ``deformctl measure images`` without a camera.

Usage: render_scene.py OUTDIR [--size-cm X Y Z] [--marker-size-cm S] [--tilt-deg T]
[--hfov-deg F] [--seed N]

Writes OUTDIR/top.png (camera above the table, tilted T degrees, a 5 cm ArUco marker of
DICT_4X4_50, id 0, lying beside the box) and OUTDIR/side.png (camera in front, the same marker
standing upright in the plane of the box's front face), plus OUTDIR/top_bg.png and
OUTDIR/side_bg.png (the same scenes without the box, for --background). The images have noise
and a lighting gradient; the camera is a pinhole with an F-degree horizontal field of view (default
60, what ``measure images`` assumes without ``--camera-matrix``), whose calibration is written
to OUTDIR/camera.yaml as ``cv2.FileStorage`` saves ``cv2.calibrateCamera``'s output. The true
size is printed on stderr, so the measurement can be compared with it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

from deformctl.vision.synth import box_views, focal_for_hfov

WIDTH, HEIGHT = 960, 720


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--size-cm", type=float, nargs=3, default=(12.0, 7.0, 5.0))
    parser.add_argument("--marker-size-cm", type=float, default=5.0)
    parser.add_argument("--tilt-deg", type=float, default=10.0)
    parser.add_argument("--hfov-deg", type=float, default=60.0)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if not 10.0 <= args.hfov_deg <= 150.0:
        sys.exit(f"error: --hfov-deg must be 10..150 degrees, got {args.hfov_deg:g}")
    size = tuple(args.size_cm)
    focal = focal_for_hfov(WIDTH, args.hfov_deg)
    setup = {
        "marker_size_cm": args.marker_size_cm,
        "tilt_deg": args.tilt_deg,
        "yaw_deg": 8.0,
        "focal_px": focal,
        "width": WIDTH,
        "height": HEIGHT,
    }
    top, side = box_views(size, (40, 40, 200), seed=args.seed, **setup)
    top_bg, side_bg = box_views(size, seed=args.seed + 10, with_box=False, **setup)
    args.outdir.mkdir(parents=True, exist_ok=True)
    for name, img in (("top", top), ("side", side), ("top_bg", top_bg), ("side_bg", side_bg)):
        cv2.imwrite(str(args.outdir / f"{name}.png"), img)
    k = np.array([[focal, 0.0, (WIDTH - 1) / 2], [0.0, focal, (HEIGHT - 1) / 2], [0.0, 0.0, 1.0]])
    fs = cv2.FileStorage(str(args.outdir / "camera.yaml"), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", WIDTH)
    fs.write("image_height", HEIGHT)
    fs.write("camera_matrix", k)
    fs.write("distortion_coefficients", np.zeros((1, 5)))
    fs.release()
    print(
        f"{args.outdir}: top.png, side.png (+ _bg), camera.yaml of a {size[0]:g} x {size[1]:g} x "
        f"{size[2]:g} cm box, marker {args.marker_size_cm:g} cm, {args.hfov_deg:g}° camera",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
