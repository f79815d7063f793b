"""Stand-in rig that prints log chatter instead of a JSON answer and exits 0."""

import sys

sys.stdin.read()
print("Connecting to robot... ok")
print("lift done, looks fine to me")
