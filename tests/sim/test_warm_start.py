"""The iterative solver's warm start (deformctl.sim.step.iterative._warm_start) and what it buys."""

from __future__ import annotations

import numpy as np
import pytest

from deformctl.sim import LiftProfile, ObjectSpec, SimSettings, lift_attempt, rigid_lift_force_n
from deformctl.sim.engine import build_model
from deformctl.sim.step.iterative import _warm_start

CUBE = ObjectSpec("cube", (10.0, 10.0, 10.0), 5.0, 0.5, 30.0, 1.0)


def _guess_and_image(dv_hist, y_hist, order, n_hist, fixed, rhs):  # type: ignore[no-untyped-def]
    out = np.full(rhs.shape[0], np.nan)
    image = np.full(rhs.shape[0], np.nan)
    err = np.zeros(dv_hist.shape[0])
    order = np.asarray(order, dtype=np.int64)
    _warm_start(dv_hist, y_hist, order, n_hist, fixed, rhs, out, image, err, np.zeros(4), False)
    return out, image


def _guess(dv_hist, y_hist, order, n_hist, fixed, rhs):  # type: ignore[no-untyped-def]
    return _guess_and_image(dv_hist, y_hist, order, n_hist, fixed, rhs)[0]


def test_short_history_is_the_linear_extrapolation() -> None:
    rng = np.random.default_rng(0)
    dv = rng.normal(size=(3, 20))
    y = rng.normal(size=(3, 20))
    fixed = np.zeros(20, dtype=bool)
    rhs = rng.normal(size=20)
    assert np.array_equal(_guess(dv, y, [2, 0, 1], 0, fixed, rhs), np.zeros(20))
    assert np.array_equal(_guess(dv, y, [2, 0, 1], 1, fixed, rhs), 2.0 * dv[2])
    # no image yet (the first steps from rest): the extrapolation from the newest two
    assert np.array_equal(
        _guess(dv, np.zeros_like(y), [1, 0, 2], 2, fixed, rhs), 2.0 * dv[1] - dv[0]
    )
    # identical images: the ridge keeps the small system solvable and the guess finite, and it
    # still fits the right-hand side at least as well as the extrapolation
    y_same = np.stack([y[0], y[0], y[0]])
    guess = _guess(dv, y_same, [1, 0, 2], 3, fixed, rhs)
    assert np.all(np.isfinite(guess))
    assert np.all(np.abs(guess) < 1e3 * np.abs(dv).max())


def test_the_guess_comes_with_its_image_from_the_same_combination() -> None:
    """``adv`` is the same combination of the images as the guess is of the velocity changes:
    with images ``y_k = A dv_k`` it is ``A`` times the guess, on every path (no history, one
    step, the extrapolation, the least squares), fixed DOFs included."""
    rng = np.random.default_rng(2)
    n = 60
    a = rng.normal(size=(n, n))
    a = a @ a.T + n * np.eye(n)
    dv = rng.normal(size=(3, n))
    fixed = np.zeros(n, dtype=bool)
    fixed[::7] = True
    rhs = rng.normal(size=n)
    for n_hist, y in ((0, dv @ a.T), (1, dv @ a.T), (3, dv @ a.T), (3, np.zeros((3, n)))):
        guess, image = _guess_and_image(dv, y, [1, 2, 0], n_hist, fixed, rhs)
        if n_hist == 3 and not y.any():  # no images: the extrapolation, and its (zero) image
            assert np.array_equal(guess, 2.0 * dv[1] - dv[2])
            assert np.array_equal(image, np.zeros(n))
            continue
        want = a @ guess
        np.testing.assert_allclose(image, want, rtol=1e-10, atol=1e-10 * np.abs(want).max())


def test_the_carried_gram_sums_give_the_same_bits_as_a_full_pass() -> None:
    """A step later the history has moved by one image: with the same free DOFs the sums
    carried from the call before are the ones a full pass forms, so guess, image and error bound
    are bit for bit those of a full pass; with other free DOFs nothing is carried."""
    rng = np.random.default_rng(5)
    n = 50
    dv = rng.normal(size=(4, n))
    y = rng.normal(size=(4, n))
    err = np.abs(rng.normal(size=4))
    fixed = np.zeros(n, dtype=bool)
    fixed[::6] = True
    rhs = [rng.normal(size=n), rng.normal(size=n)]
    gram = np.zeros(4)
    args = (np.zeros(n), np.zeros(n), err)
    # step 1 on images 2, 1, 0 (newest first), step 2 on 3, 2, 1: carried or formed afresh
    _warm_start(dv, y, np.array([2, 1, 0]), 3, fixed, rhs[0], *args, gram, False)
    order = np.array([3, 2, 1])
    carried = (np.zeros(n), np.zeros(n))
    fresh = (np.zeros(n), np.zeros(n))
    bound_carried = _warm_start(dv, y, order, 3, fixed, rhs[1], *carried, err, gram, True)
    bound_fresh = _warm_start(dv, y, order, 3, fixed, rhs[1], *fresh, err, np.zeros(4), False)
    assert bound_carried == bound_fresh
    assert np.array_equal(carried[0], fresh[0])
    assert np.array_equal(carried[1], fresh[1])
    # the carried sums are used only when the caller says the free DOFs are the same: wrong
    # sums with same_free False change nothing (the call overwrites them, so a new copy each)
    wrong = np.array([1e9, -1e9, 1e9, 1.0])
    other = (np.zeros(n), np.zeros(n))
    _warm_start(dv, y, order, 3, fixed, rhs[1], *other, err, wrong.copy(), False)
    assert np.array_equal(other[0], fresh[0])
    used = (np.zeros(n), np.zeros(n))
    _warm_start(dv, y, order, 3, fixed, rhs[1], *used, err, wrong.copy(), True)
    assert not np.array_equal(used[0], fresh[0])  # the test can see a carried sum


def test_least_squares_recovers_a_combination_and_beats_extrapolation() -> None:
    rng = np.random.default_rng(1)
    n = 200
    a = rng.normal(size=(n, n))
    a = a @ a.T + n * np.eye(n)
    dv = rng.normal(size=(3, n))
    y = dv @ a.T  # y_k = A dv_k
    fixed = np.zeros(n, dtype=bool)
    fixed[rng.choice(n, 30, replace=False)] = True
    # a right-hand side in the span: the guess is that combination
    want = 0.3 * dv[0] - 1.7 * dv[1] + 2.2 * dv[2]
    got = _guess(dv, y, [0, 1, 2], 3, fixed, a @ want)
    assert np.allclose(got, want, rtol=1e-8, atol=1e-10)
    # a longer history: its newest three
    dv4 = np.vstack([dv, rng.normal(size=(1, n))])
    y4 = dv4 @ a.T
    assert np.allclose(_guess(dv4, y4, [0, 1, 2, 3], 4, fixed, a @ want), want, rtol=1e-8)
    # with two kept: the combination of the newest two
    want2 = 0.8 * dv[2] - 0.4 * dv[0]
    got2 = _guess(dv, y, [2, 0, 1], 2, fixed, a @ want2)
    assert np.allclose(got2, want2, rtol=1e-8, atol=1e-10)
    # any right-hand side: the free residual is no larger than the linear extrapolation's
    for trial in range(20):
        rhs = rng.normal(size=n) + 3.0 * (a @ dv[0]) * trial / 20
        guess = _guess(dv, y, [0, 1, 2], 3, fixed, rhs)
        lin = 2.0 * dv[0] - dv[1]
        free = ~fixed
        assert np.linalg.norm((rhs - a @ guess)[free]) <= np.linalg.norm((rhs - a @ lin)[free]) * (
            1 + 1e-12
        )


@pytest.mark.parametrize("n", [8, 13])
def test_a_lift_attempt_needs_at_most_one_cg_iteration_per_step(n: int) -> None:
    """Measured: 0.51 (8^3) and 0.80 (13^3) CG iterations per solve; 1.24 and 1.69 with the
    linear extrapolation it replaces."""
    settings = SimSettings(particles_per_side=n)
    grip = 1.2 * rigid_lift_force_n(CUBE, LiftProfile())
    model = build_model(CUBE, settings, gripped=True, resting=True, table=True)
    model.solver_stats[:] = 0
    outcome = lift_attempt(CUBE, grip, settings=settings)
    assert outcome.lifted
    solves, iterations, _, unconverged = model.solver_stats[:4]
    assert unconverged == 0
    assert solves > 1000
    assert iterations / solves <= 1.0, iterations / solves


def test_carrying_the_product_changes_nothing_but_the_cost(monkeypatch: pytest.MonkeyPatch) -> None:
    """CG starts from the carried ``A dv`` (the warm start's images) in most steps, and the lift
    is the one it gives when the product is formed every step: the same verdict, the centre of
    mass within 3e-9 m. Both are CG solutions to the same tolerance, which alone moves the path by
    about 1e-9 m (see the engine's docstring); measured here at 6^3: 1.1e-9 m, with 0.3
    explicit products per step instead of 1."""
    from deformctl.sim import engine

    settings = SimSettings(particles_per_side=6, solver="iterative")
    grip = 1.2 * rigid_lift_force_n(CUBE, LiftProfile())
    model = build_model(CUBE, settings, gripped=True, resting=True, table=True)
    runs = {}
    for fraction in (engine.PRODUCT_CARRY_FRACTION, 0.0):
        monkeypatch.setattr(engine, "PRODUCT_CARRY_FRACTION", fraction)
        model.solver_stats[:] = 0
        outcome = lift_attempt(CUBE, grip, settings=settings)
        assert outcome.series is not None
        steps = outcome.series.time_s.size
        runs[fraction] = (outcome, model.solver_stats[4] / (steps - 1))
    (carried, carried_rate), (formed, formed_rate) = runs.values()
    assert formed_rate >= 1.0  # fraction 0: a product every step (the first starts from 0)
    assert carried_rate <= 0.5, carried_rate
    assert carried.lifted == formed.lifted
    assert carried.series is not None
    assert formed.series is not None
    np.testing.assert_allclose(
        carried.series.object_com_z_m, formed.series.object_com_z_m, rtol=0, atol=3e-9
    )
