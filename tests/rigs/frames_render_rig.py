"""Stand-in rig with a (rendered) camera: answers with before/after frame paths only.

Usage: frames_render_rig.py THRESHOLD_N PARTIAL_FROM_N [--regions] [--after-size WxH]

Renders a side view of a box between two palms (deformctl.vision.synth.Gripper) before and after
a 3 cm lift of the palms, to frames/a<attempt>_{before,after}.png in its working directory, and
answers {"before_frame": ..., "after_frame": ...}. The object's rise depends on the grip force F:

* F >= THRESHOLD_N: 2.8 cm (it lags the palms by 2 mm, within a 5 mm tolerance: lifted);
* PARTIAL_FROM_N <= F < THRESHOLD_N: 1.5 cm (partial slip, 15 mm);
* F < PARTIAL_FROM_N: 0 (it stays on the table, 30 mm).

--regions renders palms without markers (for --palm-regions); --after-size resizes the after
frame (a broken camera pipeline). The rig logs the object's rise to stderr.
"""

import argparse
import json
import os
import sys

import cv2

from deformctl.vision.synth import Gripper, gripper_frame

PALM_RISE_CM = 3.0

parser = argparse.ArgumentParser()
parser.add_argument("threshold_n", type=float)
parser.add_argument("partial_from_n", type=float)
parser.add_argument("--regions", action="store_true")
parser.add_argument("--after-size", default=None)
args = parser.parse_args()
request = json.loads(sys.stdin.read())
force_n = request["grip_force_n"]
if force_n >= args.threshold_n:
    rise_cm = PALM_RISE_CM - 0.2
elif force_n >= args.partial_from_n:
    rise_cm = 1.5
else:
    rise_cm = 0.0
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
    after_img = cv2.resize(after_img, (w, h))
cv2.imwrite(after, after_img)
print(f"attempt {i}: F = {force_n:.4g} N, object rise {rise_cm} cm", file=sys.stderr)
print(json.dumps({"before_frame": before, "after_frame": after}))
