"""What measure and characterize share about a squeeze (deformctl.squeeze): one vocabulary of
recording flags, one phase rule and one window rule, below both stages.

Known truth: a recording with a gap is flagged with a name characterize knows and describes; the
doubt flags of the recorded quantities' rules are the vocabulary's; the window rule's closed form
``0.2 s · (1000 Hz / rate)^(1/3)``, never below 0.2 s; and no module of ``measure`` imports
``characterize`` (nor the reverse), so neither restates the other.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import deformctl
from deformctl import quantities
from deformctl.characterize.quality import FLAGS, describe_flag, with_recording_flags
from deformctl.errors import UsageError
from deformctl.measure.defects import coarse_force, logging_gaps
from deformctl.squeeze.flags import DOUBT_FLAGS, RECORDING_FLAGS
from deformctl.squeeze.phase import PHASES, check_phase
from deformctl.squeeze.window import DEFAULT_WINDOW_S, default_window_s

PACKAGE = Path(deformctl.__file__).resolve().parent


def test_the_flags_measure_raises_are_the_ones_characterize_carries() -> None:
    t = np.r_[np.arange(100) * 0.01, 3.0 + np.arange(100) * 0.01]  # a 2 s gap
    gap = logging_gaps(t)
    coarse = coarse_force(np.round(np.linspace(0.0, 10.0, 200)))  # 1 N steps on a 10 N peak
    assert gap is not None
    assert coarse is not None
    for defect in (gap, coarse):
        assert defect.flag in RECORDING_FLAGS
        assert with_recording_flags("ok", [defect.flag]) == defect.flag
        assert RECORDING_FLAGS[defect.flag] in describe_flag(defect.flag, {})
    assert with_recording_flags("ok", ["not_a_flag"]) == "ok"
    # quality lists every recording flag, in the vocabulary's order, after its own
    assert FLAGS[-len(RECORDING_FLAGS) :] == tuple(RECORDING_FLAGS)


def test_the_recorded_quantities_doubt_flags_are_the_vocabulary_s() -> None:
    rules = [
        quantities.RECORDED_RATE_HZ,
        quantities.RECORDED_PEAK_FORCE_N,
        quantities.RECORDED_PEAK_COMPRESSION_M,
        quantities.RECORDED_SECANT_N_PER_CM,
    ]
    assert {rule.flag for rule in rules} == set(DOUBT_FLAGS)
    assert set(DOUBT_FLAGS) <= set(RECORDING_FLAGS)


def test_the_phase_rule() -> None:
    for phase in PHASES:
        assert check_phase(phase) == phase
    with pytest.raises(UsageError, match="--phase must be one of loading, unloading, all"):
        check_phase("peak")


def test_the_window_rule_is_its_closed_form() -> None:
    assert DEFAULT_WINDOW_S == 0.2
    for rate in (10.0, 100.0, 500.0, 999.0):
        assert default_window_s(rate) == pytest.approx(0.2 * (1000.0 / rate) ** (1 / 3), rel=1e-15)
    for rate in (1000.0, 5000.0, None, float("nan"), 0.0, -3.0):
        assert default_window_s(rate) == 0.2


def _imports(package: str) -> set[str]:
    found: set[str] = set()
    for path in (PACKAGE / package).rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                found.add(node.module)
            elif isinstance(node, ast.Import):
                found.update(alias.name for alias in node.names)
    return found


def test_measure_and_characterize_do_not_import_each_other() -> None:
    assert not {m for m in _imports("measure") if m.startswith("deformctl.characterize")}
    assert not {m for m in _imports("characterize") if m.startswith("deformctl.measure")}
