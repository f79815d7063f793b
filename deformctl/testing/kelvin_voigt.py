"""Synthetic Kelvin–Voigt squeezes: the exact response to a force profile, ground truth for tests.

:func:`kelvin_voigt_response` is the closed-form compression of ``k d + c d' = f`` for a
ramp-hold-release or a haversine force; :func:`synthetic_kelvin_voigt_squeeze` adds seeded noise
and returns a squeeze with known D and λ.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from deformctl.characterize.models import kelvin_voigt_piecewise_linear
from deformctl.errors import UsageError
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.units import N_PER_CM, NS_PER_CM

Profile = Literal["ramp_hold_release", "sine"]


def kelvin_voigt_response(
    time_s: FloatArray,
    deformability_n_per_cm: float,
    damping_ns_per_cm: float,
    *,
    peak_force_n: float,
    profile: Profile,
    duration_s: float,
) -> tuple[FloatArray, FloatArray]:
    """Noise-free force and exact compression of a Kelvin–Voigt object under a force profile.

    Profiles (force starts at 0 with the object at rest, ``d(0) = 0``):

    * ``"ramp_hold_release"``: linear ramp to ``peak_force_n`` over the first 25 % of
      ``duration_s``, hold for 40 %, linear release to 0 over 25 %, rest for the last 10 %.
      The hold shows creep (λ), the ramps load both terms.
    * ``"sine"``: two haversine pulses ``f = F (1 − cos ωt)/2``, ``ω = 4π/duration_s``; the
      closed form is the steady harmonic response plus the decaying transient.

    Args:
        time_s: sample times ``[n]``, s, in ``[0, duration_s]``.
        deformability_n_per_cm: D, N/cm (> 0).
        damping_ns_per_cm: λ, N·s/cm (≥ 0).
        peak_force_n: peak force, N.
        profile: ``"ramp_hold_release"`` or ``"sine"``.
        duration_s: squeeze duration, s.

    Returns:
        ``(force_n [n], compression_m [n])``.
    """
    k = deformability_n_per_cm * N_PER_CM
    c = damping_ns_per_cm * NS_PER_CM
    if not k > 0 or not c >= 0:
        raise UsageError(f"need D > 0 and λ >= 0, got D={deformability_n_per_cm}, λ={c}")
    t = np.asarray(time_s, dtype=np.float64)
    if profile == "ramp_hold_release":
        knots = duration_s * np.array([0.0, 0.25, 0.65, 0.90, 1.0])
        forces = peak_force_n * np.array([0.0, 1.0, 1.0, 0.0, 0.0])
        return np.interp(t, knots, forces), kelvin_voigt_piecewise_linear(t, knots, forces, k, c)
    if profile == "sine":
        a = 0.5 * peak_force_n
        w = 4.0 * math.pi / duration_s
        force = a * (1.0 - np.cos(w * t))
        if c == 0.0:
            return force, force / k
        den = k * k + (c * w) ** 2
        steady = a / k - a * (k * np.cos(w * t) + c * w * np.sin(w * t)) / den
        transient = -(a / k - a * k / den) * np.exp(-t * k / c)
        return force, steady + transient
    raise UsageError(f"unknown profile {profile!r}; expected 'ramp_hold_release' or 'sine'")


def synthetic_kelvin_voigt_squeeze(
    deformability_n_per_cm: float,
    damping_ns_per_cm: float,
    *,
    peak_force_n: float = 10.0,
    profile: Profile = "ramp_hold_release",
    duration_s: float = 4.0,
    rate_hz: float = 1000.0,
    force_noise_rel: float = 0.01,
    position_noise_m: float = 5e-5,
    seed: int = 0,
    object_id: str = "synthetic",
    squeeze_index: int = 0,
) -> SqueezeSeries:
    """A squeeze log of a Kelvin–Voigt object with known D and λ, plus Gaussian noise.

    The noise-free compression is exact (:func:`kelvin_voigt_response`). Noise: force noise
    has standard deviation ``force_noise_rel · peak_force_n`` (N); compression noise has
    standard deviation ``position_noise_m`` (m). ``commanded_force_n`` holds the noise-free force.

    Args:
        deformability_n_per_cm: D, N/cm.
        damping_ns_per_cm: λ, N·s/cm.
        peak_force_n: peak squeeze force, N.
        profile: ``"ramp_hold_release"`` or ``"sine"``.
        duration_s: squeeze duration, s.
        rate_hz: sample rate, Hz.
        force_noise_rel: force noise std relative to the peak force.
        position_noise_m: compression noise std, m.
        seed: seed of ``np.random.default_rng``.
        object_id: catalog id written into the series.
        squeeze_index: index written into the series.

    Returns:
        The squeeze, ``round(duration_s · rate_hz) + 1`` samples.
    """
    n = round(duration_s * rate_hz) + 1
    t = np.arange(n) / rate_hz
    force, comp = kelvin_voigt_response(
        t,
        deformability_n_per_cm,
        damping_ns_per_cm,
        peak_force_n=peak_force_n,
        profile=profile,
        duration_s=duration_s,
    )
    rng = np.random.default_rng(seed)
    return SqueezeSeries(
        object_id=object_id,
        squeeze_index=squeeze_index,
        time_s=t,
        force_n=force + rng.normal(0.0, force_noise_rel * peak_force_n, n),
        compression_m=comp + rng.normal(0.0, position_noise_m, n),
        commanded_force_n=force,
    )
