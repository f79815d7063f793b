"""``characterize`` of a recording a notebook already holds: time, force and compression arrays.

:func:`characterize_arrays` gives the coefficients row ``measure csv`` then ``characterize``
would write for the same samples, with the command's defaults: the arrays are one squeeze, kept
up to a rupture as ``measure`` keeps it (:func:`deformctl.squeeze.rupture.cut_rupture`,
which records it), fitted as a rig recording (an intercept for a preload,
the force's lag fitted, the material law chosen by BIC), the Savitzky–Golay window chosen from
the sample rate, and the quality policy applied. The arrays are in SI (s, N, m); nothing is
read from or written to disk.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from deformctl.errors import InputDataError, UsageError
from deformctl.series import SqueezeSeries

if TYPE_CHECKING:  # pragma: no cover - pandas loads with the fit
    import pandas as pd
    from numpy.typing import ArrayLike

#: The ``source`` of an object characterized from arrays (fitted as a rig recording).
ARRAYS_SOURCE = "arrays"


class CoefficientsWarning(UserWarning):
    """A flagged object of :func:`characterize_arrays` (the row's ``quality`` names the flags),
    or a rupture cut off."""


def _series(name: str, values: ArrayLike) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputDataError(f"{name} is not numeric") from None
    if arr.ndim != 1:
        raise InputDataError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        first = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise InputDataError(f"{name}[{first}] is not finite ({arr[first]})")
    return arr


def _check(time_s: np.ndarray, force_n: np.ndarray, compression_m: np.ndarray) -> None:
    if not len(time_s) == len(force_n) == len(compression_m):
        raise InputDataError(
            f"time_s, force_n and compression_m differ in length ({len(time_s)}, "
            f"{len(force_n)}, {len(compression_m)})"
        )
    if len(time_s) < 2:
        raise InputDataError(f"a recording needs at least 2 samples, got {len(time_s)}")
    steps = np.diff(time_s)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        raise InputDataError(
            f"time_s must increase: time_s[{k + 1}] = {time_s[k + 1]!r} after {time_s[k]!r}"
        )
    if float(np.max(compression_m)) <= 0.0:
        raise InputDataError(
            "compression_m never exceeds 0: give the compression between the palms in m, "
            "positive when squeezing"
        )


def characterize_arrays(
    time_s: ArrayLike,
    force_n: ArrayLike,
    compression_m: ArrayLike,
    *,
    object_id: str = "object",
    weight_n: float | None = None,
    friction_mu: float | None = None,
    method: str = "lsq",
    model: str = "auto",
    at_force_n: float | None = None,
    window_s: float | None = None,
    preload: str | None = None,
    strict: bool = False,
    allow_flagged: bool = False,
) -> pd.DataFrame:
    """The coefficients row of one object's recording, as ``characterize`` writes it.

    Args:
        time_s: sample times, s, strictly increasing (any origin).
        force_n: the squeeze force at each time, N (positive when squeezing).
        compression_m: the total compression between the palms at each time, m (positive when
            squeezing; 0 at the first contact).
        object_id: the row's ``object_id``.
        weight_n, friction_mu: the object's W (N) and μ: copied into the row, and F_w = W/(2μ)
            is the operating force D is stated at when both are given (``characterize``'s
            default); None: not known (NaN in the row).
        method, model, at_force_n, window_s, preload: as ``characterize --method --model
            --at-force-n --window-s --preload`` (None: the command's default, the window from
            the sample rate and, lsq, a fitted preload).
        strict, allow_flagged: as ``characterize --strict`` / ``--allow-flagged``.

    Returns:
        One row with exactly the columns of a coefficients table
        (:data:`deformctl.characterize.COEFFICIENT_COLUMNS`). A flagged row (``quality`` not
        ``ok``) also raises a :class:`CoefficientsWarning` naming the flags, and so does a
        rupture (the squeeze is kept up to it, and the row's rupture columns say where).

    Raises:
        InputDataError: arrays of different lengths, fewer than 2 samples, a value that is not
            finite, time not increasing, no compression, or a recording that cannot be fitted;
            a flagged row with ``strict``, a negative D without ``allow_flagged``.
        UsageError: an option out of range (the command's rules).
    """
    from deformctl.characterize.coefficients import _coefficient_frame
    from deformctl.characterize.material_options import MaterialOptions
    from deformctl.characterize.options import FitOptions, QualityPolicy, check_method
    from deformctl.characterize.quality import enforce
    from deformctl.characterize.stage import _fit_object
    from deformctl.quantities import FRICTION_MU, WEIGHT_N
    from deformctl.squeeze.rupture import cut_rupture
    from deformctl.squeeze.window import default_window_s

    t, f, d = (_series(n, v) for n, v in (("time_s", time_s), ("force_n", force_n),
                                          ("compression_m", compression_m)))  # fmt: skip
    _check(t, f, d)
    if not object_id:
        raise UsageError("object_id must not be empty")
    WEIGHT_N.check_optional(weight_n)
    FRICTION_MU.check_optional(friction_mu)
    options = FitOptions(
        method=check_method(method),
        window_s=window_s,
        preload=preload,  # type: ignore[arg-type]  # checked when built
        materials=MaterialOptions(model=model, at_force_n=at_force_n),
    )
    policy = QualityPolicy(strict=strict, allow_flagged=allow_flagged)
    rate_hz = float(1.0 / np.median(np.diff(t)))
    window = options.window_s if options.window_s is not None else default_window_s(rate_hz)
    whole = SqueezeSeries(
        object_id=object_id, squeeze_index=0, time_s=t - t[0], force_n=f, compression_m=d
    )
    squeeze, rupture = cut_rupture(
        whole, window_s=default_window_s(rate_hz), recording_offset_s=0.0
    )
    obj: dict[str, Any] = {
        "object_id": object_id,
        "weight_n": weight_n,
        "friction_mu": friction_mu,
        "force_rate_hz": rate_hz,
        "position_rate_hz": rate_hz,
        "source": ARRAYS_SOURCE,
    }
    if rupture is not None:
        obj["ruptures"] = [rupture.to_record()]
        warnings.warn(
            f"object {object_id!r}: rupture in {rupture.describe()}: cut off",
            CoefficientsWarning,
            stacklevel=2,
        )
    row, _ = _fit_object(object_id, [squeeze], obj, options, window_s=window)
    table = _coefficient_frame([row])
    for line in enforce(table, strict=policy.strict, allow_flagged=policy.allow_flagged):
        warnings.warn(line, CoefficientsWarning, stacklevel=2)
    return table


__all__ = ["ARRAYS_SOURCE", "CoefficientsWarning", "characterize_arrays"]
