"""``python -m deformctl.sim.warmup`` (run by ``make install``) compiles every kernel a run uses.

Checked in a fresh numba cache (``NUMBA_CACHE_DIR``): after the warm-up, squeezes and lift
attempts of both presets, a paper-preset bag on the iterative solver and a fine cube add nothing
to the cache, i.e. they compile nothing.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

RUNS = """
from deformctl.presets import sim_preset
from deformctl.sim import ObjectSpec, SimSettings, lift_attempt, squeeze
bag = ObjectSpec("bag", (15.0, 12.0, 9.0), 10.0, 0.5, 20.0, 2.0)
for name in ("paper", "table"):
    preset = sim_preset(name)
    squeeze(bag, peak_force_n=5.0, ramp_s=0.01, hold_s=0.01, settings=preset.settings)
    preset.lift_attempt(bag, 12.0)
squeeze(bag, peak_force_n=5.0, ramp_s=0.01, hold_s=0.01, settings=SimSettings(particles_per_side=9))
"""


def _run(code: list[str], cache: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run(
        [sys.executable, *code], check=True, capture_output=True, text=True, timeout=900, env=env
    )


def test_warmup_compiles_every_kernel_a_run_uses(tmp_path: Path) -> None:
    cache = tmp_path / "numba"
    done = _run(["-m", "deformctl.sim.warmup"], cache)
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("deformctl: simulator kernels compiled or loaded in ")
    compiled = sorted(p.relative_to(cache) for p in cache.rglob("*.nbi"))
    assert len(compiled) >= 10, compiled
    _run(["-c", RUNS], cache)
    after = sorted(p.relative_to(cache) for p in cache.rglob("*.nbi"))
    assert after == compiled, sorted(set(after) - set(compiled))
