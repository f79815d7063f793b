"""Synthetic squeezes that are not (or not only) a clean Kelvin–Voigt squeeze, for the flag tests.

Each builder returns exact samples of a stated model plus seeded Gaussian noise (force noise 1 %
of the peak force, compression noise as given), so each test knows what the right answer is:

* :func:`position_controlled`: a prescribed compression (haversine load–unload), the force
  ``F0 + D d + λ d'``: any sign of λ, with or without a preload ``F0``;
* :func:`constant_rate`: a testing machine's crosshead at constant speed (λ unidentifiable);
* :func:`rupture`: a force-controlled ramp on a Kelvin–Voigt object that gives way at ``t_r``
  (the force collapses to ``keep`` of its value within 10 ms while the gripper keeps closing);
* :func:`csv_text`: any squeeze as a CSV export (time s, force N, compression or gap in mm).
"""

from __future__ import annotations

import math

import numpy as np

from deformctl.characterize import kelvin_voigt_piecewise_linear
from deformctl.series import SqueezeSeries


def _noisy(
    oid: str, index: int, t: np.ndarray, f: np.ndarray, d: np.ndarray, seed: int, pos_noise_m: float
) -> SqueezeSeries:
    rng = np.random.default_rng(seed)
    peak = float(np.max(np.abs(f)))
    return SqueezeSeries(
        oid,
        index,
        t,
        f + rng.normal(0.0, 0.01 * peak, t.size),
        d + rng.normal(0.0, pos_noise_m, t.size),
    )


def position_controlled(
    d_n_per_cm: float,
    lam_ns_per_cm: float,
    *,
    preload_n: float = 0.0,
    peak_mm: float = 3.0,
    duration_s: float = 4.0,
    rate_hz: float = 1000.0,
    seed: int = 0,
    object_id: str = "obj",
    index: int = 0,
    pos_noise_m: float = 1e-5,
) -> SqueezeSeries:
    """A haversine compression ``d = peak (1 − cos 2πt/T)/2``; force ``F0 + D d + λ d'``."""
    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    w = 2.0 * math.pi / duration_s
    d = 0.5e-3 * peak_mm * (1.0 - np.cos(w * t))
    v = 0.5e-3 * peak_mm * w * np.sin(w * t)
    f = preload_n + 100.0 * d_n_per_cm * d + 100.0 * lam_ns_per_cm * v
    return _noisy(object_id, index, t, f, d, seed, pos_noise_m)


def constant_rate(
    d_n_per_cm: float,
    lam_ns_per_cm: float,
    *,
    speed_mm_s: float = 0.5,
    travel_mm: float = 5.0,
    rate_hz: float = 100.0,
    preload_n: float = 0.0,
    seed: int = 0,
    object_id: str = "obj",
) -> SqueezeSeries:
    """A testing machine's crosshead at constant speed: ``d = v t``, force ``F0 + D d + λ v``."""
    t = np.arange(0.0, travel_mm / speed_mm_s + 0.5 / rate_hz, 1.0 / rate_hz)
    v = speed_mm_s * 1e-3
    d = v * t
    f = preload_n + 100.0 * d_n_per_cm * d + 100.0 * lam_ns_per_cm * v
    return _noisy(object_id, 0, t, f, d, seed, 1e-5)


def rupture(
    d_n_per_cm: float,
    lam_ns_per_cm: float,
    *,
    t_rupture_s: float = 2.0,
    keep: float = 0.4,
    closing: float = 2.0,
    duration_s: float = 3.0,
    ramp_n_per_s: float = 5.0,
    rate_hz: float = 1000.0,
    seed: int = 0,
    object_id: str = "obj",
    index: int = 0,
) -> SqueezeSeries:
    """A force ramp until the object gives way at ``t_rupture_s``.

    After the rupture the force falls to ``keep`` of its value (time constant 10 ms) while the
    compression keeps growing at ``closing`` × its rate just before.
    """
    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    f = ramp_n_per_s * t
    knots_t = np.array([0.0, duration_s])
    knots_f = np.array([0.0, ramp_n_per_s * duration_s])
    d = kelvin_voigt_piecewise_linear(
        t, knots_t, knots_f, 100.0 * d_n_per_cm, 100.0 * lam_ns_per_cm
    )
    i = int(np.searchsorted(t, t_rupture_s))
    f_r, d_r = f[i], d[i]
    v_r = (d[i] - d[i - 10]) / (t[i] - t[i - 10])
    after = t >= t_rupture_s
    f = np.where(after, f_r * (keep + (1.0 - keep) * np.exp(-(t - t_rupture_s) / 0.01)), f)
    d = np.where(after, d_r + closing * v_r * (t - t_rupture_s), d)
    return _noisy(object_id, index, t, f, d, seed, 5e-5)


def csv_text(s: SqueezeSeries, *, gap_mm0: float | None = None) -> str:
    """A CSV export of ``s``: ``t`` (s), ``load`` (N) and ``pos`` (mm: the compression, or the
    gap ``gap_mm0 − d`` when ``gap_mm0`` is given)."""
    pos = 1e3 * s.compression_m if gap_mm0 is None else gap_mm0 - 1e3 * s.compression_m
    lines = ["t,load,pos"] + [
        f"{a:.6f},{b:.6f},{c:.6f}" for a, b, c in zip(s.time_s, s.force_n, pos, strict=True)
    ]
    return "\n".join(lines) + "\n"
