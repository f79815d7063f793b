"""Stand-in rig driver: lifts iff grip_force_n >= THRESHOLD_N.

Usage: threshold_rig.py THRESHOLD_N [REQUEST_LOG [MAX_FORCE_N]]
Appends every attempt request it receives (one JSON line) to REQUEST_LOG when given. With
MAX_FORCE_N it answers the handshake (rig protocol version 2) with that maximum force; without
it, it is a version-1 rig: a handshake request has no ``grip_force_n`` and it fails (exit 1).
"""

import json
import sys

threshold_n = float(sys.argv[1])
request_text = sys.stdin.read()
request = json.loads(request_text)
if request.get("handshake") and len(sys.argv) > 3:
    print(json.dumps({"protocol_version": 2, "max_force_n": float(sys.argv[3])}))
    sys.exit(0)
grip_force_n = request["grip_force_n"]  # a version-1 rig fails here on a handshake
if len(sys.argv) > 2 and sys.argv[2] != "-":
    with open(sys.argv[2], "a", encoding="utf-8") as log:
        log.write(request_text.strip() + "\n")
print(f"gripping {request['object_id']} at {grip_force_n} N", file=sys.stderr)
lifted = grip_force_n >= threshold_n
answer = {"lifted": lifted, "slip_m": 0.0 if lifted else 0.05, "message": "stand-in rig"}
print(json.dumps(answer))
