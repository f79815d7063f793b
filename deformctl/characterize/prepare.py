"""A squeeze that can be characterised: the checks every estimator makes first.

:func:`validate_squeeze` refuses, with one line that names the squeeze, what no fit can use: too
few samples, NaN or inf, time that does not increase, a compression of the wrong sign, none at
all or one that never grows, and a force that never changes.
"""

from __future__ import annotations

import numpy as np

from deformctl.errors import InputDataError
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.signals import noise_std

#: A squeeze whose peak compression is at or below this is "no compression", m.
NO_COMPRESSION_M = 1e-6
#: ... or at or below this multiple of the estimated position noise std (max of pure noise ≈ 4σ).
NO_COMPRESSION_NOISE_MULT = 6.0
#: Fewest samples a squeeze must have (before trimming).
MIN_SAMPLES = 10
#: The force "does not change" when the span of its means over :data:`FORCE_BLOCKS` blocks is at
#: most this multiple of the noise of one block mean (20 means of pure noise span about 3.7 of
#: it; a 401-sample constant force with 0.01 N noise passed the raw-span rule half the time).
FORCE_BLOCKS = 20
FORCE_BLOCK_NOISE_MULT = 8.0


def _where(s: SqueezeSeries) -> str:
    return f"squeeze {s.object_id!r} #{s.squeeze_index}"


def validate_squeeze(s: SqueezeSeries, *, min_samples: int = MIN_SAMPLES) -> None:
    """Refuse a squeeze that cannot be characterised.

    Raises:
        InputDataError: too few samples, NaN/inf samples, timestamps that do not strictly
            increase, no compression (peak compression ≤ :data:`NO_COMPRESSION_M` or the position
            noise times :data:`NO_COMPRESSION_NOISE_MULT`), a compression that never grows by
            more than that, or a force that never changes by more than its noise times the same
            multiple; a compression that is mostly negative is named as having the wrong sign.
    """
    if len(s) < min_samples:
        raise InputDataError(f"{_where(s)}: only {len(s)} samples, need at least {min_samples}")
    for name in ("time_s", "force_n", "compression_m"):
        arr: FloatArray = getattr(s, name)
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise InputDataError(
                f"{_where(s)}: {bad.size} non-finite (NaN/inf) {name} sample(s), first at index "
                f"{int(bad[0])}"
            )
    dt = np.diff(s.time_s)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise InputDataError(
            f"{_where(s)}: non-monotonic timestamps, time_s[{i}]={s.time_s[i]:.9g} s does not "
            f"follow time_s[{i - 1}]={s.time_s[i - 1]:.9g} s"
        )
    peak_m = float(np.max(s.compression_m))
    noise_m = noise_std(s.compression_m)
    low_m = float(np.min(s.compression_m))
    if -low_m > max(peak_m, NO_COMPRESSION_NOISE_MULT * noise_m, NO_COMPRESSION_M):
        raise InputDataError(
            f"{_where(s)}: no compression: it has the wrong sign (down to {low_m:.3g} m, at most "
            f"{peak_m:.3g} m): it must be positive when squeezed; re-measure with the "
            "position direction flipped (measure --position-increases-when)"
        )
    if peak_m <= max(NO_COMPRESSION_M, NO_COMPRESSION_NOISE_MULT * noise_m):
        raise InputDataError(
            f"{_where(s)}: no compression (peak compression {peak_m:.3g} m, position noise "
            f"{noise_m:.3g} m); the palms did not squeeze the object, or compression has the "
            "wrong sign (it must be positive when squeezed)"
        )
    span_m = peak_m - low_m
    if span_m <= max(NO_COMPRESSION_M, NO_COMPRESSION_NOISE_MULT * noise_m):
        raise InputDataError(
            f"{_where(s)}: the compression never grows (it stays within {span_m:.3g} m, position "
            f"noise {noise_m:.3g} m); the palms did not move against the object"
        )
    force_span = float(np.max(s.force_n) - np.min(s.force_n))
    force_noise = noise_std(s.force_n)
    # the raw span of pure noise grows with the samples (≈ 6σ at 400): the means of blocks of
    # k samples shrink it by √k, so a constant force with noise is told from a small change
    k = max(1, len(s) // FORCE_BLOCKS)
    means = s.force_n[: k * (len(s) // k)].reshape(-1, k).mean(axis=1)
    mean_span = float(np.max(means) - np.min(means))
    if force_span <= max(1e-9, NO_COMPRESSION_NOISE_MULT * force_noise) or (
        k > 1 and mean_span <= FORCE_BLOCK_NOISE_MULT * force_noise / np.sqrt(k)
    ):
        raise InputDataError(
            f"{_where(s)}: the force does not change (it stays within {force_span:.3g} N, force "
            f"noise {force_noise:.3g} N): nothing resisted the squeeze, or the force column is "
            "not the squeeze force"
        )
