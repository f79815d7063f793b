"""deformctl.plausibility's own rules: the bands it applies live with their quantities, and the
implied damping ratio ζ = λ / (2 √(D m)) against its closed form, flagged on both sides of 1000.

(Moved here from tests/measure/test_two_sided.py, which keeps the recordings judged end to end.)
"""

from __future__ import annotations

import math

import pytest

from deformctl import plausibility, quantities
from deformctl.plausibility import damping_ratio_doubt, implied_damping_ratio
from deformctl.units import GRAVITY_M_S2


def test_the_bands_live_with_their_quantities() -> None:
    assert plausibility.MIN_RATE_HZ == quantities.RECORDED_RATE_HZ.low == 1.0
    assert plausibility.MAX_RATE_HZ == quantities.RECORDED_RATE_HZ.high == 1e5
    assert plausibility.MIN_UNSTATED_RATE_HZ == quantities.RECORDED_RATE_HZ.doubt_low == 10.0
    assert plausibility.MAX_PEAK_FORCE_N == quantities.RECORDED_PEAK_FORCE_N.high == 1e4
    assert plausibility.MIN_PEAK_FORCE_N == quantities.RECORDED_PEAK_FORCE_N.doubt_low == 0.05
    assert quantities.RECORDED_PEAK_FORCE_N.doubt_high == plausibility.DOUBTFUL_PEAK_FORCE_N
    assert quantities.RECORDED_PEAK_COMPRESSION_M.doubt_low == plausibility.MIN_PEAK_COMPRESSION_M
    assert quantities.RECORDED_SECANT_N_PER_CM.doubt_high == plausibility.MAX_SECANT_N_PER_CM
    assert plausibility.MAX_DAMPING_RATIO == quantities.IMPLIED_DAMPING_RATIO.doubt_high == 1000
    force = quantities.RECORDED_PEAK_FORCE_N
    assert [force.refused(v) for v in (-1.0, 0.0, 5.0, 1e4, 1.1e4)] == [
        True, False, False, False, True,
    ]  # fmt: skip
    assert [force.doubtful(v) for v in (0.01, 0.05, 10.0, 3000.0, 3001.0, 2e4)] == [
        True, False, False, False, True, False,
    ]  # fmt: skip


def test_the_implied_damping_ratio_is_the_closed_form() -> None:
    """The paper's sponge (Table I, A): D = 49.18 N/cm, λ = 6.47 N·s/cm, W = 0.7 N."""
    m = 0.7 / GRAVITY_M_S2
    expected = 647.0 / (2.0 * math.sqrt(4918.0 * m))
    assert implied_damping_ratio(49.18, 6.47, 0.7) == pytest.approx(expected, rel=1e-12)
    assert 17.2 < expected < 17.3
    assert math.isnan(implied_damping_ratio(0.0, 6.47, 0.7))
    assert math.isnan(implied_damping_ratio(49.18, math.nan, 0.7))
    assert damping_ratio_doubt(expected, time_unit_stated=True) is None  # right: silent
    stated = damping_ratio_doubt(1000 * expected, time_unit_stated=True)  # ms read as s
    assert stated == (
        "damping_ratio_implausible",
        "implied damping ratio ζ = λ / (2 √(D m)) = 1.73e+04 is above 1000; plausible with time "
        "stamps 1,000 times shorter (ms read as s?): is the time unit right?",
    )
    us = damping_ratio_doubt(1e6 * expected, time_unit_stated=True)
    assert us is not None
    assert "1,000,000 times shorter (µs read as s?)" in us[1]
    hopeless = damping_ratio_doubt(1e12, time_unit_stated=True)
    assert hopeless is not None
    assert "no time unit fixes it" in hopeless[1]
    unstated = damping_ratio_doubt(1000 * expected, time_unit_stated=False)
    assert unstated is not None
    assert unstated[0] == "time_unit_doubtful"
    assert unstated[1].startswith("time unit not stated and implied damping ratio")


def test_zeta_scales_as_the_closed_form_says() -> None:
    """ζ ∝ λ, ∝ 1/√D, ∝ 1/√W: the units cancel the same way at every size."""
    base = implied_damping_ratio(20.0, 3.0, 1.0)
    assert base == pytest.approx(300.0 / (2.0 * math.sqrt(2000.0 / GRAVITY_M_S2)), rel=1e-12)
    assert implied_damping_ratio(20.0, 6.0, 1.0) == pytest.approx(2 * base, rel=1e-12)
    assert implied_damping_ratio(80.0, 3.0, 1.0) == pytest.approx(base / 2, rel=1e-12)
    assert implied_damping_ratio(20.0, 3.0, 4.0) == pytest.approx(base / 2, rel=1e-12)
    assert implied_damping_ratio(20.0, 0.0, 1.0) == 0.0  # undamped


@pytest.mark.parametrize("bad", [None, "x", math.inf, -1.0])
def test_zeta_is_nan_when_an_input_is_missing_or_impossible(bad: object) -> None:
    assert math.isnan(implied_damping_ratio(bad, 3.0, 1.0))
    assert math.isnan(implied_damping_ratio(20.0, 3.0, bad))
    if bad != -1.0:  # a negative λ is refused elsewhere (DAMPING_NS_PER_CM)
        assert math.isnan(implied_damping_ratio(20.0, bad, 1.0))


def test_the_doubt_fires_above_1000_and_not_at_or_below() -> None:
    assert damping_ratio_doubt(999.0, time_unit_stated=True) is None
    assert damping_ratio_doubt(1000.0, time_unit_stated=True) is None
    assert damping_ratio_doubt(0.0, time_unit_stated=False) is None
    assert damping_ratio_doubt(math.nan, time_unit_stated=False) is None
    above = damping_ratio_doubt(1001.0, time_unit_stated=True)
    assert above is not None
    assert above[0] == "damping_ratio_implausible"
    assert "ms read as s?" in above[1]


def test_an_infinite_damping_ratio_is_doubtful_and_nan_is_not_judged() -> None:
    flag, text = damping_ratio_doubt(math.inf, time_unit_stated=True) or ("", "")
    assert flag == "damping_ratio_implausible"
    assert "= inf is above 1000" in text
    assert damping_ratio_doubt(math.nan, time_unit_stated=True) is None
