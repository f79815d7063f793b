"""Stand-in rig driver: lifts iff grip_force_n >= THRESHOLD_N.

Usage: threshold_rig.py THRESHOLD_N [REQUEST_LOG]
Appends every request it receives (one JSON line) to REQUEST_LOG when given.
"""

import json
import sys

threshold_n = float(sys.argv[1])
request_text = sys.stdin.read()
request = json.loads(request_text)
if len(sys.argv) > 2:
    with open(sys.argv[2], "a", encoding="utf-8") as log:
        log.write(request_text.strip() + "\n")
print(f"gripping {request['object_id']} at {request['grip_force_n']} N", file=sys.stderr)
lifted = request["grip_force_n"] >= threshold_n
answer = {"lifted": lifted, "slip_m": 0.0 if lifted else 0.05, "message": "stand-in rig"}
print(json.dumps(answer))
