"""Split-conformal upper bounds: the finite-sample rank rule and coverage on a known noise law."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformctl.grip.conformal import (
    conformal_margin,
    conformal_rank,
    coverage_report,
    relative_scores,
    upper_bound,
)


@pytest.mark.parametrize(
    ("n", "p", "k"),
    [(9, 0.9, 9), (8, 0.9, 9), (99, 0.9, 90), (100, 0.9, 91), (19, 0.95, 19), (100, 0.95, 96)],
)
def test_rank_is_the_ceiling_of_n_plus_one_times_p(n: int, p: float, k: int) -> None:
    assert conformal_rank(n, p) == k


def test_margin_is_the_kth_smallest_score_or_inf() -> None:
    scores = np.arange(10.0)[::-1] / 100.0  # 0.09 .. 0.00, unsorted
    assert conformal_margin(scores, 0.5) == pytest.approx(0.05)  # k = ceil(5.5) = 6
    assert conformal_margin(scores, 0.9) == pytest.approx(0.09)  # k = ceil(9.9) = 10 = n
    assert conformal_margin(scores, 0.95) == math.inf  # k = 11 > 10
    assert np.all(np.isinf(upper_bound(np.array([1.0, 2.0]), math.inf)))


@pytest.mark.parametrize("bad", [0.0, 1.0, -0.1, 1.5, math.nan, math.inf])
def test_coverage_outside_the_open_unit_interval_is_refused(bad: float) -> None:
    with pytest.raises(ValueError, match="coverage must be a number in"):
        conformal_margin(np.zeros(5), bad)


def test_relative_scores_need_positive_predictions() -> None:
    assert relative_scores([2.0, 1.0], [1.0, 2.0]).tolist() == [1.0, -0.5]
    with pytest.raises(ValueError, match="predictions > 0"):
        relative_scores([1.0], [0.0])


@pytest.mark.parametrize(("n", "p"), [(30, 0.9), (100, 0.9), (100, 0.95), (200, 0.95)])
def test_coverage_on_a_known_noise_law(n: int, p: float) -> None:
    """y = ŷ (1 + ε), ε ~ N(0.01, 0.03²): given the calibration draw, the bound covers a new
    object with probability F(q) (F: ε's CDF), and over calibration draws F(q) ~ Beta(k, n+1-k),
    whose mean k / (n + 1) is >= P (the guarantee) and < P + 1 / (n + 1). 4000 seeded draws:
    the mean of F(q) within 4 standard errors of k / (n + 1), and an empirical check on fresh
    test rows agrees."""
    from scipy.stats import norm

    rng = np.random.default_rng(20240601)
    mu, sigma, trials, m = 0.01, 0.03, 4000, 50
    k = conformal_rank(n, p)
    pred_cal = rng.uniform(1.0, 100.0, (trials, n))
    y_cal = pred_cal * (1.0 + rng.normal(mu, sigma, (trials, n)))
    q = np.array(
        [conformal_margin(relative_scores(y, x), p) for y, x in zip(y_cal, pred_cal, strict=True)]
    )
    cover_prob = norm.cdf(q, mu, sigma)
    pred_test = rng.uniform(1.0, 100.0, (trials, m))
    y_test = pred_test * (1.0 + rng.normal(mu, sigma, (trials, m)))
    empirical = np.mean(y_test <= upper_bound(pred_test, 0.0) * (1.0 + q[:, None]), axis=1)
    expected = k / (n + 1)
    beta_sd = math.sqrt(expected * (1 - expected) / (n + 2))
    assert expected >= p
    assert expected < p + 1.0 / (n + 1)
    assert abs(cover_prob.mean() - expected) < 4 * beta_sd / math.sqrt(trials)
    assert abs(empirical.mean() - expected) < 4 * math.sqrt(beta_sd**2 + expected / m) / math.sqrt(
        trials
    )


def test_coverage_report_on_rows_the_bound_has_not_seen() -> None:
    rng = np.random.default_rng(3)
    pred = rng.uniform(1.0, 10.0, 2000)
    y = pred * (1.0 + rng.uniform(-0.05, 0.05, 2000))
    scores = relative_scores(y[:1000], pred[:1000])
    report = coverage_report(scores, y[1000:], pred[1000:])
    assert set(report) == {"0.9", "0.95"}
    assert report["0.9"]["coverage"] == pytest.approx(0.9, abs=0.03)
    assert report["0.95"]["coverage"] == pytest.approx(0.95, abs=0.02)
    # margin of the uniform law at P: 0.05 (2P - 1); mean margin = E[(1 + q) / (1 + ε)] - 1
    assert report["0.9"]["margin"] == pytest.approx(0.04, abs=0.004)
    assert report["0.9"]["mean_margin"] == pytest.approx(0.04, abs=0.004)
    assert report["0.9"]["rank"] == 901
