"""Stand-in rig that prints ANSWER verbatim (no newline added) and exits with STATUS.

Usage: echo_rig.py ANSWER [STATUS [STDERR_TEXT]]
"""

import sys

sys.stdin.read()
sys.stdout.write(sys.argv[1])
if len(sys.argv) > 3:
    sys.stderr.write(sys.argv[3])
sys.exit(int(sys.argv[2]) if len(sys.argv) > 2 else 0)
