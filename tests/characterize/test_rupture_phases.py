"""Rupture detection and the loading/unloading phases (``deformctl.squeeze.rupture``).

The rupture criterion must fire on a force collapse while the gripper keeps closing or holds
still, at the collapse, and stay silent on every Kelvin–Voigt squeeze, including heavily damped
ones whose compression still grows while their force falls (the reason for its third condition),
and on the simulator's squeezes.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from deformctl.errors import UsageError
from deformctl.measure import simulate_squeezes
from deformctl.population import golden_population
from deformctl.squeeze.rupture import Rupture, cut_rupture, phase_slice, ruptures_from_object
from deformctl.testing.kelvin_voigt import synthetic_kelvin_voigt_squeeze
from tests._helpers.doubtful_logs import rupture

WINDOW_S = 0.2


@pytest.mark.parametrize(("d", "lam"), [(5.0, 1.0), (13.0, 0.33), (30.0, 6.47), (20.0, 15.0)])
@pytest.mark.parametrize("keep", [0.3, 0.69])
@pytest.mark.parametrize("closing", [1.0, 3.0])
def test_rupture_found_at_the_collapse(d: float, lam: float, keep: float, closing: float) -> None:
    s = rupture(d, lam, keep=keep, closing=closing)
    cut, r = cut_rupture(s, window_s=WINDOW_S)
    assert r is not None
    assert r.time_s == pytest.approx(2.0, abs=0.02)  # the peak before the collapse
    assert r.force_n == pytest.approx(10.0, rel=0.05)
    assert cut.time_s[-1] == pytest.approx(r.time_s)
    assert len(cut) < len(s)


def test_a_sudden_force_drop_with_the_gripper_stopped_is_a_rupture() -> None:
    # a collapse while the compression holds is a rupture (a force-controlled gripper
    # that backs off after it keeps its fingers still); a smooth decay is relaxation
    # (tests/characterize/test_rupture.py)
    s = rupture(30.0, 6.47, keep=0.3, closing=0.0)
    _, r = cut_rupture(s, window_s=WINDOW_S)
    assert r is not None
    assert r.time_s == pytest.approx(2.0, abs=0.01)


def test_no_rupture_in_kelvin_voigt_squeezes() -> None:
    found = []
    for profile, d, lam, seed in itertools.product(
        ("ramp_hold_release", "sine"),
        (5.0, 13.0, 30.0, 60.0),
        (0.0, 0.33, 1.0, 6.47, 15.0),
        range(2),
    ):
        s = synthetic_kelvin_voigt_squeeze(d, lam, profile=profile, seed=seed)  # type: ignore[arg-type]
        if cut_rupture(s, window_s=WINDOW_S)[1] is not None:
            found.append((profile, d, lam, seed))
    assert not found


def test_no_rupture_in_simulated_squeezes() -> None:
    _, squeezes = simulate_squeezes(golden_population().iloc[:2])
    assert all(cut_rupture(s, window_s=WINDOW_S)[1] is None for s in squeezes)


def test_rupture_record_round_trip() -> None:
    r = Rupture(1, 2.0, 10.1, 0.004, recording_time_s=7.5)
    assert Rupture.from_record(r.to_record()) == r
    assert ruptures_from_object({"ruptures": [r.to_record(), {"bad": 1}, 3]}) == [r]
    assert ruptures_from_object({"object_id": "x"}) == []
    assert r.describe() == "squeeze #1 at 2 s, 10.1 N"


def test_phases_of_a_ramp_hold_release() -> None:
    s = synthetic_kelvin_voigt_squeeze(20.0, 2.0, duration_s=4.0)  # ramp 0-1 s, hold to 2.6 s
    load = phase_slice(s.time_s, s.force_n, "loading", window_s=WINDOW_S)
    unload = phase_slice(s.time_s, s.force_n, "unloading", window_s=WINDOW_S)
    assert s.time_s[load.stop - 1] == pytest.approx(1.0, abs=0.05)
    assert s.time_s[unload.start] == pytest.approx(2.6, abs=0.05)
    assert unload.stop == len(s)
    assert phase_slice(s.time_s, s.force_n, "all", window_s=WINDOW_S) == slice(0, len(s))
    assert float(np.max(s.force_n[unload])) > 9.5
    with pytest.raises(UsageError, match="phase must be one of loading, unloading, all"):
        phase_slice(s.time_s, s.force_n, "hold", window_s=WINDOW_S)


def test_phases_of_a_force_that_never_turns_positive() -> None:
    # a sign mistake upstream must not become an IndexError: the peak is the largest value
    s = synthetic_kelvin_voigt_squeeze(20.0, 1.0, profile="ramp_hold_release", seed=0)
    neg = -np.abs(s.force_n) - 0.05
    load = phase_slice(s.time_s, neg, "loading", window_s=WINDOW_S)
    unload = phase_slice(s.time_s, neg, "unloading", window_s=WINDOW_S)
    assert 0 < load.stop <= len(s)
    assert 0 <= unload.start < len(s)
    top = int(np.argmax(neg))
    assert load.stop - 1 <= top + 5
