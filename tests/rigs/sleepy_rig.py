"""Stand-in rig that hangs: sleeps SECONDS before answering.

Usage: sleepy_rig.py SECONDS [CHILD_PID_FILE]
With CHILD_PID_FILE, it first starts a child process that inherits stdout and also sleeps (a
driver that forked a helper), and writes the child's pid to that file.
"""

import json
import subprocess
import sys
import time

seconds = float(sys.argv[1])
sys.stdin.read()
if len(sys.argv) > 2:
    child = subprocess.Popen([sys.executable, "-c", f"import time; time.sleep({seconds})"])
    with open(sys.argv[2], "w", encoding="utf-8") as f:
        f.write(str(child.pid))
time.sleep(seconds)
print(json.dumps({"lifted": True, "slip_m": 0.0}))
