"""The exact compression of a Kelvin–Voigt object, ``k d + c d' = f``, under a piecewise-linear
force (:func:`kelvin_voigt_piecewise_linear`): the known truth of the examples' recordings and of
the synthetic squeezes of :mod:`deformctl.testing.kelvin_voigt`.
"""

from __future__ import annotations

import math

import numpy as np

from deformctl.series import FloatArray


def kelvin_voigt_piecewise_linear(
    time_s: FloatArray,
    knot_time_s: FloatArray,
    knot_force_n: FloatArray,
    stiffness_n_per_m: float,
    damping_ns_per_m: float,
) -> FloatArray:
    """Exact compression of ``k d + c d' = f`` for a piecewise-linear ``f``, ``d(knot0) = 0``.

    On a segment ``f = f0 + b (t − t0)`` the solution is ``d = d_p + (d0 − d_p(t0)) e^{−(t−t0)/τ}``
    with ``d_p(t) = f(t)/k − b c/k²`` and ``τ = c/k``; for ``c = 0``, ``d = f/k``.

    Args:
        time_s: evaluation times ``[n]`` within ``[knot_time_s[0], knot_time_s[-1]]``.
        knot_time_s: breakpoints ``[K]``, increasing.
        knot_force_n: force at the breakpoints ``[K]``, N.
        stiffness_n_per_m: k.
        damping_ns_per_m: c ≥ 0.

    Returns:
        Compression ``[n]``, m.
    """
    k, c = stiffness_n_per_m, damping_ns_per_m
    f_t = np.interp(time_s, knot_time_s, knot_force_n)
    if c == 0.0:
        return f_t / k
    tau = c / k
    slopes = np.diff(knot_force_n) / np.diff(knot_time_s)
    d0 = np.zeros(knot_time_s.shape[0])
    for j, b in enumerate(slopes):
        h = knot_time_s[j + 1] - knot_time_s[j]
        dp0 = knot_force_n[j] / k - b * c / k**2
        dp1 = knot_force_n[j + 1] / k - b * c / k**2
        d0[j + 1] = dp1 + (d0[j] - dp0) * math.exp(-h / tau)
    seg = np.clip(np.searchsorted(knot_time_s, time_s, side="right") - 1, 0, slopes.shape[0] - 1)
    b_t = slopes[seg]
    t0 = knot_time_s[seg]
    dp_t = f_t / k - b_t * c / k**2
    dp_t0 = knot_force_n[seg] / k - b_t * c / k**2
    out: FloatArray = dp_t + (d0[seg] - dp_t0) * np.exp(-(time_s - t0) / tau)
    return out
