"""One object's material fit end to end: its squeezes in, every law's fit and the row's numbers out.

:func:`fit_object` is ``characterize --method lsq``: it validates each squeeze
(:func:`deformctl.characterize.prepare.validate_squeeze`), cuts it at a rupture and looks for
relaxation (:mod:`deformctl.characterize.rupture`), judges whether damping can be identified
(:func:`deformctl.characterize.stiffness.speed_summary` and
:func:`deformctl.characterize.quality.damping_identifiable`), fits the asked law or all three
(:func:`deformctl.characterize.materials.fit_material`; ``auto`` chooses by BIC) and states the
deformability at the operating force, the small-strain stiffness and the stiffening of the
loading curve, and the loop's dissipated energy.

When damping cannot be identified (the rate is a constant, follows the compression, or only
changes its sign: a constant-rate ramp, a load–unload cycle at one rate) the laws are fitted
without their rate-dependent part and without a lag, with an intercept (at one speed a viscous
force is a constant, and a lag a shift of it): the damping columns are NaN, the row says
``damping_unidentifiable`` and gives ``hysteresis_energy_j`` when a loop closes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from deformctl.characterize.laws import (
    DAMPING_PARAMETERS,
    PARAMETERS,
    compression_at_force,
    elastic_force,
    equivalent_damping,
    rate_force,
    secant_stiffness,
)
from deformctl.characterize.material_options import MODELS
from deformctl.characterize.materials import (
    MIN_COMPRESSION_FRAC,
    FitData,
    FitSqueeze,
    MaterialFit,
    choose,
    fit_material,
    fit_squeeze,
)
from deformctl.characterize.prepare import _where, validate_squeeze
from deformctl.characterize.quality import damping_identifiable
from deformctl.characterize.rupture import (
    Relaxation,
    Rupture,
    cut_rupture,
    find_relaxation,
    phase_slice,
)
from deformctl.characterize.stiffness import (
    LoadingStiffness,
    SpeedSummary,
    hysteresis_energy_j,
    loading_stiffness,
    operating_force_n,
    speed_summary,
)
from deformctl.errors import InputDataError, UsageError
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.signals import quarter_window_length, savgol, sg_window_length, uniform_grid

#: The windows compared with the law where D is stated: mean compression within this fraction
#: of the law's compression at the operating force (``secant_residual_frac``).
SECANT_BAND = 0.1
#: Savitzky–Golay order of the window length (the window the log's rate implies, as ``paper``).
POLYORDER = 3
#: Windows slower than this fraction of the 95th-percentile speed have no direction of motion.
HOLD_RATE_FRAC = 0.02
#: Speeds within this ratio are one speed in the per-speed residuals.
SAME_SPEED_RATIO = 1.2


@dataclass(frozen=True)
class Grid:
    """One squeeze on its uniform grid (after its rupture cut)."""

    squeeze_index: int
    dt_s: float
    force_n: FloatArray
    compression_m: FloatArray


@dataclass(frozen=True)
class ObjectFit:
    """Everything :func:`fit_object` found for one object.

    Attributes:
        fits: every law fitted (one, or three for ``auto``), in :data:`MODELS` order.
        chosen: the law whose numbers the row reports.
        data: the windows the laws were fitted to.
        grids: the squeezes on their grids (after their rupture cuts).
        deformability_n_per_m: secant stiffness at the operating force, N/m.
        deformability_se_n_per_m: its standard error (delta method), N/m.
        damping_ns_per_m: the equivalent damping at the operating compression, N·s/m (NaN when
            not identifiable).
        damping_se_ns_per_m: its standard error.
        operating_force_n: the force D is stated at, N; ``operating_force_source`` says why.
        loading: the loading curve's slopes (N/m).
        speeds: the squeezes' speeds.
        damping_identifiable: whether the rate-dependent part was fitted.
        damping_excitation: share of the rate independent of a constant and of d.
        hysteresis_energy_j: mean dissipated energy of the closed loops, J (NaN: none).
        ruptures, relaxations: what the squeezes showed.
        sample_r2: each law's R² on the samples.
        fit_preload: a preload was asked for (without damping one is fitted anyway: the row
            reports it only when asked).
    """

    fits: tuple[MaterialFit, ...]
    chosen: MaterialFit
    data: FitData
    grids: tuple[Grid, ...]
    deformability_n_per_m: float
    deformability_se_n_per_m: float
    damping_ns_per_m: float
    damping_se_ns_per_m: float
    operating_force_n: float
    operating_force_source: str
    loading: LoadingStiffness
    speeds: SpeedSummary
    damping_identifiable: bool
    damping_excitation: float
    hysteresis_energy_j: float
    ruptures: tuple[Rupture, ...] = ()
    relaxations: tuple[Relaxation, ...] = ()
    window_samples: int = 0
    n_samples: int = 0
    peak_force_n: float = math.nan
    compression_range_m: tuple[float, float] = (math.nan, math.nan)
    force_range_n: tuple[float, float] = (math.nan, math.nan)
    per_speed: tuple[tuple[float, float], ...] = field(default=())
    sample_r2: dict[str, float] = field(default_factory=dict)
    fit_preload: bool = False
    secant_residual_frac: float = math.nan

    def fit(self, model: str) -> MaterialFit | None:
        """The fit of one law, or None when it was not fitted."""
        return next((f for f in self.fits if f.model == model), None)


def _grid(s: SqueezeSeries, window_s: float) -> tuple[Grid, int]:
    dt_s, _, (force_n, comp_m) = uniform_grid(s.time_s, s.force_n, s.compression_m)
    wl = sg_window_length(window_s, dt_s, POLYORDER)
    if force_n.shape[0] < 2 * wl:
        rate_hz = 1.0 / dt_s
        why = (
            f"; the sample rate {rate_hz:.3g} Hz is implausible: is the time unit right?"
            if not 1.0 <= rate_hz <= 1e5
            else " (use a shorter window)"
        )
        raise InputDataError(
            f"{_where(s)}: only {force_n.shape[0]} samples on the uniform grid, need at least "
            f"{2 * wl} for a {wl}-sample window{why}"
        )
    return Grid(s.squeeze_index, dt_s, force_n, comp_m), wl


def _identifiable(data: FitData) -> tuple[bool, float, SpeedSummary]:
    """Whether damping can be told, the rate's excitation, and the speeds.

    λ must be separable from a preload, from D and from a rate-independent force that only
    follows the direction of motion (hysteresis, friction: ``μ sign(ḋ)``): on the window means,
    the share of the rate's mean square that ``[1, d, sign(ḋ)]`` cannot explain is the
    excitation, and allowing the preload and the direction term moves λ by the sensitivity;
    :func:`deformctl.characterize.quality.damping_identifiable` judges them. A constant-rate
    ramp and a load–unload cycle at one rate (``ḋ = v sign(ḋ)``) give an excitation near 0.
    Squeezes that move at a single speed without a hold
    (:attr:`~deformctl.characterize.stiffness.SpeedSummary.single_speed`) are not identifiable
    either, however exactly the short accelerations at their corners pin a Kelvin–Voigt λ: a
    real material's rate dependence cannot be told from one speed.
    """
    rates = [s.mean_rate() for s in data.squeezes]
    comps = [s.mean_compression() for s in data.squeezes]
    speeds = speed_summary(rates, comps, data.window_samples)
    d, v = np.concatenate(comps), np.concatenate(rates)
    f = data.target()
    top = float(np.percentile(np.abs(v), 95)) if v.size else 0.0
    direction = np.where(np.abs(v) > HOLD_RATE_FRAC * top, np.sign(v), 0.0)
    base = np.column_stack([np.ones_like(d), d, direction])
    excitation = _unexplained(v, base)
    sensitivity = math.inf
    try:
        lam2 = float(np.linalg.lstsq(np.column_stack([d, v]), f, rcond=None)[0][1])
        lam4 = float(np.linalg.lstsq(np.column_stack([base, v]), f, rcond=None)[0][3])
        big = max(abs(lam2), abs(lam4))
        sensitivity = abs(lam2 - lam4) / big if big > 0 else 0.0
    except np.linalg.LinAlgError:
        pass
    ok = damping_identifiable(excitation, sensitivity) and not speeds.single_speed
    return ok, excitation, speeds


def _unexplained(v: FloatArray, x: FloatArray) -> float:
    """``‖v − P v‖² / ‖v‖²`` with ``P`` the projection onto the columns of ``x``, in [0, 1]."""
    total = float(v @ v)
    if not total > 0:
        return 0.0
    coef, *_ = np.linalg.lstsq(x, v, rcond=None)
    resid = v - x @ coef
    return min(1.0, float(resid @ resid) / total)


def _short_rate(d: FloatArray, window_samples: int, dt_s: float) -> FloatArray:
    """The compression's rate from a cubic Savitzky–Golay fit over a quarter window (at least 5
    samples; one-sided at the ends), m/s: short, so the corners of a squeeze are not smeared."""
    length = quarter_window_length(window_samples)
    if d.shape[0] < length:
        return np.gradient(d, dt_s)
    return savgol(d, length, 3, deriv=1, delta=dt_s)


def _secant_residual(chosen: MaterialFit, data: FitData, force_n: float) -> float:
    """How far the chosen law misses the recording where D is stated: the median window residual
    (measured mean force − the law's) over the windows whose mean compression is within
    :data:`SECANT_BAND` of the law's compression at ``force_n`` (above the preload), as a fraction
    of ``force_n``; NaN when no window is there (the law is extrapolated, nothing to compare)."""
    d_op = compression_at_force(chosen.model, chosen.params, force_n)
    if not (math.isfinite(d_op) and d_op > 0 and force_n > 0):
        return math.nan
    lag = chosen.params.get("lag_s", 0.0)
    lag = lag if math.isfinite(lag) else 0.0
    resid: list[FloatArray] = []
    for s in data.squeezes:
        near = np.abs(s.mean_compression() - d_op) <= SECANT_BAND * d_op
        resid.append((s.mean_force(lag) - chosen.window_prediction(s))[near])
    r = np.concatenate(resid)
    return float(np.median(r)) / force_n if r.size else math.nan


def _loading(
    chosen: MaterialFit, data: FitData, grids: Sequence[Grid], damping: bool
) -> tuple[LoadingStiffness, FloatArray]:
    """The loading curve's slopes on the loading samples, with the chosen law's preload and
    (when damping was fitted) rate-dependent force taken out, and the loading samples' forces.

    The force is moved back by the fitted lag; KV's and HC's rate comes from a short cubic
    Savitzky–Golay derivative (:func:`_short_rate`: a long one smooths the squeeze's corners, and
    under damping that error lands in the small-strain slope), SLS's arm from its recursion.
    """
    lag = chosen.params.get("lag_s", 0.0)
    lag = lag if math.isfinite(lag) else 0.0
    name = {"kv": "damping_ns_per_m", "hc": "damping_ns_per_m_pow_n_plus_1"}.get(
        chosen.model, "arm_stiffness_n_per_m"
    )
    value = chosen.params[name]
    unit = dict(chosen.params)
    unit[name] = 1.0
    ds: list[FloatArray] = []
    fs: list[FloatArray] = []
    rs: list[FloatArray] = []
    raw: list[FloatArray] = []
    for g in grids:
        t = np.asarray(g.dt_s * np.arange(g.force_n.shape[0]), dtype=np.float64)
        load = phase_slice(t, g.force_n, "loading", window_s=data.window_samples * g.dt_s)
        f = np.interp(t + lag, t, g.force_n) if lag > 0 else g.force_n
        d = g.compression_m
        per_unit = np.zeros_like(d)
        if damping and math.isfinite(value) and value > 0:
            rate = _short_rate(d, data.window_samples, g.dt_s)
            per_unit = rate_force(chosen.model, unit, d, rate, g.dt_s)
        elastic = f - chosen.params["preload_n"] - (value * per_unit if damping else 0.0)
        ds.append(d[load])
        fs.append(elastic[load])
        rs.append(per_unit[load])
        raw.append(g.force_n[load])
    se = chosen.se.get(name, math.nan)
    return (
        loading_stiffness(
            np.concatenate(ds),
            np.concatenate(fs),
            rate_force_per_unit=np.concatenate(rs) if damping else None,
            rate_unit_se=se if math.isfinite(se) else 0.0,
            correlated_samples=data.window_samples if damping else 1,
        ),
        np.concatenate(raw),
    )


def _sample_rates(data: FitData, grids: Sequence[Grid]) -> list[FloatArray] | None:
    """Each grid's compression rate from a cubic Savitzky–Golay derivative over the window, m/s
    (None when the laws carry no damping): computed once, for every law's :func:`_sample_r2`."""
    if not data.damping:
        return None
    rates = []
    for g in grids:
        n = g.compression_m.shape[0]
        wl = min(data.window_samples, n - (1 - n % 2))
        rates.append(savgol(g.compression_m, wl, POLYORDER, deriv=1, delta=g.dt_s))
    return rates


def _sample_r2(
    fit: MaterialFit, grids: Sequence[Grid], rates: Sequence[FloatArray] | None
) -> float:
    """R² of a law on the samples in contact (not the window means, which average the sensor's
    noise away): ``1 − Σ(f − f̂)²/Σ(f − f̄)²`` with the force moved back by the lag and the rate
    from :func:`_sample_rates` (None: no damping term)."""
    lag = fit.params.get("lag_s", 0.0)
    lag = lag if math.isfinite(lag) else 0.0
    ys: list[FloatArray] = []
    preds: list[FloatArray] = []
    for i, g in enumerate(grids):
        n = g.force_n.shape[0]
        t = np.asarray(g.dt_s * np.arange(n), dtype=np.float64)
        f = np.interp(t + lag, t, g.force_n) if lag > 0 else g.force_n
        d = g.compression_m
        pred = fit.params["preload_n"] + elastic_force(fit.model, fit.params, d)
        if rates is not None:
            pred = pred + rate_force(fit.model, fit.params, d, rates[i], g.dt_s)
        contact = np.maximum.accumulate(d) >= MIN_COMPRESSION_FRAC * float(np.max(d))
        ys.append(f[contact])
        preds.append(pred[contact])
    y, p = np.concatenate(ys), np.concatenate(preds)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    return 1.0 - float(np.sum((y - p) ** 2)) / ss_tot if ss_tot > 0 else math.nan


def _per_speed(speeds: SpeedSummary, rms: Sequence[float]) -> tuple[tuple[float, float], ...]:
    """``(speed, RMS window residual)`` per distinct speed (squeezes within
    :data:`SAME_SPEED_RATIO` pooled)."""
    groups: list[tuple[list[float], list[float]]] = []
    for v, r in sorted(zip(speeds.speeds_m_per_s, rms, strict=True)):
        if groups and v <= SAME_SPEED_RATIO * groups[-1][0][0]:
            groups[-1][0].append(v)
            groups[-1][1].append(r)
        else:
            groups.append(([v], [r]))
    return tuple((float(np.mean(v)), float(np.sqrt(np.mean(np.square(r))))) for v, r in groups)


def fit_object(
    squeezes: Sequence[SqueezeSeries],
    *,
    model: str = "auto",
    window_s: float,
    fit_preload: bool,
    lag_s: float | None = None,
    at_force_n: float | None = None,
    weight_n: float | None = None,
    friction_mu: float | None = None,
) -> ObjectFit:
    """Fit one object's squeezes (module docstring).

    Args:
        squeezes: the object's squeezes (same ``object_id``).
        model: ``kv``, ``hc``, ``sls`` or ``auto`` (all three, chosen by BIC).
        window_s: the averaging window, s (the Savitzky–Golay window the log's rate implies).
        fit_preload: fit a preload ``F0``.
        lag_s: the lag of the force behind the compression, s; None fits it.
        at_force_n: the operating force for D, N; None: F_w from ``weight_n`` and
            ``friction_mu`` when both are known, else the median loading force.
        weight_n, friction_mu: the object's weight and friction (from the log).

    Raises:
        InputDataError: a squeeze no fit can use (see ``validate_squeeze``), or too short.
        UsageError: ``at_force_n`` above the peak force of the squeezes (exit 2).
    """
    if model not in (*MODELS, "auto"):
        raise UsageError(f"unknown model {model!r}")
    grids: list[Grid] = []
    fit_squeezes: list[FitSqueeze] = []
    ruptures: list[Rupture] = []
    relaxations: list[Relaxation] = []
    wl = 0
    for s in squeezes:
        validate_squeeze(s)
        cut, rupture = cut_rupture(s, window_s=window_s)
        if rupture is not None:
            ruptures.append(rupture)
        relax = find_relaxation(cut, window_s=window_s)
        if relax is not None:
            relaxations.append(relax)
        g, wl_i = _grid(cut, window_s)
        wl = max(wl, wl_i)
        grids.append(g)
        fit_squeezes.append(fit_squeeze(g.squeeze_index, g.dt_s, g.force_n, g.compression_m, wl_i))
    peak_force = max(float(np.max(g.force_n)) for g in grids)
    if at_force_n is not None and not at_force_n <= peak_force:
        raise UsageError(
            f"--at-force-n {at_force_n:g} N is above the peak force {peak_force:.4g} N of "
            f"object {squeezes[0].object_id!r}: the fit says nothing there"
        )
    base = FitData(tuple(fit_squeezes), wl, fit_preload=fit_preload, lag_s=lag_s)
    identifiable, excitation, speeds = _identifiable(base)
    # without damping a single speed's viscous force is a constant: an intercept takes it
    data = (
        base
        if identifiable
        else FitData(base.squeezes, wl, fit_preload=True, lag_s=0.0, damping=False)
    )
    models = MODELS if model == "auto" else (model,)
    fits = tuple(fit_material(m, data) for m in models)
    chosen = choose(fits)
    loading, loading_force = _loading(chosen, data, grids, identifiable)
    f_op, source = operating_force_n(at_force_n, weight_n, friction_mu, loading_force)
    preload = chosen.params["preload_n"]
    f_peak = peak_force - preload

    def above(params: dict[str, float]) -> float:  # the operating force above the preload
        return max(f_op - params["preload_n"], 1e-3 * f_peak)

    def secant(params: dict[str, float]) -> float:
        return secant_stiffness(chosen.model, params, above(params))

    def damping(params: dict[str, float]) -> float:
        d_op = compression_at_force(chosen.model, params, above(params))
        return equivalent_damping(chosen.model, params, d_op)

    lam = damping(chosen.params) if identifiable else math.nan
    held = chosen.at_bound
    lam_held = any(p in DAMPING_PARAMETERS[chosen.model] for p in held)
    lam_se = chosen.derived_se(damping) if identifiable and not lam_held else math.nan
    d_se = math.nan if PARAMETERS[chosen.model][0] in held else chosen.derived_se(secant)
    d_all = np.concatenate([s.compression_m for s in data.squeezes])
    f_all = np.concatenate([g.force_n for g in grids])
    rates = _sample_rates(data, grids)
    return ObjectFit(
        fits=fits,
        chosen=chosen,
        data=data,
        grids=tuple(grids),
        deformability_n_per_m=secant(chosen.params),
        deformability_se_n_per_m=d_se,
        damping_ns_per_m=lam,
        damping_se_ns_per_m=lam_se,
        operating_force_n=f_op,
        operating_force_source=source,
        loading=loading,
        speeds=speeds,
        damping_identifiable=identifiable,
        damping_excitation=excitation,
        hysteresis_energy_j=hysteresis_energy_j(
            [g.compression_m for g in grids], [g.force_n for g in grids]
        ),
        ruptures=tuple(ruptures),
        relaxations=tuple(relaxations),
        window_samples=wl,
        n_samples=int(sum(g.force_n.shape[0] for g in grids)),
        peak_force_n=peak_force,
        compression_range_m=(float(np.min(d_all)), float(np.max(d_all))),
        force_range_n=(float(np.min(f_all)), float(np.max(f_all))),
        per_speed=_per_speed(speeds, chosen.residual_rms_n),
        sample_r2={f.model: _sample_r2(f, grids, rates) for f in fits},
        fit_preload=fit_preload,
        secant_residual_frac=_secant_residual(chosen, data, above(chosen.params)),
    )
