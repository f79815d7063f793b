"""``deformctl warmup``: compile the simulator's kernels and the scene writer ahead of time."""

from __future__ import annotations

import sys

from deformctl.cli._common import translate_errors


@translate_errors
def warmup() -> None:
    """Compile the simulator's kernels (and the scene writer) once, ahead of the first run.

    A fresh install compiles them on its first simulated command (about a minute on 2 cores,
    announced on one stderr line); this does it now, so that command starts at once. Later runs
    load the compiled code in well under a second; run it again after upgrading deformctl.

    Example: deformctl warmup
    """
    from deformctl.artifacts.mcap._scene_text import compile_writer
    from deformctl.sim.protocols import compile_kernels

    seconds = compile_kernels()
    compile_writer()
    print(f"deformctl: simulator kernels compiled or loaded in {seconds:.1f} s", file=sys.stderr)
