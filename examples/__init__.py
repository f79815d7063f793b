"""Runnable examples, installed with the wheel as ``deformctl.examples``.

``python -m deformctl.examples.threshold_rig`` is the stand-in rig of the docs, so a rig example
runs from an installed wheel as it does from a checkout (``python3 examples/threshold_rig.py``).
"""
