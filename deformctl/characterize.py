"""Deformability D and damping λ from squeeze logs (the paper's Kelvin model, section III.B).

A squeeze is modelled as one Kelvin–Voigt element between the palms::

    f(t) = D · d(t) + λ · d'(t)

with ``f`` the force felt by the manipulator (N), ``d`` the total compression between the palms
(m, see :mod:`deformctl.series`) and ``d'`` its rate (m/s). Inside the code D is a stiffness in
N/m and λ a damping in N·s/m; results are reported in the paper's units (N/cm, N·s/cm) through
:data:`deformctl.units.N_PER_CM` and :data:`deformctl.units.NS_PER_CM`.

Two estimators:

* :func:`fit_lsq` (the default): one joint linear least-squares fit of ``f = D d + λ d'`` over
  every usable sample of every squeeze of an object. ``d`` and ``d'`` come from one
  Savitzky–Golay local polynomial per sample (on a uniform time grid; non-uniform logs are
  resampled linearly first), so noisy positions are differentiated robustly. Samples within half
  a filter window of either end of a squeeze are dropped (the filter's edge fit is a one-sided
  extrapolation whose derivative is much noisier and biased), as are samples whose compression is
  below ``min_compression_frac`` of the squeeze's peak (before contact a log carries no
  information about the object, and on a real rig the palms may travel in free air). Standard
  errors are heteroscedasticity-and-autocorrelation-consistent (Newey–West, Bartlett weights,
  bandwidth one SG window, within each squeeze): the smoothed regressors carry position noise
  that is correlated over a window, so plain OLS errors ``s² (XᵀX)⁻¹`` come out 2–3× too small.
  Known bias: noise in ``d'`` (errors in variables) pulls λ towards zero by roughly
  ``var(noise in d') / mean(d'²)``; a longer window reduces it at the cost of smoothing bias.

* :func:`fit_paper`: the paper's estimator. The paper defines the deformability function per
  sample, ``D(t_m) = f(t_m) / d(t_m)`` "for all t_m", and then the damping function on the
  residual, ``λ(t_m) = (f(t_m) − D d(t_m)) / d'(t_m)``, and reports one number per object
  (Table II). Our reading: each squeeze's D is the *median* of the per-sample ratios over the
  samples with non-negligible compression (the median because a ratio with a small denominator
  has heavy tails; ``aggregate="mean"`` is available), λ is the median of the residual ratios
  over the samples with non-negligible rate ``|d'|``, and the object's values are the means over
  its squeezes, with the squeeze-to-squeeze standard error when there are two or more. The
  paper does not say how it differentiates ``d``; we use the same Savitzky–Golay derivative as
  :func:`fit_lsq`, so the two estimators differ only in the estimator. Note the bias this
  method carries by construction: ``f/d = D + λ d'/d``, so wherever the object is still moving
  the ratio mixes damping into D.

:func:`read_and_characterize` fits every object of a squeeze log, :func:`characterize_dir` those
of a ``measure`` dataset directory, and :func:`characterize_file` writes their table; at scale,
:class:`CharacterizeTask` is the sweep task of one object and :func:`characterize_sweep` writes a
coefficients dataset directory.

:func:`synthetic_kelvin_voigt_squeeze` generates squeezes with known D and λ (the exact
Kelvin–Voigt response to a ramp-hold-release or a haversine force, plus seeded noise) for tests
and examples.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd

from deformctl.artifacts import check_output_path, write_table
from deformctl.artifacts.dataset import (
    MANIFEST_NAME,
    dataset_fingerprint,
    dataset_part_paths,
    iter_dataset_parts,
    part_name,
    spec_rows,
    table_schema,
)
from deformctl.artifacts.provenance import Provenance, sha256_file
from deformctl.errors import InputDataError, MissingInputError, UsageError
from deformctl.parallel import SweepOptions, SweepSummary, run_sweep
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.units import N_PER_CM, NS_PER_CM

Method = Literal["lsq", "paper"]
Profile = Literal["ramp_hold_release", "sine"]

#: Default Savitzky–Golay window, s. Long enough that the derivative of 0.05 mm position noise is
#: small against squeeze rates of a few mm/s (noise in ``d'`` biases λ low, see ``fit_lsq``), short
#: enough that a cubic follows a squeeze of a few seconds (cubic smoothing bias < 0.1 % in tests).
DEFAULT_WINDOW_S = 0.2
#: Sample rate the default window was chosen for, Hz (see :func:`default_window_s`).
DEFAULT_WINDOW_RATE_HZ = 1000.0
#: Default Savitzky–Golay polynomial order (cubic: exact for d through a smooth corner).
DEFAULT_POLYORDER = 3
#: Samples with compression below this fraction of the squeeze's peak compression are not used.
DEFAULT_MIN_COMPRESSION_FRAC = 0.02
#: Paper method: samples with |d'| below this fraction of the peak |d'| are not used for λ.
DEFAULT_MIN_RATE_FRAC = 0.05
#: A squeeze whose peak compression is at or below this is "no compression", m.
NO_COMPRESSION_M = 1e-6
#: ... or at or below this multiple of the estimated position noise std (max of pure noise ≈ 4σ).
NO_COMPRESSION_NOISE_MULT = 6.0
#: Fewest samples a squeeze must have (before trimming).
MIN_SAMPLES = 10
#: Relative spread of the sampling interval above which a log is resampled to a uniform grid.
UNIFORM_DT_RTOL = 1e-3

COEFFICIENT_COLUMNS = (
    "object_id",
    "deformability_n_per_cm",
    "damping_ns_per_cm",
    "method",
    "deformability_se_n_per_cm",
    "damping_se_ns_per_cm",
    "r2",
    "n_samples",
    "n_squeezes",
)


@dataclass(frozen=True)
class CoefficientFit:
    """Deformability and damping of one object, with fit quality.

    Attributes:
        deformability_n_per_cm: D, N/cm.
        damping_ns_per_cm: λ, N·s/cm.
        method: ``"lsq"`` or ``"paper"``.
        deformability_se_n_per_cm: standard error of D, N/cm (NaN when not estimable).
        damping_se_ns_per_cm: standard error of λ, N·s/cm (NaN when not estimable).
        r2: coefficient of determination of ``f ≈ D d + λ d'`` on the samples used.
        n_samples: samples used in the fit (after trimming and masking).
        n_squeezes: squeezes contributing.
    """

    deformability_n_per_cm: float
    damping_ns_per_cm: float
    method: str
    deformability_se_n_per_cm: float
    damping_se_ns_per_cm: float
    r2: float
    n_samples: int
    n_squeezes: int

    @property
    def stiffness_n_per_m(self) -> float:
        """D in SI, N/m."""
        return self.deformability_n_per_cm * N_PER_CM

    @property
    def damping_ns_per_m(self) -> float:
        """λ in SI, N·s/m."""
        return self.damping_ns_per_cm * NS_PER_CM


@dataclass(frozen=True)
class _Prepared:
    """One validated squeeze on a uniform grid with SG-smoothed compression and rate.

    All arrays ``[m]`` after trimming half a window at each end.
    """

    force_n: FloatArray
    compression_m: FloatArray
    rate_m_per_s: FloatArray
    window_samples: int


def _where(s: SqueezeSeries) -> str:
    return f"squeeze {s.object_id!r} #{s.squeeze_index}"


def validate_squeeze(s: SqueezeSeries, *, min_samples: int = MIN_SAMPLES) -> None:
    """Refuse a squeeze that cannot be characterised.

    Raises:
        InputDataError: too few samples, NaN/inf samples, timestamps that do not strictly
            increase, or no compression (peak compression ≤ :data:`NO_COMPRESSION_M`).
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
    noise_m = _noise_std_m(s.compression_m)
    if peak_m <= max(NO_COMPRESSION_M, NO_COMPRESSION_NOISE_MULT * noise_m):
        raise InputDataError(
            f"{_where(s)}: no compression (peak compression {peak_m:.3g} m, position noise "
            f"{noise_m:.3g} m); the palms did not squeeze the object, or compression has the "
            "wrong sign (it must be positive when squeezed)"
        )


def _noise_std_m(compression_m: FloatArray) -> float:
    """Robust white-noise std of a sampled signal from the MAD of its second differences, m.

    For a smooth signal sampled densely the second difference is noise only:
    ``Δ²e`` has std ``√6 σ``; the median absolute deviation ignores the few corners.
    """
    dd = np.diff(compression_m, 2)
    if dd.size == 0:
        return 0.0
    return float(np.median(np.abs(dd - np.median(dd))) / 0.6745 / math.sqrt(6.0))


def _uniform(s: SqueezeSeries) -> tuple[float, FloatArray, FloatArray]:
    """Return ``(dt_s, force_n [m], compression_m [m])`` on a uniform grid.

    A log whose sampling interval varies by more than :data:`UNIFORM_DT_RTOL` is linearly
    resampled onto the grid ``t0 + k · median(dt)``.
    """
    t = s.time_s
    dt = np.diff(t)
    dt_s = float(np.median(dt))
    if float(np.max(np.abs(dt - dt_s))) <= UNIFORM_DT_RTOL * dt_s:
        return dt_s, s.force_n, s.compression_m
    n = math.floor((t[-1] - t[0]) / dt_s) + 1
    grid = t[0] + dt_s * np.arange(n)
    return (
        dt_s,
        np.interp(grid, t, s.force_n),
        np.interp(grid, t, s.compression_m),
    )


def _window_length(window_s: float, dt_s: float, polyorder: int) -> int:
    """Odd SG window length in samples closest to ``window_s`` and at least ``polyorder + 2``."""
    n = round(window_s / dt_s)
    n = max(n, polyorder + 2)
    return n if n % 2 == 1 else n + 1


def _prepare(
    s: SqueezeSeries, *, window_s: float, polyorder: int, min_compression_frac: float
) -> _Prepared:
    """Validate, resample, differentiate, trim the edges and mask negligible compression."""
    validate_squeeze(s)
    dt_s, force_n, comp_m = _uniform(s)
    wl = _window_length(window_s, dt_s, polyorder)
    if force_n.shape[0] < 2 * wl:
        raise InputDataError(
            f"{_where(s)}: only {force_n.shape[0]} samples on the uniform grid, need at least "
            f"{2 * wl} for a {wl}-sample Savitzky–Golay window (use a shorter window)"
        )
    from scipy.signal import savgol_filter  # deferred: ~1 s to import, only fits need it

    d_m = savgol_filter(comp_m, wl, polyorder, deriv=0)
    rate = savgol_filter(comp_m, wl, polyorder, deriv=1, delta=dt_s)
    half = wl // 2
    core = slice(half, force_n.shape[0] - half)
    f, d, v = force_n[core], d_m[core], rate[core]
    keep = d > min_compression_frac * float(np.max(d))
    return _Prepared(
        force_n=f[keep], compression_m=d[keep], rate_m_per_s=v[keep], window_samples=wl
    )


def _check_options(window_s: float, polyorder: int, min_compression_frac: float) -> None:
    if not window_s > 0:
        raise UsageError(f"window_s must be > 0, got {window_s}")
    if polyorder < 1:
        raise UsageError(f"polyorder must be >= 1 (the fit needs a derivative), got {polyorder}")
    if not 0 <= min_compression_frac < 1:
        raise UsageError(f"min_compression_frac must be in [0, 1), got {min_compression_frac}")


def _hac_meat(x: FloatArray, resid: FloatArray, lags: int) -> FloatArray:
    """Newey–West (Bartlett) estimate of ``Σ_t Σ_s w_|t−s| (x_t e_t)(x_s e_s)ᵀ``, ``[p, p]``.

    Args:
        x: regressors of one squeeze, ``[m, p]``.
        resid: residuals ``[m]``.
        lags: bandwidth in samples (the SG window: the span over which smoothed regressors,
            and so residuals, are correlated).
    """
    u = x * resid[:, None]
    meat = u.T @ u
    for lag in range(1, min(lags, u.shape[0] - 1) + 1):
        g = u[lag:].T @ u[:-lag]
        meat += (1.0 - lag / (lags + 1)) * (g + g.T)
    return np.asarray(meat, dtype=np.float64)


def _r2(f: FloatArray, pred: FloatArray) -> float:
    ss_tot = float(np.sum((f - f.mean()) ** 2))
    ss_res = float(np.sum((f - pred) ** 2))
    return 1.0 - ss_res / ss_tot if ss_tot > 0 else float("nan")


def _require(squeezes: Sequence[SqueezeSeries]) -> None:
    if len(squeezes) == 0:
        raise InputDataError("no squeezes to characterize")
    ids = {s.object_id for s in squeezes}
    if len(ids) > 1:
        raise InputDataError(f"squeezes of several objects in one fit: {sorted(ids)}")


def fit_lsq(
    squeezes: Sequence[SqueezeSeries],
    *,
    window_s: float = DEFAULT_WINDOW_S,
    polyorder: int = DEFAULT_POLYORDER,
    min_compression_frac: float = DEFAULT_MIN_COMPRESSION_FRAC,
) -> CoefficientFit:
    """Joint least-squares fit of ``f = D d + λ d'`` over all squeezes of one object.

    Args:
        squeezes: the object's squeezes (same ``object_id``), each with ``time_s``, ``force_n``
            and ``compression_m`` of shape ``[n]``.
        window_s: Savitzky–Golay window, s (rounded to an odd number of samples).
        polyorder: Savitzky–Golay polynomial order.
        min_compression_frac: drop samples with compression below this fraction of the
            squeeze's peak.

    Returns:
        The fit in N/cm and N·s/cm with OLS standard errors, R², samples and squeezes used.

    Raises:
        InputDataError: a squeeze that fails :func:`validate_squeeze`, is shorter than two
            filter windows, or a set of samples that cannot separate D from λ.
        UsageError: an invalid option value.
    """
    _check_options(window_s, polyorder, min_compression_frac)
    _require(squeezes)
    prepared = [
        _prepare(
            s, window_s=window_s, polyorder=polyorder, min_compression_frac=min_compression_frac
        )
        for s in squeezes
    ]
    f = np.concatenate([p.force_n for p in prepared])
    x = np.column_stack(
        [
            np.concatenate([p.compression_m for p in prepared]),
            np.concatenate([p.rate_m_per_s for p in prepared]),
        ]
    )
    n = f.shape[0]
    if n < 3:
        raise InputDataError(f"object {squeezes[0].object_id!r}: only {n} usable samples")
    xtx = x.T @ x
    cond = np.linalg.cond(xtx)
    if not np.isfinite(cond) or cond > 1e12:
        raise InputDataError(
            f"object {squeezes[0].object_id!r}: compression and its rate are collinear "
            "(the force profile does not excite the damping term); cannot separate D from λ"
        )
    coef, *_ = np.linalg.lstsq(x, f, rcond=None)
    pred = x @ coef
    resid = f - pred
    meat = np.zeros((2, 2))
    start = 0
    for p in prepared:
        stop = start + p.force_n.shape[0]
        meat += _hac_meat(x[start:stop], resid[start:stop], p.window_samples)
        start = stop
    bread = np.linalg.inv(xtx)
    cov = bread @ meat @ bread * (n / (n - 2))
    se = np.sqrt(np.diag(cov))
    return CoefficientFit(
        deformability_n_per_cm=float(coef[0]) / N_PER_CM,
        damping_ns_per_cm=float(coef[1]) / NS_PER_CM,
        method="lsq",
        deformability_se_n_per_cm=float(se[0]) / N_PER_CM,
        damping_se_ns_per_cm=float(se[1]) / NS_PER_CM,
        r2=_r2(f, pred),
        n_samples=n,
        n_squeezes=len(squeezes),
    )


def fit_paper(
    squeezes: Sequence[SqueezeSeries],
    *,
    aggregate: Literal["median", "mean"] = "median",
    window_s: float = DEFAULT_WINDOW_S,
    polyorder: int = DEFAULT_POLYORDER,
    min_compression_frac: float = DEFAULT_MIN_COMPRESSION_FRAC,
    min_rate_frac: float = DEFAULT_MIN_RATE_FRAC,
) -> CoefficientFit:
    """The paper's estimator: D from ``f/d``, then λ from ``(f − D d)/d'`` (section III.B).

    Per squeeze: ``D_i = agg(f/d)`` over the samples with compression above
    ``min_compression_frac`` of the peak, ``λ_i = agg((f − D_i d)/d')`` over those samples whose
    ``|d'|`` is above ``min_rate_frac`` of the squeeze's peak ``|d'|``; ``agg`` is the median (or
    the mean). The object's D and λ are the means over squeezes; their standard errors are the
    squeeze-to-squeeze standard deviations over ``√n`` (NaN for a single squeeze). R² is that of
    ``D d + λ d'`` on the samples used for D. See the module docstring for why this is biased.

    Args:
        squeezes: the object's squeezes, arrays ``[n]``.
        aggregate: ``"median"`` (default) or ``"mean"`` of the per-sample ratios.
        window_s: Savitzky–Golay window for ``d'``, s.
        polyorder: Savitzky–Golay polynomial order.
        min_compression_frac: minimum compression, as a fraction of the squeeze's peak.
        min_rate_frac: minimum ``|d'|`` for the λ ratios, as a fraction of the peak ``|d'|``.

    Returns:
        The fit in N/cm and N·s/cm.

    Raises:
        InputDataError: as :func:`fit_lsq`.
        UsageError: an invalid option value.
    """
    _check_options(window_s, polyorder, min_compression_frac)
    if aggregate not in ("median", "mean"):
        raise UsageError(f"aggregate must be 'median' or 'mean', got {aggregate!r}")
    if not 0 <= min_rate_frac < 1:
        raise UsageError(f"min_rate_frac must be in [0, 1), got {min_rate_frac}")
    _require(squeezes)
    agg = np.median if aggregate == "median" else np.mean
    d_list: list[float] = []
    lam_list: list[float] = []
    fs: list[FloatArray] = []
    preds: list[FloatArray] = []
    for s in squeezes:
        p = _prepare(
            s, window_s=window_s, polyorder=polyorder, min_compression_frac=min_compression_frac
        )
        if p.force_n.shape[0] < 3:
            raise InputDataError(f"{_where(s)}: only {p.force_n.shape[0]} usable samples")
        d_i = float(agg(p.force_n / p.compression_m))
        abs_rate = np.abs(p.rate_m_per_s)
        moving = abs_rate > min_rate_frac * float(np.max(abs_rate))
        if not np.any(moving):
            raise InputDataError(f"{_where(s)}: compression never changes; no damping estimate")
        resid = p.force_n[moving] - d_i * p.compression_m[moving]
        lam_i = float(agg(resid / p.rate_m_per_s[moving]))
        d_list.append(d_i)
        lam_list.append(lam_i)
        fs.append(p.force_n)
        preds.append(d_i * p.compression_m + lam_i * p.rate_m_per_s)
    d_arr = np.asarray(d_list)
    lam_arr = np.asarray(lam_list)
    k = d_arr.shape[0]
    se_d = float(np.std(d_arr, ddof=1) / math.sqrt(k)) if k > 1 else float("nan")
    se_l = float(np.std(lam_arr, ddof=1) / math.sqrt(k)) if k > 1 else float("nan")
    f_all = np.concatenate(fs)
    return CoefficientFit(
        deformability_n_per_cm=float(d_arr.mean()) / N_PER_CM,
        damping_ns_per_cm=float(lam_arr.mean()) / NS_PER_CM,
        method="paper",
        deformability_se_n_per_cm=se_d / N_PER_CM,
        damping_se_ns_per_cm=se_l / NS_PER_CM,
        r2=_r2(f_all, np.concatenate(preds)),
        n_samples=int(f_all.shape[0]),
        n_squeezes=k,
    )


def characterize(
    squeezes_by_object: Mapping[str, Sequence[SqueezeSeries]],
    method: Method = "lsq",
    **options: float,
) -> pd.DataFrame:
    """Fit every object's squeezes and return the coefficient table.

    Args:
        squeezes_by_object: object id → that object's squeezes.
        method: ``"lsq"`` (default, :func:`fit_lsq`) or ``"paper"`` (:func:`fit_paper`).
        **options: passed to the estimator (``window_s``, ``polyorder``, ...).

    Returns:
        One row per object, columns :data:`COEFFICIENT_COLUMNS` (coefficients in N/cm, N·s/cm).

    Raises:
        UsageError: an unknown method.
        InputDataError: any object whose squeezes cannot be fitted (the message names it).
    """
    if method not in ("lsq", "paper"):
        raise UsageError(f"unknown method {method!r}; expected 'lsq' or 'paper'")
    rows: list[dict[str, object]] = []
    for object_id, squeezes in squeezes_by_object.items():
        fit = fit_lsq(squeezes, **options) if method == "lsq" else fit_paper(squeezes, **options)  # type: ignore[arg-type]
        rows.append(
            {
                "object_id": object_id,
                "deformability_n_per_cm": fit.deformability_n_per_cm,
                "damping_ns_per_cm": fit.damping_ns_per_cm,
                "method": fit.method,
                "deformability_se_n_per_cm": fit.deformability_se_n_per_cm,
                "damping_se_ns_per_cm": fit.damping_se_ns_per_cm,
                "r2": fit.r2,
                "n_samples": fit.n_samples,
                "n_squeezes": fit.n_squeezes,
            }
        )
    df = pd.DataFrame(rows, columns=list(COEFFICIENT_COLUMNS))
    return df.astype({"n_samples": "int64", "n_squeezes": "int64"})


def default_window_s(position_rate_hz: float | None) -> float:
    """The Savitzky–Golay window for a log whose positions were sampled at ``position_rate_hz``.

    A squeeze log from a rig may carry positions sampled far more slowly than its forces (a
    100 Hz pose topic beside a 1 kHz wrench topic); ingestion interpolates them onto the force
    timestamps, so a window of ``T`` seconds holds only ``N = rate · T`` independent position
    samples. The noise variance of an SG derivative scales as ``σ² / (N T²) = σ² / (rate T³)``,
    and that noise biases λ low (see :func:`fit_lsq`). The default keeps it at the level of
    :data:`DEFAULT_WINDOW_S` at :data:`DEFAULT_WINDOW_RATE_HZ`::

        T = DEFAULT_WINDOW_S · (DEFAULT_WINDOW_RATE_HZ / rate)^(1/3),  never below DEFAULT_WINDOW_S

    (100 Hz → 0.43 s, 500 Hz → 0.25 s, ≥ 1 kHz → 0.2 s). A longer window costs smoothing bias
    at the corners of the force profile, so squeezes should last several windows.

    Args:
        position_rate_hz: position sample rate, Hz; None (unknown) gives the default.

    Returns:
        The window, s.
    """
    if position_rate_hz is None or not math.isfinite(position_rate_hz) or position_rate_hz <= 0:
        return DEFAULT_WINDOW_S
    scale = (DEFAULT_WINDOW_RATE_HZ / position_rate_hz) ** (1.0 / 3.0)
    return DEFAULT_WINDOW_S * max(1.0, scale)


@dataclass(frozen=True)
class LogCoefficients:
    """What :func:`read_and_characterize` found in one squeeze log.

    Attributes:
        table: one row per object, columns :data:`COEFFICIENT_COLUMNS`, in log order.
        window_s: object id → the Savitzky–Golay window used, s.
        position_rate_hz: object id → the position sample rate stored in the log, Hz (None
            when the log does not say).
    """

    table: pd.DataFrame
    window_s: dict[str, float]
    position_rate_hz: dict[str, float | None]


def _stored_rate(obj: Mapping[str, object] | None) -> float | None:
    value = None if obj is None else obj.get("position_rate_hz")
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    return None


def read_and_characterize(
    path: str | PathLike[str],
    method: Method = "lsq",
    *,
    window_s: float | None = None,
) -> LogCoefficients:
    """Read a squeeze log (validated), group its squeezes by object and fit each object.

    Args:
        path: the squeeze-log ``.mcap``, or ``-`` for stdin (read into memory).
        method: ``"lsq"`` (:func:`fit_lsq`) or ``"paper"`` (:func:`fit_paper`).
        window_s: Savitzky–Golay window, s, for every object; None picks it per object from
            the ``position_rate_hz`` the log stores for it (:func:`default_window_s`).

    Returns:
        The coefficient table and the window used for each object.

    Raises:
        MissingInputError: the log does not exist (exit 66).
        InputDataError: a damaged log or one that does not match its schema, no squeezes, or an
            object whose squeezes cannot be fitted (no compression, too short, ...); the
            message names the file and the object (exit 65).
        UsageError: an unknown method or a window that is not > 0 (exit 2).
    """
    from deformctl.artifacts.io import display_name
    from deformctl.artifacts.mcaplog import read_squeeze_log

    if method not in ("lsq", "paper"):
        raise UsageError(f"unknown method {method!r}; expected 'lsq' or 'paper'")
    if window_s is not None and not (math.isfinite(window_s) and window_s > 0):
        raise UsageError(f"window must be a finite number > 0 s, got {window_s}")
    name = display_name(path)
    objects, squeezes = read_squeeze_log(path)
    if not squeezes:
        raise InputDataError("the squeeze log holds no squeezes", path=name)
    by_object: dict[str, list[SqueezeSeries]] = {}
    for s in squeezes:
        by_object.setdefault(s.object_id, []).append(s)
    meta = {str(o["object_id"]): o for o in objects}
    rates = {oid: _stored_rate(meta.get(oid)) for oid in by_object}
    windows = {
        oid: window_s if window_s is not None else default_window_s(rates[oid]) for oid in by_object
    }
    frames = []
    for oid, group in by_object.items():
        try:
            frames.append(characterize({oid: group}, method, window_s=windows[oid]))
        except InputDataError as err:
            if err.path is None:  # the estimators name the object; add the file
                raise InputDataError(err.message, path=name) from err
            raise
    table = pd.concat(frames, ignore_index=True)
    return LogCoefficients(table=table, window_s=windows, position_rate_hz=rates)


# --------------------------------------------------------------------------------------------
# Squeeze-log directories and sweeps (measure --sim -o DIR/, characterize -o DIR/)
# --------------------------------------------------------------------------------------------


def squeeze_log_parts(path: str | PathLike[str]) -> list[Path]:
    """The squeeze logs ``part-*.mcap`` of a ``measure`` dataset directory, in part order.

    Raises:
        InputDataError: no logs, or a part of the sweep missing (rerun measure with --resume).
    """
    return dataset_part_paths(path, ".mcap", what="squeeze logs", rerun="measure")


def characterize_dir(
    path: str | PathLike[str], method: Method = "lsq", *, window_s: float | None = None
) -> LogCoefficients:
    """:func:`read_and_characterize` of every squeeze log of a ``measure`` directory, in order."""
    parts = [read_and_characterize(p, method, window_s=window_s) for p in squeeze_log_parts(path)]
    return LogCoefficients(
        table=pd.concat([p.table for p in parts], ignore_index=True),
        window_s={k: v for p in parts for k, v in p.window_s.items()},
        position_rate_hz={k: v for p in parts for k, v in p.position_rate_hz.items()},
    )


def characterize_file(
    log: str,
    method: Method = "lsq",
    *,
    output: str,
    window_s: float | None = None,
    force: bool = False,
) -> LogCoefficients:
    """``characterize LOG -o TABLE``: fit a squeeze log (or a ``measure`` directory's logs).

    The coefficients table is written atomically with its provenance (the method, the window
    used for each object and the position sample rates behind it).

    Raises:
        OutputExistsError: ``output`` exists and ``force`` is false (exit 1).
        MissingInputError, InputDataError, UsageError: see :func:`read_and_characterize`.
    """
    check_output_path(output, force)
    if os.path.isdir(log):
        result = characterize_dir(log, method, window_s=window_s)
    else:
        result = read_and_characterize(log, method, window_s=window_s)
    provenance = Provenance.from_invocation(
        [log],
        settings={
            "method": method,
            "window_s": result.window_s,
            "window_s_option": window_s,
            "position_rate_hz": result.position_rate_hz,
        },
    )
    write_table(result.table, output, "coefficients", provenance=provenance, force=force)
    return result


def characterize_items(path: str | PathLike[str]) -> list[dict[str, Any]]:
    """One sweep item per object of a ``measure`` dataset: ``object_id`` and its log's path.

    The objects are those with rows in the dataset (failed objects have no squeezes).
    """
    from deformctl.artifacts.mcaplog import read_squeeze_log

    d = Path(path).resolve()
    logs = squeeze_log_parts(d)
    items: list[dict[str, Any]] = []
    if (d / MANIFEST_NAME).is_file() and any(d.glob("part-*.parquet")):
        for k, table in enumerate(iter_dataset_parts(d)):
            part_log = str(d / part_name(k, ".mcap"))
            items.extend(
                {"object_id": oid, "log_path": part_log} for oid in table["object_id"].to_pylist()
            )
        return items
    for log in logs:  # no manifest: ask each log for its objects
        objects, _ = read_squeeze_log(log)
        items.extend({"object_id": str(o["object_id"]), "log_path": str(log)} for o in objects)
    return items


_LOG_CACHE: dict[tuple[str, int], tuple[dict[str, Any], dict[str, list[SqueezeSeries]]]] = {}


def _read_log_cached(path: str) -> tuple[dict[str, Any], dict[str, list[SqueezeSeries]]]:
    """A squeeze log's objects and squeezes by object id; the last log read is kept per process.

    Items arrive in catalog order, so a worker reads each part's log about once.
    """
    from deformctl.artifacts.mcaplog import read_squeeze_log

    key = (path, os.stat(path).st_mtime_ns)
    if key not in _LOG_CACHE:
        objects, squeezes = read_squeeze_log(path)
        by_object: dict[str, list[SqueezeSeries]] = {}
        for s in squeezes:
            by_object.setdefault(s.object_id, []).append(s)
        _LOG_CACHE.clear()
        _LOG_CACHE[key] = ({str(o["object_id"]): o for o in objects}, by_object)
    return _LOG_CACHE[key]


@dataclass(frozen=True)
class CharacterizeTask:
    """``characterize`` for one object of a squeeze-log directory (a picklable sweep task)."""

    method: str = "lsq"
    window_s: float | None = None

    def __call__(self, item: dict[str, Any]) -> Any:
        """Fit one object; its coefficients row (an Arrow table).

        Raises:
            InputDataError: the object has no squeezes or cannot be fitted (recorded as failed).
        """
        oid, log = str(item["object_id"]), str(item["log_path"])
        meta, by_object = _read_log_cached(log)
        group = by_object.get(oid)
        if not group:
            raise InputDataError(f"object {oid!r} has no squeezes", path=log)
        rate_hz = _stored_rate(meta.get(oid))
        window = self.window_s if self.window_s is not None else default_window_s(rate_hz)
        try:
            df = characterize({oid: group}, self.method, window_s=window)  # type: ignore[arg-type]
        except InputDataError as err:
            if err.path is None:
                raise InputDataError(err.message, path=log) from err
            raise
        return spec_rows(df, "coefficients")


def characterize_sweep(
    log_dir: str,
    task: CharacterizeTask,
    *,
    output: str,
    sweep: SweepOptions,
    force: bool = False,
) -> SweepSummary:
    """``characterize DIR -o OUT/``: one fit per object of a squeeze-log directory, in parallel.

    Raises:
        MissingInputError: ``log_dir`` does not exist (exit 66).
        UsageError: ``log_dir`` is a file, or the window is not > 0 (exit 2).
    """
    if task.window_s is not None and not (math.isfinite(task.window_s) and task.window_s > 0):
        raise UsageError(f"--window-s must be a finite number > 0 s, got {task.window_s}")
    if not os.path.isdir(log_dir):
        if not os.path.exists(log_dir):
            raise MissingInputError("no such file or directory", path=log_dir)
        raise UsageError(
            "a dataset directory output (-o DIR/) needs a squeeze-log directory input "
            "(measure --sim -o DIR/)"
        )
    settings = {"method": task.method, "window_s_option": task.window_s}
    fingerprint = dataset_fingerprint(
        "characterize", "coefficients", settings, {"log": sha256_file(log_dir)}
    )
    return run_sweep(
        task,
        characterize_items(log_dir),
        out_dir=output,
        schema=table_schema("coefficients"),
        fingerprint=fingerprint,
        force=force,
        **sweep.run_kwargs(),
    )


# --------------------------------------------------------------------------------------------
# Synthetic Kelvin–Voigt squeezes (ground truth for tests and examples)
# --------------------------------------------------------------------------------------------


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
