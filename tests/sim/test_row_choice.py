"""The iterative solver's row loops leave out far, inactive table and palm-plane rows
(deformctl.sim.step.contact._choose_rows): the results are bit-identical to visiting every row."""

from __future__ import annotations

import numpy as np
import pytest

from deformctl.sim import (
    LiftProfile,
    ObjectSpec,
    SimSettings,
    free_run,
    lift_attempt,
    rigid_lift_force_n,
)
from deformctl.sim.engine import build_model
from deformctl.sim.protocols import squeeze_many

CUBE = ObjectSpec("cube", (10.0, 10.0, 10.0), 5.0, 0.5, 30.0, 1.0)
SOFT = ObjectSpec("soft", (8.0, 6.0, 5.0), 2.0, 0.4, 4.0, 0.3)


def _lift(spec: ObjectSpec, grip_n: float, n: int) -> tuple[object, np.ndarray]:
    settings = SimSettings(particles_per_side=n, solver="iterative")
    model = build_model(spec, settings, gripped=True, resting=True, table=True)
    model.solver_stats[:] = 0
    outcome = lift_attempt(spec, grip_n, settings=settings)
    return outcome, model.solver_stats.copy()


def _same_fields(a: object, b: object) -> None:
    for name in a.__dataclass_fields__:  # type: ignore[attr-defined]
        va, vb = getattr(a, name), getattr(b, name)
        if isinstance(va, np.ndarray):
            np.testing.assert_array_equal(va, vb, err_msg=name)


def _same_series(a: object, b: object) -> None:
    """The same verdict and every series of a lift attempt (all arrays)."""
    assert a.lifted == b.lifted  # type: ignore[attr-defined]
    _same_fields(a.series, b.series)  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("spec", "factor", "n"),
    [(CUBE, 1.2, 8), (CUBE, 0.7, 8), (SOFT, 1.3, 7)],
    ids=["cube-lifts", "cube-slips", "soft-lifts"],
)
def test_leaving_out_far_rows_changes_nothing(
    monkeypatch: pytest.MonkeyPatch, spec: ObjectSpec, factor: float, n: int
) -> None:
    """Every row visited (margin inf), the default margin, a margin so small that the rows are
    chosen again every few steps and the speed check falls back to all rows, and one that keeps
    every row: the same lift, bit for bit; the default visits far fewer rows."""
    from deformctl.sim import engine

    grip = factor * rigid_lift_force_n(spec, LiftProfile())
    default = engine.ROW_MARGIN_FRACTION
    runs = {}
    for fraction in (np.inf, default, 1e-4, 1e3):
        monkeypatch.setattr(engine, "ROW_MARGIN_FRACTION", fraction)
        runs[fraction] = _lift(spec, grip, n)
    (every, every_stats), *others = runs.values()
    assert every.lifted == (factor > 1.0)  # type: ignore[attr-defined]
    for outcome, stats in others:
        _same_series(every, outcome)
        # the same solves and rounds
        np.testing.assert_array_equal(stats[:5], every_stats[:5])
    default_rows = runs[default][1][5]
    assert default_rows < 0.5 * every_stats[5], (default_rows, every_stats[5])
    # the tiny margin: its speed check fell back to every row in some steps
    assert default_rows < runs[1e-4][1][5] < every_stats[5]
    # a margin larger than the object keeps every row
    assert runs[1e3][1][5] == every_stats[5]


@pytest.mark.parametrize("fraction", [0.5, 1e-4])
def test_a_drop_onto_the_table_is_unchanged(
    monkeypatch: pytest.MonkeyPatch, fraction: float
) -> None:
    """An object dropped from 2 cm: its table rows start far and are left out, and each comes
    back before its particle reaches the table. With the tiny margin they come back only through
    the speed check (the fall covers far more than the margin in a step): without that check
    the bottom layer would pass through the table."""
    from deformctl.sim import engine

    settings = SimSettings(particles_per_side=6, solver="iterative")
    out = {}
    for f in (np.inf, fraction):
        monkeypatch.setattr(engine, "ROW_MARGIN_FRACTION", f)
        out[f] = free_run(SOFT, duration_s=0.25, drop_height_m=0.02, settings=settings)
    every, chosen = out.values()
    assert every.table_force_n.max() > 0.0  # it landed
    _same_fields(every, chosen)


def test_a_squeeze_is_unchanged(monkeypatch: pytest.MonkeyPatch) -> None:
    """The squeeze protocol (palms closing on the object on the table), at the default margin
    and at the tiny one."""
    from deformctl.sim import engine

    settings = SimSettings(particles_per_side=7, solver="iterative")
    out = []
    for f in (np.inf, engine.ROW_MARGIN_FRACTION, 1e-4):
        monkeypatch.setattr(engine, "ROW_MARGIN_FRACTION", f)
        out.append(
            squeeze_many(SOFT, 1, peak_force_n=30.0, ramp_s=0.1, hold_s=0.1, settings=settings)[0]
        )
    _same_fields(out[0], out[1])
    _same_fields(out[0], out[2])


@pytest.mark.parametrize("n", [6, 11])
def test_predicted_release_saves_rounds_not_accuracy(
    monkeypatch: pytest.MonkeyPatch, n: int
) -> None:
    """Releasing a table row before the first round when its impulse, extrapolated from the last
    two steps, is not positive: the same lift up to the CG tolerance (centre of mass within
    3e-9 m; measured 4.4e-10 at 6^3 and 6.6e-10 at 11^3), in fewer active-set rounds and CG
    iterations (measured 1081 -> 1077 rounds, 421 -> 406 iterations at 6^3; 1087 -> 1078 and
    572 -> 535 at 11^3)."""
    from deformctl.sim import engine

    grip = 1.2 * rigid_lift_force_n(CUBE, LiftProfile())
    runs = {}
    for predict in (False, True):
        monkeypatch.setattr(engine, "PREDICT_RELEASE", predict)
        runs[predict] = _lift(CUBE, grip, n)
    (plain, plain_stats), (predicted, predicted_stats) = runs.values()
    assert plain.lifted  # type: ignore[attr-defined]
    assert predicted.lifted  # type: ignore[attr-defined]
    np.testing.assert_allclose(
        predicted.series.object_com_z_m,  # type: ignore[attr-defined]
        plain.series.object_com_z_m,  # type: ignore[attr-defined]
        rtol=0,
        atol=3e-9,
    )
    assert predicted_stats[2] < plain_stats[2]  # rounds
    assert predicted_stats[1] < plain_stats[1]  # CG iterations
    assert predicted_stats[3] == 0  # every solve converged
