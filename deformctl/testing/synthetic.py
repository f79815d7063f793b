"""Synthetic recordings with known truth: each material law, a rupture with back-off, a relaxation.

Ground truth for the tests and the docs' examples. Every recording is made on a grid
:data:`FINE` times finer than its sample rate and then sampled, so the fit never sees the
generator's own discretisation; the force is delayed by a lag (the force sensor's latency) and
seeded Gaussian noise is added to force and compression.

* :func:`synthetic_law_squeeze`: a testing-machine squeeze (position control) of a ``kv``,
  ``hc``, ``sls`` or ``exp`` material: a ramp at one speed to a peak compression, a hold, and a
  release at another speed (two speeds and a hold, so damping is identifiable), velocity corners
  smoothed over ``corner_s``.
* :func:`synthetic_rupture_backoff`: a force-controlled gripper squeezing a Kelvin–Voigt object
  that collapses at a known force, after which the controller backs off while the gripper holds
  its position.
* :func:`synthetic_relaxation_hold`: a standard linear solid pressed to a compression and held:
  the force decays smoothly at constant position (stress relaxation, not rupture).
* :func:`synthetic_ramp_hold`: the textbook recording of any law: one ramp at one speed to a
  compression, then a hold, sampled slowly with a force noise in newtons (no lag, no position
  noise). Its hold identifies damping; a ramp alone (``hold_s=0``) does not.
* :func:`synthetic_force_hold_squeeze`: one of :data:`FORCE_HOLD_SHAPES`, force-controlled
  squeezes of a heavily damped Kelvin–Voigt fruit whose controller lowers the force while the
  jaws hold: a standard linear solid fits them best with its stiffness at 0 (a fluid), the
  degenerate law ``auto`` must never choose.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from deformctl.characterize.laws import law_force
from deformctl.series import FloatArray, SqueezeSeries

#: Generation grid: this many sub-steps per sample.
FINE = 10


def _velocity_profile(
    t: FloatArray, knots: list[tuple[float, float]], corner_s: float
) -> FloatArray:
    """A piecewise-constant velocity (``(start time, velocity)`` knots) with linear blends of
    ``corner_s`` at each change, ``[n]``."""
    v = np.zeros_like(t)
    prev = 0.0
    for start, vel in knots:
        ramp = np.clip((t - start) / corner_s, 0.0, 1.0) if corner_s > 0 else (t >= start) * 1.0
        v += (vel - prev) * ramp
        prev = vel
    return v


def _integrate(v: FloatArray, h: float) -> FloatArray:
    out = np.empty_like(v)
    out[0] = 0.0
    np.cumsum(0.5 * (v[1:] + v[:-1]) * h, out=out[1:])
    return out


def _sample(
    t_fine: FloatArray,
    force: FloatArray,
    comp: FloatArray,
    *,
    rate_hz: float,
    lag_s: float,
    force_noise_n: float,
    position_noise_m: float,
    seed: int,
    object_id: str,
    squeeze_index: int,
) -> SqueezeSeries:
    n = round(t_fine[-1] * rate_hz) + 1
    t = np.arange(n) / rate_hz
    f = np.interp(t - lag_s, t_fine, force, left=force[0])
    d = np.interp(t, t_fine, comp)
    rng = np.random.default_rng(seed)
    return SqueezeSeries(
        object_id=object_id,
        squeeze_index=squeeze_index,
        time_s=t,
        force_n=f + rng.normal(0.0, force_noise_n, n),
        compression_m=d + rng.normal(0.0, position_noise_m, n),
    )


def _grid(duration_s: float, rate_hz: float) -> tuple[FloatArray, float]:
    """The generation grid (times ``[n]`` and step, s) of ``duration_s`` sampled at ``rate_hz``."""
    h = 1.0 / (rate_hz * FINE)
    return np.arange(round(duration_s / h) + 1, dtype=np.float64) * h, h


def _law_squeeze(
    model: str,
    params: Mapping[str, float],
    grid: tuple[FloatArray, float],
    d: FloatArray,
    v: FloatArray,
    *,
    force_noise_rel: float = 0.0,
    force_noise_n: float = 0.0,
    **sample: Any,
) -> SqueezeSeries:
    """A law's squeeze along ``d`` (velocity ``v``) on ``grid``, sampled (:func:`_sample`) with a
    force noise of ``force_noise_n`` plus ``force_noise_rel`` times the peak force."""
    t, h = grid
    force = law_force(model, params, d, v, h)
    noise = force_noise_n + force_noise_rel * float(np.max(np.abs(force)))
    return _sample(t, force, d, force_noise_n=noise, **sample)


def synthetic_law_squeeze(
    model: str,
    params: Mapping[str, float],
    *,
    peak_compression_m: float = 0.01,
    load_s: float = 1.0,
    hold_s: float = 1.0,
    release_s: float = 2.5,
    rest_s: float = 0.5,
    corner_s: float = 0.05,
    rate_hz: float = 500.0,
    lag_s: float = 0.02,
    force_noise_rel: float = 0.005,
    position_noise_m: float = 2e-6,
    seed: int = 0,
    object_id: str = "synthetic",
    squeeze_index: int = 0,
) -> SqueezeSeries:
    """A position-controlled squeeze of a material law with known parameters (SI).

    The compression rises at ``peak/load_s`` to the peak, holds for ``hold_s``, falls at
    ``peak/release_s`` and rests for ``rest_s``; the force is the law's (``params`` as
    :data:`deformctl.characterize.laws.PARAMETERS`, plus an optional ``preload_n``), delayed by
    ``lag_s``, with noise of ``force_noise_rel`` times the peak force and ``position_noise_m``.
    """
    t, h = grid = _grid(load_s + hold_s + release_s + rest_s, rate_hz)
    knots = [(0.0, peak_compression_m / load_s), (load_s, 0.0)]
    if release_s > 0:  # else the squeeze ends with the hold
        knots += [
            (load_s + hold_s, -peak_compression_m / release_s),
            (load_s + hold_s + release_s, 0.0),
        ]
    v = _velocity_profile(t, knots, corner_s)
    return _law_squeeze(
        model, params, grid, _integrate(v, h), v, force_noise_rel=force_noise_rel,
        rate_hz=rate_hz, lag_s=lag_s, position_noise_m=position_noise_m, seed=seed,
        object_id=object_id, squeeze_index=squeeze_index,
    )  # fmt: skip


def synthetic_rupture_backoff(
    *,
    stiffness_n_per_m: float = 1000.0,
    damping_ns_per_m: float = 50.0,
    rupture_force_n: float = 12.0,
    force_rate_n_per_s: float = 8.0,
    collapse_frac: float = 0.2,
    collapse_s: float = 0.03,
    backoff_s: float = 0.6,
    backoff_to_frac: float = 0.1,
    rest_s: float = 0.5,
    rate_hz: float = 200.0,
    lag_s: float = 0.0,
    force_noise_n: float = 0.03,
    position_noise_m: float = 2e-6,
    seed: int = 0,
    object_id: str = "ruptured",
) -> SqueezeSeries:
    """A force-controlled squeeze that ruptures at ``rupture_force_n`` and then backs off.

    The commanded force rises at ``force_rate_n_per_s``; the object is Kelvin–Voigt
    (``k d + c ḋ = f``) until the force reaches the rupture force. It then collapses: the force
    falls by ``collapse_frac`` of the rupture force within ``collapse_s`` (less than a rupture
    detector's 30 % on its own), and the controller backs off, lowering the force to
    ``backoff_to_frac`` of it over ``backoff_s``, while the gripper holds its position (the
    crushed object does not spring back). The true rupture force is ``rupture_force_n``.
    """
    t_r = rupture_force_n / force_rate_n_per_s
    t, _ = _grid(t_r + collapse_s + backoff_s + rest_s, rate_hz)
    k, c = stiffness_n_per_m, damping_ns_per_m
    load = t <= t_r
    f = np.where(load, force_rate_n_per_s * t, 0.0)
    # exact KV compression under a force ramp f = b t
    b = force_rate_n_per_s
    tau = c / k
    d: FloatArray = (b / k) * (t - tau * (1.0 - np.exp(-t / tau))) if c > 0 else b * t / k
    d_r = float(np.interp(t_r, t, d))
    after = ~load
    tc = t[after] - t_r
    collapse = rupture_force_n * (1.0 - collapse_frac * np.clip(tc / collapse_s, 0.0, 1.0))
    f_c = rupture_force_n * (1.0 - collapse_frac)
    f_end = backoff_to_frac * rupture_force_n
    backoff = f_c + (f_end - f_c) * np.clip((tc - collapse_s) / backoff_s, 0.0, 1.0)
    f[after] = np.where(tc <= collapse_s, collapse, backoff)
    d[after] = d_r
    return _sample(
        t, f, d, rate_hz=rate_hz, lag_s=lag_s, force_noise_n=force_noise_n,
        position_noise_m=position_noise_m, seed=seed, object_id=object_id, squeeze_index=0,
    )  # fmt: skip


def synthetic_relaxation_hold(
    *,
    stiffness_n_per_m: float = 800.0,
    arm_stiffness_n_per_m: float = 1200.0,
    relaxation_time_s: float = 0.8,
    peak_compression_m: float = 0.01,
    load_s: float = 1.0,
    hold_s: float = 4.0,
    rate_hz: float = 200.0,
    force_noise_rel: float = 0.005,
    position_noise_m: float = 2e-6,
    seed: int = 0,
    object_id: str = "relaxing",
) -> SqueezeSeries:
    """A standard linear solid pressed to ``peak_compression_m`` and held: stress relaxation.

    During the hold the force decays from ``k1 d + σ`` towards ``k1 d`` with time constant
    ``relaxation_time_s``; with the defaults it loses about half of its peak, smoothly.
    """
    params = {
        "stiffness_n_per_m": stiffness_n_per_m,
        "arm_stiffness_n_per_m": arm_stiffness_n_per_m,
        "relaxation_time_s": relaxation_time_s,
    }
    return synthetic_law_squeeze(
        "sls", params, peak_compression_m=peak_compression_m, load_s=load_s, hold_s=hold_s,
        release_s=0.0, rest_s=0.0, corner_s=0.02, rate_hz=rate_hz, lag_s=0.0,
        force_noise_rel=force_noise_rel, position_noise_m=position_noise_m, seed=seed,
        object_id=object_id,
    )  # fmt: skip


def synthetic_ramp_hold(
    model: str,
    params: Mapping[str, float],
    *,
    peak_compression_m: float = 0.006,
    speed_m_per_s: float = 0.006,
    hold_s: float = 1.0,
    rate_hz: float = 100.0,
    force_noise_n: float = 0.02,
    seed: int = 0,
    object_id: str = "ramp_hold",
) -> SqueezeSeries:
    """A ramp at ``speed_m_per_s`` to ``peak_compression_m`` and a hold of ``hold_s`` (sharp
    corners), the force of a law with known parameters (SI) plus seeded noise of
    ``force_noise_n`` (N). The defaults are the textbook Kelvin–Voigt test: 0.6 cm at 0.6 cm/s,
    a 1 s hold, 100 Hz, 0.02 N (with ``f = 20 d + 1.0 ḋ`` in N, cm, s:
    ``{"stiffness_n_per_m": 2000, "damping_ns_per_m": 100}``).
    """
    load_s = peak_compression_m / speed_m_per_s
    t, _ = grid = _grid(load_s + hold_s, rate_hz)
    v = np.where(t < load_s, speed_m_per_s, 0.0)
    d = np.minimum(speed_m_per_s * t, peak_compression_m)
    return _law_squeeze(
        model, params, grid, d, v, force_noise_n=force_noise_n, rate_hz=rate_hz, lag_s=0.0,
        position_noise_m=0.0, seed=seed, object_id=object_id, squeeze_index=0,
    )  # fmt: skip


#: Force-controlled squeezes on which a standard linear solid fits best with its stiffness at
#: its bound 0 (each a :func:`synthetic_rupture_backoff` without a collapse, at 77 Hz: a heavily
#: damped Kelvin–Voigt object, the force lowered while the jaws hold).
FORCE_HOLD_SHAPES: dict[str, dict[str, float]] = {
    "heavy_damping": {"damping_ns_per_m": 400.0, "backoff_s": 1.0, "backoff_to_frac": 0.2},
    "fast_ramp": {
        "damping_ns_per_m": 400.0,
        "force_rate_n_per_s": 20.0,
        "backoff_s": 0.5,
        "backoff_to_frac": 0.2,
    },
    "soft": {
        "stiffness_n_per_m": 500.0,
        "damping_ns_per_m": 300.0,
        "backoff_s": 1.0,
        "backoff_to_frac": 0.2,
    },
    "lagged": {"damping_ns_per_m": 300.0, "lag_s": 0.17, "backoff_s": 1.0, "backoff_to_frac": 0.2},
    "deep_backoff": {
        "damping_ns_per_m": 250.0,
        "backoff_s": 0.8,
        "backoff_to_frac": 0.05,
        "rest_s": 1.5,
    },
}


def synthetic_force_hold_squeeze(shape: str, *, seed: int = 0) -> SqueezeSeries:
    """One of :data:`FORCE_HOLD_SHAPES` (its Kelvin–Voigt truth: the shape's
    ``stiffness_n_per_m`` and ``damping_ns_per_m`` over :func:`synthetic_rupture_backoff`'s
    defaults)."""
    return synthetic_rupture_backoff(
        collapse_frac=0.0, rate_hz=77.0, seed=seed, object_id=shape, **FORCE_HOLD_SHAPES[shape]
    )
