"""Stand-in rig that answers by THRESHOLD_N but crashes (exit 3) at attempt_index 2.

Usage: crash_rig.py THRESHOLD_N
"""

import json
import sys

threshold_n = float(sys.argv[1])
request = json.loads(sys.stdin.read())
if request["attempt_index"] == 2:
    print("Traceback (most recent call last):", file=sys.stderr)
    print('  File "driver.py", line 12, in grip', file=sys.stderr)
    print("MotorFault: left palm encoder lost", file=sys.stderr)
    sys.exit(3)
lifted = request["grip_force_n"] >= threshold_n
print(json.dumps({"lifted": lifted, "slip_m": 0.0 if lifted else 0.05}))
