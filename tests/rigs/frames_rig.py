"""Stand-in rig with a camera only: answers with frame paths, no 'lifted' flag.

Usage: frames_rig.py THRESHOLD_N
Writes frames/a<attempt>_before.txt and _after.txt in its working directory. A "frame" is a text
file holding the object's height above the table, m; the palms rise 0.05 m. Below the threshold
the object stays on the table.
"""

import json
import os
import sys

PALM_RISE_M = 0.05
threshold_n = float(sys.argv[1])
request = json.loads(sys.stdin.read())
os.makedirs("frames", exist_ok=True)
i = request["attempt_index"]
before, after = f"frames/a{i}_before.txt", f"frames/a{i}_after.txt"
with open(before, "w", encoding="utf-8") as f:
    f.write("0.0")
with open(after, "w", encoding="utf-8") as f:
    f.write(str(PALM_RISE_M if request["grip_force_n"] >= threshold_n else 0.0))
print(json.dumps({"before_frame": before, "after_frame": after}))
