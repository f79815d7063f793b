"""Stand-in rig that answers by THRESHOLD_N, then stalls at one attempt (a robot that hangs).

Usage: stall_rig.py THRESHOLD_N REQUEST_LOG STALL_OBJECT STALL_INDEX
Appends every request it answers to REQUEST_LOG (one JSON line). At STALL_OBJECT's attempt
STALL_INDEX it writes its pid to REQUEST_LOG.stalled instead and sleeps 120 s without answering
(a test kills the run meanwhile, then this process by that pid).
"""

import json
import os
import sys
import time

threshold_n, request_log, stall_object, stall_index = sys.argv[1:5]
request = json.loads(sys.stdin.read())
assert request["grip_force_n"] <= request.get("max_force_n", float("inf")), request
if request["object_id"] == stall_object and request["attempt_index"] == int(stall_index):
    with open(request_log + ".stalled", "w", encoding="utf-8") as f:
        f.write(str(os.getpid()))
    time.sleep(120)
lifted = request["grip_force_n"] >= float(threshold_n)
with open(request_log, "a", encoding="utf-8") as log:
    log.write(json.dumps(request) + "\n")
print(json.dumps({"lifted": lifted, "slip_m": 0.0 if lifted else 0.05}))
