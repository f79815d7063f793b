"""The fit: D and λ of one object's squeezes (the paper's Kelvin model, section III.B).

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

Every fit carries its diagnostics (R², standard errors, samples, the loading range, the damping
excitation and design condition, the preload) and quality flags
(:mod:`deformctl.characterize.quality`): λ is NaN when it cannot be told from a constant force or
from D, a squeeze that ruptured is fitted up to its rupture
(:mod:`deformctl.squeeze.rupture`), and the policy (warnings, ``strict``, negative D) is
applied before a table is written. ``preload="fit"`` adds an intercept F0 (a
contact preload) to the model; the lsq fits always bound λ ≥ 0.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pandas as pd

from deformctl.characterize.coefficients import CoefficientFit, _coefficient_frame
from deformctl.characterize.material_options import check_model, lag_estimated
from deformctl.characterize.objectfit import ObjectFit, fit_object
from deformctl.characterize.options import (
    Method,
    Preload,
    check_method,
    check_paper_options,
    check_preload,
)
from deformctl.characterize.prepare import _where, validate_squeeze
from deformctl.characterize.quality import PAPER_MONOTONIC_FRAC
from deformctl.characterize.stiffness import damping_excitation
from deformctl.errors import InputDataError, UsageError
from deformctl.quantities import WINDOW_S
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.signals import sg_smooth, sg_window_length, uniform_grid
from deformctl.squeeze.rupture import Rupture, cut_rupture_smoothed
from deformctl.squeeze.window import DEFAULT_WINDOW_S
from deformctl.units import N_PER_CM, NS_PER_CM

#: Default Savitzky–Golay polynomial order (cubic: exact for d through a smooth corner).
DEFAULT_POLYORDER = 3
#: Samples with compression below this fraction of the squeeze's peak compression are not used.
DEFAULT_MIN_COMPRESSION_FRAC = 0.02
#: Paper method: samples with |d'| below this fraction of the peak |d'| are not used for λ.
DEFAULT_MIN_RATE_FRAC = 0.05
#: Relative spread of the sampling interval above which a log is resampled to a uniform grid.
UNIFORM_DT_RTOL = 1e-3


@dataclass(frozen=True)
class _Prepared:
    """One validated squeeze on a uniform grid with SG-smoothed compression and rate.

    All arrays ``[m]`` after trimming half a window at each end; ``rupture`` is where the
    squeeze was cut (None when it did not rupture).
    """

    force_n: FloatArray
    compression_m: FloatArray
    rate_m_per_s: FloatArray
    window_samples: int
    rupture: Rupture | None = None


def _uniform(s: SqueezeSeries) -> tuple[float, FloatArray, FloatArray]:
    """Return ``(dt_s, force_n [m], compression_m [m])`` on a uniform grid.

    A log whose sampling interval varies by more than :data:`UNIFORM_DT_RTOL` is linearly
    resampled onto the grid ``t0 + k · median(dt)``.
    """
    dt_s, _, (force_n, comp_m) = uniform_grid(s.time_s, s.force_n, s.compression_m)
    return dt_s, force_n, comp_m


_window_length = sg_window_length


def _prepare(
    s: SqueezeSeries, *, window_s: float, polyorder: int, min_compression_frac: float
) -> _Prepared:
    """Validate, cut at a rupture, resample, differentiate, trim the edges and mask small d."""
    validate_squeeze(s)
    s, rupture, smoothed = cut_rupture_smoothed(s, window_s=window_s)
    dt_s, force_n, comp_m = _uniform(s)
    wl = _window_length(window_s, dt_s, polyorder)
    if force_n.shape[0] < 2 * wl:
        rate_hz = 1.0 / dt_s
        why = (
            f"; the sample rate {rate_hz:.3g} Hz is implausible: is the time unit right?"
            if not 1.0 <= rate_hz <= 1e5
            else f" (cut at a rupture, {rupture.describe()})"
            if rupture is not None
            else " (use a shorter window)"
        )
        raise InputDataError(
            f"{_where(s)}: only {force_n.shape[0]} samples on the uniform grid, need at least "
            f"{2 * wl} for a {wl}-sample Savitzky–Golay window{why}"
        )
    if (
        smoothed is not None
        and (smoothed.dt_s, smoothed.window_samples, smoothed.polyorder) == (dt_s, wl, polyorder)
        and smoothed.compression_m.shape == comp_m.shape
    ):  # the rupture search smoothed this very squeeze so already
        d_m, rate = smoothed.compression_m, smoothed.rate_m_per_s
    else:
        d_m, rate = sg_smooth(comp_m, wl, polyorder, dt_s)
    half = wl // 2
    core = slice(half, force_n.shape[0] - half)
    f, d, v = force_n[core], d_m[core], rate[core]
    keep = d > min_compression_frac * float(np.max(d))
    return _Prepared(
        force_n=f[keep],
        compression_m=d[keep],
        rate_m_per_s=v[keep],
        window_samples=wl,
        rupture=rupture,
    )


def _check_options(window_s: float, polyorder: int, min_compression_frac: float) -> None:
    WINDOW_S.check(window_s)
    if polyorder < 1:
        raise UsageError(f"polyorder must be >= 1 (the fit needs a derivative), got {polyorder}")
    if not 0 <= min_compression_frac < 1:
        raise UsageError(f"min_compression_frac must be in [0, 1), got {min_compression_frac}")


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


def _unit_rms(x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``x`` with unit-RMS columns, and the column scales (1 for an all-zero column)."""
    scale = np.sqrt(np.mean(x * x, axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    return x / scale, scale


def _ranges(f: FloatArray, d: FloatArray) -> dict[str, float]:
    """The loading range used: d (cm) and f (N) extremes, keyed as the row's columns."""
    return {
        "compression_min_cm": float(np.min(d)) * 100.0,
        "compression_max_cm": float(np.max(d)) * 100.0,
        "force_min_n": float(np.min(f)),
        "force_max_n": float(np.max(f)),
    }


def _ruptures(prepared: Sequence[_Prepared]) -> tuple[Rupture, ...]:
    return tuple(p.rupture for p in prepared if p.rupture is not None)


def fit_lsq(
    squeezes: Sequence[SqueezeSeries],
    *,
    window_s: float = DEFAULT_WINDOW_S,
    preload: Preload = "zero",
    model: str = "kv",
    lag_s: float | None = 0.0,
    at_force_n: float | None = None,
) -> CoefficientFit:
    """One object's least-squares fit: a material law (Kelvin–Voigt by default), bounded.

    The fit of :func:`deformctl.characterize.objectfit.fit_object` (window means of the law's
    integral over the whole squeeze, λ ≥ 0, a lag when asked for), as a :class:`CoefficientFit`.

    Args:
        squeezes: the object's squeezes (same ``object_id``), arrays ``[n]``.
        window_s: averaging window, s.
        preload: ``"zero"`` or ``"fit"`` (an intercept F0, reported as ``preload_n``).
        model: ``kv`` (default), ``hc``, ``sls`` or ``auto``.
        lag_s: the force's lag behind the compression, s; None fits it.
        at_force_n: the operating force D is stated at, N (None: the median loading force).

    Raises:
        InputDataError: a squeeze that fails :func:`validate_squeeze` or is shorter than two
            windows.
        UsageError: an invalid option value.
    """
    _check_options(window_s, DEFAULT_POLYORDER, DEFAULT_MIN_COMPRESSION_FRAC)
    check_preload(preload)
    check_model(model)
    _require(squeezes)
    obj = fit_object(
        squeezes,
        model=model,
        window_s=window_s,
        fit_preload=preload == "fit",
        lag_s=lag_s,
        at_force_n=at_force_n,
    )
    return CoefficientFit.from_object(obj)


def _monotonic(rate: FloatArray) -> bool:
    """Whether the rate has one sign on all but :data:`PAPER_MONOTONIC_FRAC` of its samples."""
    if rate.size == 0:
        return True
    minority = min(float(np.mean(rate > 0)), float(np.mean(rate < 0)))
    return minority < PAPER_MONOTONIC_FRAC


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

    A squeeze whose rate keeps one sign (a monotonic loading, see
    :data:`deformctl.characterize.quality.PAPER_MONOTONIC_FRAC`) gives no λ: its residual ratio is
    pinned near 0 by construction. λ is the mean over the other squeezes, NaN with the flag
    ``damping_unidentifiable`` when there are none.

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
    ds: list[FloatArray] = []
    vs: list[FloatArray] = []
    preds: list[FloatArray] = []
    prepared: list[_Prepared] = []
    for s in squeezes:
        p = _prepare(
            s, window_s=window_s, polyorder=polyorder, min_compression_frac=min_compression_frac
        )
        if p.force_n.shape[0] < 3:
            raise InputDataError(f"{_where(s)}: only {p.force_n.shape[0]} usable samples")
        prepared.append(p)
        d_i = float(agg(p.force_n / p.compression_m))
        abs_rate = np.abs(p.rate_m_per_s)
        moving = abs_rate > min_rate_frac * float(np.max(abs_rate))
        if not np.any(moving):
            raise InputDataError(f"{_where(s)}: compression never changes; no damping estimate")
        if _monotonic(p.rate_m_per_s[moving]):
            lam_i = math.nan
        else:
            resid = p.force_n[moving] - d_i * p.compression_m[moving]
            lam_i = float(agg(resid / p.rate_m_per_s[moving]))
        d_list.append(d_i)
        lam_list.append(lam_i)
        fs.append(p.force_n)
        ds.append(p.compression_m)
        vs.append(p.rate_m_per_s)
        lam_pred = 0.0 if math.isnan(lam_i) else lam_i
        preds.append(d_i * p.compression_m + lam_pred * p.rate_m_per_s)
    d_arr = np.asarray(d_list)
    lam_arr = np.asarray([x for x in lam_list if not math.isnan(x)])
    k, k_lam = d_arr.shape[0], lam_arr.shape[0]
    se_d = float(np.std(d_arr, ddof=1) / math.sqrt(k)) if k > 1 else float("nan")
    se_l = float(np.std(lam_arr, ddof=1) / math.sqrt(k_lam)) if k_lam > 1 else float("nan")
    f_all, d_all, v_all = np.concatenate(fs), np.concatenate(ds), np.concatenate(vs)
    x = np.column_stack([d_all, v_all])
    return CoefficientFit(
        deformability_n_per_cm=float(d_arr.mean()) / N_PER_CM,
        damping_ns_per_cm=(float(lam_arr.mean()) if k_lam else math.nan) / NS_PER_CM,
        method="paper",
        deformability_se_n_per_cm=se_d / N_PER_CM,
        damping_se_ns_per_cm=se_l / NS_PER_CM,
        r2=_r2(f_all, np.concatenate(preds)),
        n_samples=int(f_all.shape[0]),
        n_squeezes=k,
        damping_excitation=damping_excitation(d_all, v_all),
        design_condition=float(np.linalg.cond(_unit_rms(x)[0])),
        damping_unidentifiable=k_lam == 0,
        window_samples=max(p.window_samples for p in prepared),
        ruptures=_ruptures(prepared),
    ).with_ranges(_ranges(f_all, d_all))


def characterize(
    squeezes_by_object: Mapping[str, Sequence[SqueezeSeries]],
    method: Method = "lsq",
    *,
    preload: Preload | Mapping[str, Preload] = "zero",
    recorded_ruptures: Mapping[str, Sequence[Rupture]] | None = None,
    model: str = "auto",
    at_force_n: float | None = None,
    lag_s: float | Mapping[str, float | None] | None = 0.0,
    objects: Mapping[str, Mapping[str, object]] | None = None,
    **options: float,
) -> pd.DataFrame:
    """Fit every object's squeezes and return the coefficient table.

    Args:
        squeezes_by_object: object id → that object's squeezes.
        method: ``"lsq"`` (default: the material laws,
            :func:`deformctl.characterize.objectfit.fit_object`) or ``"paper"``
            (:func:`fit_paper`).
        preload: lsq only: ``"zero"`` or ``"fit"``, for every object or per object id.
        recorded_ruptures: object id → the ruptures ``measure`` cut off (from the log); they
            count for the ``rupture`` flag and the rupture columns with those found here.
        model: lsq: ``kv``, ``hc``, ``sls``, ``exp`` or ``auto`` (all four, chosen by
            :func:`deformctl.characterize.materials.choose`).
        at_force_n: lsq: the operating force D is stated at, N (None: F_w, else the median
            loading force).
        lag_s: lsq: the force's lag behind the compression, s, for every object or per object
            id; None fits it. The library's default is 0 (simulated squeezes have none; the
            stage fits it for rig recordings, :func:`deformctl.characterize.default_lag`).
        objects: object id → its catalog fields (``weight_n``, ``friction_mu`` for F_w;
            ``force_lag_source`` ``auto``, a lag ``measure`` estimated and took out of the
            force: λ is withheld, :func:`deformctl.characterize.material_options.lag_estimated`).
        **options: passed to the estimator (``window_s``, ...).

    Returns:
        One row per object, columns :data:`COEFFICIENT_COLUMNS` (coefficients in N/cm, N·s/cm;
        ``quality`` is ``ok`` or the flags of :mod:`deformctl.characterize.quality`).

    Raises:
        UsageError: an unknown method or model, a fitted preload with ``method="paper"``, or
            ``at_force_n`` above an object's peak force.
        InputDataError: any object whose squeezes cannot be fitted (the message names it).
    """
    rows = _fit_rows(
        squeezes_by_object,
        method,
        preload=preload,
        recorded_ruptures=recorded_ruptures,
        model=model,
        at_force_n=at_force_n,
        lag_s=lag_s,
        objects=objects,
        fits_out=None,
        **options,
    )
    return _coefficient_frame(rows)


def _number(value: object) -> float | None:
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def _fit_rows(
    squeezes_by_object: Mapping[str, Sequence[SqueezeSeries]],
    method: Method,
    *,
    preload: Preload | Mapping[str, Preload],
    recorded_ruptures: Mapping[str, Sequence[Rupture]] | None,
    model: str = "auto",
    at_force_n: float | None = None,
    lag_s: float | Mapping[str, float | None] | None = 0.0,
    objects: Mapping[str, Mapping[str, object]] | None = None,
    fits_out: dict[str, ObjectFit] | None = None,
    **options: float,
) -> list[dict[str, object]]:
    """The rows of :func:`characterize`, one per object (lsq: each object's material fit goes
    into ``fits_out`` when given)."""
    check_method(method)
    check_paper_options(method, preload)
    check_model(model)
    rows: list[dict[str, object]] = []
    for object_id, squeezes in squeezes_by_object.items():
        if method == "lsq":
            mode = preload if isinstance(preload, str) else preload.get(object_id, "zero")
            lag = lag_s if lag_s is None or isinstance(lag_s, float | int) else lag_s.get(object_id)
            meta = (objects or {}).get(object_id, {})
            obj = fit_object(
                squeezes,
                model=model,
                window_s=float(options.get("window_s", DEFAULT_WINDOW_S)),
                fit_preload=mode == "fit",
                lag_s=None if lag is None else float(lag),
                at_force_n=at_force_n,
                weight_n=_number(meta.get("weight_n")),
                friction_mu=_number(meta.get("friction_mu")),
                lag_estimated=lag_estimated(meta),
            )
            fit = CoefficientFit.from_object(obj)
            if fits_out is not None:
                fits_out[object_id] = obj
        else:
            fit = fit_paper(squeezes, **options)  # type: ignore[arg-type]
        recorded = list((recorded_ruptures or {}).get(object_id, ()))
        if recorded:
            merged = sorted([*recorded, *fit.ruptures], key=lambda r: r.squeeze_index)
            fit = dataclasses.replace(fit, ruptures=tuple(merged))
        rows.append(fit.row(object_id))
    return rows
