#!/usr/bin/env python3
"""A stand-in rig with a camera only, for ``deformctl lift rig --slip-from-frames``.

It follows the rig protocol (docs/rig-protocol.md) but answers each attempt with the paths of
two frames instead of ``lifted``: a side view of a box between two palms (rendered with
``deformctl.vision.synth.Gripper``) before and after a 3 cm lift of the palms, written to
``frames/a<attempt>_{before,after}.png`` in its working directory. deformctl judges the slip
from the frames. The object's rise depends on the grip force F:

* F >= THRESHOLD_N: 2.8 cm (it lags the palms by 2 mm, within a 5 mm tolerance: lifted);
* PARTIAL_FROM_N <= F < THRESHOLD_N: 1.5 cm (partial slip, 15 mm);
* F < PARTIAL_FROM_N: 0 (it stays on the table, 30 mm).

``--regions`` renders palms without markers (for ``--palm-regions``); ``--after-size WxH``
resizes the after frame (a broken camera pipeline). To the handshake it states
``--max-force-n`` (default 500 N). The rig logs the object's rise to stderr.

Usage (deformctl runs it once per attempt; objects.csv from ``deformctl measure images``):
    deformctl lift rig objects.csv --command "python3 examples/frames_render_rig.py 3.0 2.6" \\
        --slip-from-frames --palm-marker-ids 1,2 --frame-marker-size-cm 2.4 -o lift.parquet
"""

import argparse
import json
import os
import sys

import cv2

from deformctl.vision.synth import Gripper, gripper_frame

PALM_RISE_CM = 3.0


def object_rise_cm(force_n: float, threshold_n: float, partial_from_n: float) -> float:
    """How far the object rises when gripped with ``force_n`` while the palms rise 3 cm."""
    if force_n >= threshold_n:
        return PALM_RISE_CM - 0.2
    if force_n >= partial_from_n:
        return 1.5
    return 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("threshold_n", type=float, help="the object lifts from this force, N")
    parser.add_argument("partial_from_n", type=float, help="it slips partly from this force, N")
    parser.add_argument("--regions", action="store_true", help="palms without markers")
    parser.add_argument("--after-size", metavar="WxH", help="resize the after frame")
    parser.add_argument(
        "--max-force-n", type=float, default=500.0, help="the maximum force it states, N"
    )
    args = parser.parse_args()
    request = json.load(sys.stdin)
    if request.get("handshake"):  # rig protocol 2: state the maximum force, do not move
        print(json.dumps({"protocol_version": 2, "max_force_n": args.max_force_n}))
        return
    force_n = request["grip_force_n"]
    rise_cm = object_rise_cm(force_n, args.threshold_n, args.partial_from_n)
    gripper = Gripper(palm_markers=not args.regions, width=800, height=600)
    i = request["attempt_index"]
    os.makedirs("frames", exist_ok=True)
    before, after = f"frames/a{i}_before.png", f"frames/a{i}_after.png"
    cv2.imwrite(before, gripper_frame(gripper, object_rise_cm=0.0, palm_rise_cm=0.0, seed=2 * i))
    after_img = gripper_frame(
        gripper, object_rise_cm=rise_cm, palm_rise_cm=PALM_RISE_CM, seed=2 * i + 1
    )
    if args.after_size:
        w, h = (int(v) for v in args.after_size.split("x"))
        cv2.imwrite(after, cv2.resize(after_img, (w, h)))
    else:
        cv2.imwrite(after, after_img)
    print(f"attempt {i}: F = {force_n:.4g} N, object rise {rise_cm} cm", file=sys.stderr)
    print(json.dumps({"before_frame": before, "after_frame": after}))


if __name__ == "__main__":
    main()
