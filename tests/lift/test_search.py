"""The lifting-force search against a threshold runner whose true answer is known.

A threshold runner lifts iff the grip force is >= T, so the true minimum lifting force is
max(T, F_w) and every claim below is checked against closed-form numbers.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformctl.errors import (
    EXIT_FAILURE,
    RigError,
    SearchError,
    SimulationError,
    UsageError,
)
from deformctl.lift import (
    DEFAULT_TOLERANCE_REL,
    LiftSearchResult,
    RigSearchAbortedError,
    SearchAbortedError,
    find_min_lift_force,
    rigid_grip_force_n,
)
from deformctl.series import TrialOutcome
from tests._helpers.lift import ThresholdRunner


def _forces(result: LiftSearchResult) -> list[float]:
    return [t.grip_force_n for t in result.trials]


# W = 10 N, mu = 0.5 -> F_w = 10 N; ramp 10, 12, 14.4, 17.28; T = 17 N lifts first at 17.28 N.
W_N, MU, T_N = 10.0, 0.5, 17.0


def test_rigid_grip_force_is_weight_over_two_mu() -> None:
    assert rigid_grip_force_n(W_N, MU) == pytest.approx(10.0)
    assert rigid_grip_force_n(3.0, 0.3) == pytest.approx(5.0)


def test_paper_ramp_multiplies_by_growth_until_lifted() -> None:
    runner = ThresholdRunner(T_N)
    r = find_min_lift_force(runner, weight_n=W_N, friction_mu=MU, protocol="paper", object_id="A")
    assert _forces(r) == pytest.approx([10.0, 12.0, 14.4, 17.28])
    assert [i for _, i in runner.calls] == [0, 1, 2, 3]
    assert r.lift_force_n == pytest.approx(17.28)
    assert r.f_w_n == pytest.approx(10.0)
    assert r.f_d_n == pytest.approx(7.28)
    assert r.bracket_n == pytest.approx((14.4, 17.28))
    assert r.attempts == 4
    assert r.converged
    assert r.protocol == "paper"
    assert r.growth == 1.2
    assert "'A'" in r.message
    assert "17.28" in r.message


def test_refine_reproduces_paper_ramp_then_bisects_to_tolerance() -> None:
    paper = find_min_lift_force(
        ThresholdRunner(T_N), weight_n=W_N, friction_mu=MU, protocol="paper"
    )
    refine = find_min_lift_force(ThresholdRunner(T_N), weight_n=W_N, friction_mu=MU)
    assert refine.protocol == "refine"
    assert _forces(refine)[:4] == _forces(paper)
    assert refine.ramp_attempts == 4
    assert refine.paper_bracket_n == pytest.approx(paper.bracket_n)
    # The bracket [14.4, 17.28] (2.88 N wide) halves per step; the default 0.5 % of L_f (~17 N)
    # is ~0.085 N: 2.88 / 32 = 0.09 > 0.085 and 2.88 / 64 = 0.045 <= 0.085, so 6 bisection steps.
    assert DEFAULT_TOLERANCE_REL == 0.005
    assert refine.attempts == 4 + 6
    low, high = refine.bracket_n
    assert (high - low) / high <= 0.005
    assert high == refine.lift_force_n
    assert T_N <= refine.lift_force_n <= T_N / (1 - 0.005)
    assert 14.4 < refine.lift_force_n <= 17.28
    assert paper.lift_force_n <= 1.2 * refine.lift_force_n
    assert refine.converged
    # Only forces that were tried and lifted are reported.
    assert any(t.lifted and t.grip_force_n == refine.lift_force_n for t in refine.trials)
    assert not ThresholdRunner(T_N)(0.97 * refine.lift_force_n, 99).lifted


@pytest.mark.parametrize("protocol", ["paper", "refine"])
@pytest.mark.parametrize("threshold_n", [0.0, 5.0, 10.0])
def test_fw_lifting_at_once_gives_lf_equal_fw(protocol: str, threshold_n: float) -> None:
    r = find_min_lift_force(
        ThresholdRunner(threshold_n),
        weight_n=W_N,
        friction_mu=MU,
        protocol=protocol,  # type: ignore[arg-type]
    )
    assert r.lift_force_n == r.f_w_n == pytest.approx(10.0)
    assert r.f_d_n == 0.0
    assert r.bracket_n == (r.f_w_n, r.f_w_n)
    assert r.attempts == 1
    assert r.converged


def test_never_lifts_within_max_attempts() -> None:
    r = find_min_lift_force(
        ThresholdRunner(1e9), weight_n=W_N, friction_mu=MU, max_attempts=5, object_id="brick-7"
    )
    last_n = 10.0 * 1.2**4  # 20.736 N
    assert r.attempts == 5
    assert not r.converged
    assert not r.lifted
    assert math.isnan(r.lift_force_n)
    assert math.isnan(r.f_d_n)
    assert r.last_force_n == pytest.approx(last_n)
    assert r.bracket_n == (pytest.approx(last_n), math.inf)
    assert "'brick-7'" in r.message
    assert "20.736 N" in r.message
    assert "\n" not in r.message


def test_refine_out_of_attempts_during_bisection_reports_tried_upper_bound() -> None:
    r = find_min_lift_force(ThresholdRunner(T_N), weight_n=W_N, friction_mu=MU, max_attempts=6)
    assert r.attempts == 6
    assert not r.converged
    assert r.lifted
    low, high = r.bracket_n
    assert (high - low) / high > DEFAULT_TOLERANCE_REL
    assert r.lift_force_n == high >= T_N
    assert any(t.lifted and t.grip_force_n == high for t in r.trials)
    assert "tolerance" in r.message


def test_tolerance_below_float_resolution_terminates() -> None:
    r = find_min_lift_force(
        ThresholdRunner(math.pi * 10), weight_n=W_N, friction_mu=MU, tolerance_rel=1e-300,
        max_attempts=10_000,
    )  # fmt: skip
    assert not r.converged
    assert r.attempts < 100  # about 52 halvings reach the float spacing of ~31 N
    assert "floating-point" in r.message
    assert r.lift_force_n >= math.pi * 10


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"friction_mu": 0.0}, "friction_mu must be a number in"),
        ({"friction_mu": -0.3}, "friction_mu must be a number in"),
        ({"friction_mu": math.nan}, "friction_mu must be a number in"),
        ({"weight_n": 0.0}, "weight_n must be a number in"),
        ({"weight_n": -1.0}, "weight_n must be a number in"),
        ({"weight_n": math.inf}, "weight_n must be a number in"),
        ({"tolerance_rel": 0.0}, "tolerance must be"),
        ({"tolerance_rel": -0.01}, "tolerance must be"),
        ({"tolerance_rel": 1.0}, "tolerance must be"),
        ({"growth": 1.0}, "growth must be"),
        ({"growth": 0.8}, "growth must be"),
        ({"max_attempts": 0}, "--max-attempts must be"),
        ({"max_attempts": 2.5}, "--max-attempts must be"),
        ({"protocol": "bisect"}, "protocol must be one of"),
    ],
)
def test_bad_parameters_raise_one_line_usage_error(
    kwargs: dict[str, object], fragment: str
) -> None:
    runner = ThresholdRunner(T_N)
    params: dict[str, object] = {"weight_n": W_N, "friction_mu": MU, "object_id": "A"} | kwargs
    with pytest.raises(UsageError, match=fragment) as info:
        find_min_lift_force(runner, **params)  # type: ignore[arg-type]
    assert "\n" not in str(info.value)
    assert info.value.exit_code == 2
    assert runner.calls == []  # nothing was run


def _failing_runner(error: Exception, at_index: int) -> Callable[[float, int], TrialOutcome]:
    inner = ThresholdRunner(T_N)

    def run(grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        if attempt_index == at_index:
            raise error
        return inner(grip_force_n, attempt_index)

    return run


def test_rig_failure_mid_search_keeps_partial_attempts() -> None:
    runner = _failing_runner(RigError("rig: encoder lost"), at_index=2)
    with pytest.raises(RigSearchAbortedError) as info:
        find_min_lift_force(runner, weight_n=W_N, friction_mu=MU, object_id="sponge")
    err = info.value
    assert isinstance(err, RigError)
    assert isinstance(err, SearchError)
    assert err.exit_code == EXIT_FAILURE
    assert "\n" not in str(err)
    assert "'sponge'" in str(err)
    assert "attempt 2 at 14.4 N" in str(err)
    assert str(err) == "search aborted, 2 attempts kept: object 'sponge': attempt 2 at 14.4 N: " + (
        "rig: encoder lost"
    )
    assert isinstance(err.__cause__, RigError)
    partial = err.partial
    assert _forces(partial) == pytest.approx([10.0, 12.0])
    assert partial.attempts == 2
    assert not partial.converged
    assert math.isnan(partial.lift_force_n)


def test_simulation_failure_is_a_search_error_not_a_rig_error() -> None:
    runner = _failing_runner(SimulationError("non-finite state"), at_index=5)
    with pytest.raises(SearchAbortedError) as info:
        find_min_lift_force(runner, weight_n=W_N, friction_mu=MU)
    assert not isinstance(info.value, RigError)
    # Failed in the bisection: the partial keeps the best tried force that lifted.
    assert info.value.partial.attempts == 5
    assert info.value.partial.lift_force_n == pytest.approx(17.28)


def test_runner_returning_wrong_type_is_a_bug() -> None:
    with pytest.raises(TypeError, match="not TrialOutcome"):
        find_min_lift_force(lambda f, i: (f, True), weight_n=W_N, friction_mu=MU)  # type: ignore[arg-type,return-value]


def test_summary_is_scalar_row() -> None:
    r = find_min_lift_force(ThresholdRunner(T_N), weight_n=W_N, friction_mu=MU, object_id="A")
    row = r.summary()
    assert row["lift_force_n"] == r.lift_force_n
    assert row["bracket_low_n"] == r.bracket_n[0]
    assert row["converged"] is True
    assert "trials" not in row


@settings(max_examples=300, deadline=None)
@given(
    weight_n=st.floats(0.01, 1000.0),
    friction_mu=st.floats(0.05, 2.0),
    threshold_over_fw=st.floats(0.1, 1000.0),
    tolerance_rel=st.floats(1e-4, 0.029),
    growth=st.floats(1.01, 3.0),
)
def test_search_invariants_hold_for_any_threshold(
    weight_n: float, friction_mu: float, threshold_over_fw: float, tolerance_rel: float,
    growth: float,
) -> None:  # fmt: skip
    f_w_n = rigid_grip_force_n(weight_n, friction_mu)
    threshold_n = threshold_over_fw * f_w_n
    # A budget large enough for any case here: the invariants are about the answer, not the budget
    # (the budget rule is tested above). growth 1.01 from 0.1 to 1000 x F_w needs ~700 ramp steps.
    common = {"weight_n": weight_n, "friction_mu": friction_mu, "growth": growth}
    budget = 2000
    paper = find_min_lift_force(
        ThresholdRunner(threshold_n), protocol="paper", max_attempts=budget, **common
    )
    refine = find_min_lift_force(
        ThresholdRunner(threshold_n),
        protocol="refine",
        tolerance_rel=tolerance_rel,
        max_attempts=budget,
        **common,
    )
    for r in (paper, refine):
        assert r.converged
        assert r.lift_force_n >= r.f_w_n
        assert all(f >= r.f_w_n for f in _forces(r))
        assert any(t.lifted and t.grip_force_n == r.lift_force_n for t in r.trials)
        assert r.lift_force_n >= threshold_n  # it lifted, so it is at or above the threshold
    # refine replays the paper ramp, then stays inside the paper's last bracket.
    assert _forces(refine)[: paper.attempts] == _forces(paper)
    p_low, p_high = paper.bracket_n
    assert p_low <= refine.lift_force_n <= p_high
    assert paper.lift_force_n <= growth * refine.lift_force_n * (1 + 1e-12)
    # refine is within tolerance above the true minimum max(T, F_w) ...
    true_n = max(threshold_n, f_w_n)
    assert (refine.lift_force_n - true_n) / refine.lift_force_n <= tolerance_rel
    # ... and 3 % less slips whenever the answer is above F_w (F_w is reported by definition).
    if refine.lift_force_n > f_w_n:
        assert not ThresholdRunner(threshold_n)(0.97 * refine.lift_force_n, 0).lifted
    # Bisection cost: the width halves per step and high >= low_0 = high_0 / growth, so
    # (high - low) / high <= (growth - 1) / 2**n; n = ceil(log2((growth - 1) / tol)) steps suffice.
    if refine.attempts > paper.attempts:
        assert refine.attempts - paper.attempts <= math.ceil(
            math.log2((growth - 1) / tolerance_rel)
        )


def test_ramp_overflow_stops_without_trying_an_infinite_force() -> None:
    runner = ThresholdRunner(math.inf)
    r = find_min_lift_force(runner, weight_n=W_N, friction_mu=MU, growth=1e100, max_attempts=100)
    assert not r.converged
    assert all(math.isfinite(f) for f, _ in runner.calls)
    assert r.attempts == 4  # 10 * 1e100**k is finite for k <= 3 (max float ~1.8e308)
    assert "overflowed" in r.message


def test_the_package_face_is_the_search_s_public_names() -> None:
    # deformctl/lift/__init__.py names the search's public names (its lazy face must name them
    # without importing the search): the two lists stay the same, and each name resolves to
    # the search's own object
    import deformctl.lift as face
    import deformctl.lift.search as search

    assert sorted(face.__all__) == sorted(search.__all__)
    for name in search.__all__:
        assert getattr(face, name) is getattr(search, name)
