"""The simulator's kernels take their arrays as a few named-tuple bundles: no numba
kernel of deformctl.sim has more than 12 parameters, and no module of it more than 800 lines."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from pathlib import Path

import numba

import deformctl.sim

MAX_PARAMETERS = 12
MAX_LINES = 800


def _kernels() -> dict[str, int]:
    counts: dict[str, int] = {}
    for info in pkgutil.walk_packages(deformctl.sim.__path__, "deformctl.sim."):
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if isinstance(value, numba.core.registry.CPUDispatcher) and value.__module__ == (
                info.name
            ):
                counts[f"{info.name}.{name}"] = len(inspect.signature(value.py_func).parameters)
    return counts


def test_no_kernel_takes_more_than_twelve_parameters() -> None:
    counts = _kernels()
    assert len(counts) >= 50
    assert {k: n for k, n in counts.items() if n > MAX_PARAMETERS} == {}
    # the step loops take the model, the run and the solver as bundles
    assert counts["deformctl.sim.step.direct.integrate"] == 7
    assert counts["deformctl.sim.step.iterative.integrate_iterative"] == 7


def test_no_simulator_module_exceeds_800_lines() -> None:
    root = Path(deformctl.sim.__file__).parent
    sizes = {p.name: len(p.read_text().splitlines()) for p in root.rglob("*.py")}
    assert {name: n for name, n in sizes.items() if n > MAX_LINES} == {}
