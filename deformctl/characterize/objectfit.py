"""One object's material fit end to end: its squeezes in, every law's fit and the row's numbers out.

:func:`fit_object` is ``characterize --method lsq``: it validates each squeeze
(:func:`deformctl.characterize.prepare.validate_squeeze`), cuts it at a rupture and looks for
relaxation (:mod:`deformctl.squeeze.rupture`), judges whether damping can be identified
(:func:`deformctl.characterize.stiffness.speed_summary` and
:func:`deformctl.characterize.quality.damping_identifiable`), fits the asked law or all four
(:func:`deformctl.characterize.materials.fit_material`; ``auto`` chooses by
:func:`deformctl.characterize.materials.choose`) and states the
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
    WINDOW_STRIDE_DIV,
    FitData,
    FitSqueeze,
    MaterialFit,
    choose,
    fit_material,
    fit_squeeze,
)
from deformctl.characterize.prepare import _where, validate_squeeze
from deformctl.characterize.quality import damping_identifiable
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
from deformctl.squeeze.rupture import (
    Relaxation,
    Rupture,
    cut_rupture,
    find_relaxation,
    phase_slice,
)

#: The windows compared with the law where D is stated: mean compression within this fraction
#: of the law's compression at the operating force (``secant_residual_frac``).
SECANT_BAND = 0.1
#: λ is reported only when its standard error is at most this fraction of it: a recording that
#: determines λ more loosely (a force lag that trades against λ, a rate barely above the noise)
#: gets λ = NaN and ``damping_unidentifiable``, so that no λ off by more than 20 % is written as
#: ``ok``. Measured (``python -m deformctl.testing.shapes check --draws 2000``): the latency
#: draws whose λ came out 67 % and 90 % low had standard errors of 61 % and 96 %; clean
#: Kelvin–Voigt ramp-and-holds 0.3–3 %.
DAMPING_SE_REL_MAX = 0.25
#: ... or within this absolute error, N·s/m (0.15 N·s/cm, about 1 % of the paper's λ range of
#: 0–13 N·s/cm: a λ near 0 is determined when its error is small against that range, though not
#: against itself; a 0.17 s lagged λ = 0 squeeze reads 0.05 ± 0.10 N·s/cm, the two latency
#: draws above have errors of 0.24 and 0.26 N·s/cm).
DAMPING_SE_FLOOR_NS_PER_M = 15.0
#: With a lag of the force fitted (not known), λ is reported only when the lag's whole shift of
#: it and :data:`DAMPING_LAG_SE_COUNT` of its standard errors together are at most this fraction
#: of it (or :data:`DAMPING_SE_FLOOR_NS_PER_M`): ``D·L + k·SE_λ``, with D the law's secant and L
#: the lag. A lag shifts the force in time, ``D d(t − L) + λ ḋ(t − L) ≈ D d + (λ − D L) ḋ``, so
#: the ramps identify only ``λ − D L`` and λ and L come apart only at the few corners of the
#: speed. A fitted lag can be all error: the lag is bounded below by 0, so on a recording without
#: one any lag fitted is above the truth and λ takes ``+D·L`` with it. Measured
#: (``python -m deformctl.testing.shapes``, seed 1, 101 Kelvin–Voigt ramp-and-holds without a
#: lag whose fitted lag came out above 0): λ's errors averaged +1.29 standard errors (spread
#: 1.29); less ``D·L`` they average −0.11 (spread 0.84, at most 3.1). ``D·L`` is the bias and
#: the standard error is honest about the rest, so the error budget is the lag's whole shift plus
#: the usual two standard errors. A latency known from the rig goes to ``measure --lag-s
#: SECONDS``: the log records it and ``characterize`` fits no lag at all
#: (:func:`deformctl.characterize.default_lag`); after ``--lag-s auto`` λ is withheld
#: (``lag_estimated`` of :func:`fit_object`).
DAMPING_LAG_SHARE_MAX = 0.2
#: ``k``: the standard errors of λ counted with the lag's shift ``D·L`` (above).
DAMPING_LAG_SE_COUNT = 2.0
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
        fits: every law fitted (one, or four for ``auto``), in :data:`MODELS` order.
        chosen: the law whose numbers the row reports.
        data: the windows the laws were fitted to.
        grids: the squeezes on their grids (after their rupture cuts).
        deformability_n_per_m: D, the secant stiffness at the operating force from first contact
            (the log's zero of compression), N/m: the recording's own, the operating force over
            :func:`stated_compression` (not the force above a fitted preload), or the chosen
            law's above its preload when the loading never reaches the force or the law's
            damping is held at its bound 0 (``deformability_source``).
        deformability_se_n_per_m: its standard error (the law's, delta method, scaled), N/m.
        law_deformability_n_per_m: the chosen law's own secant at the operating force above its
            preload, N/m.
        deformability_source: ``recording`` or ``law``.
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
    law_deformability_n_per_m: float = math.nan
    deformability_source: str = "law"
    #: the share of the loading samples whose force is at or below the operating force
    loading_share_below_operating: float = math.nan

    def fit(self, model: str) -> MaterialFit | None:
        """The fit of one law, or None when it was not fitted."""
        return next((f for f in self.fits if f.model == model), None)


def _damping_determined(
    lam: float, lam_se: float, stiffness_n_per_m: float, params: dict[str, float], data: FitData
) -> bool:
    """Whether the fit determines λ (N·s/m, its standard error ``lam_se``; the law's secant
    stiffness where λ is stated, N/m; the law's parameters): its standard error is known and
    within :data:`DAMPING_SE_REL_MAX` of it (or :data:`DAMPING_SE_FLOOR_NS_PER_M`), and, when
    the force's lag was fitted (``data.lag_s`` None), the lag is not at its largest value (there
    the lag could not take the delay out of the force, and λ took it instead) and the lag's shift
    of λ and :data:`DAMPING_LAG_SE_COUNT` standard errors, ``D·L + k·SE_λ``, are at most
    :data:`DAMPING_LAG_SHARE_MAX` of it (or the floor)."""
    allowed = max(DAMPING_SE_REL_MAX * abs(lam), DAMPING_SE_FLOOR_NS_PER_M)
    if not (math.isfinite(lam) and math.isfinite(lam_se) and lam_se <= allowed):
        return False
    if data.lag_s is not None:  # known
        return True
    lag = max(params.get("lag_s", 0.0), 0.0)
    if lag >= data.lag_max_s * (1.0 - 1e-4):
        return False
    budget = max(DAMPING_LAG_SHARE_MAX * abs(lam), DAMPING_SE_FLOOR_NS_PER_M)
    return abs(stiffness_n_per_m) * lag + DAMPING_LAG_SE_COUNT * lam_se <= budget


def _grid(s: SqueezeSeries, window_s: float, rupture: Rupture | None = None) -> tuple[Grid, int]:
    """One squeeze on its uniform grid and its SG window, samples (``rupture``: where it was
    cut, for the error line).

    Raises:
        InputDataError: fewer than two windows of samples.
    """
    dt_s, _, (force_n, comp_m) = uniform_grid(s.time_s, s.force_n, s.compression_m)
    wl = sg_window_length(window_s, dt_s, POLYORDER)
    if force_n.shape[0] < 2 * wl:
        rate_hz = 1.0 / dt_s
        why = (
            f"; the sample rate {rate_hz:.3g} Hz is implausible: is the time unit right?"
            if not 1.0 <= rate_hz <= 1e5
            else " (use a shorter window)"
        )
        cut = (
            ""
            if rupture is None
            else f" up to its rupture at {rupture.time_s:.3g} s ({rupture.force_n:.3g} N)"
        )
        raise InputDataError(
            f"{_where(s)}: only {force_n.shape[0]} samples on the uniform grid{cut}, need at "
            f"least {2 * wl} for a {wl}-sample window{why}"
        )
    return Grid(s.squeeze_index, dt_s, force_n, comp_m), wl


def _identifiable(data: FitData) -> tuple[bool, float, SpeedSummary]:
    """Whether damping can be told, the rate's excitation, and the speeds.

    λ must be separable from a preload, from D and from a rate-independent force that only
    follows the direction of motion (hysteresis, friction: ``μ sign(ḋ)``): on the window means,
    the share of the rate's mean square that ``[1, d, sign(ḋ)]`` cannot explain (the sign kept
    through a hold, :func:`_stick_direction`) is the
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
    direction = np.concatenate([_stick_direction(r, HOLD_RATE_FRAC * top) for r in rates])
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


def _stick_direction(rate: FloatArray, still: float) -> FloatArray:
    """``sign(ḋ)`` of the windows, a hold keeping the last direction of motion (0 before the
    first): a rate-independent force (friction, hysteresis) sticks at a hold, where a viscous
    force vanishes, so a hold separates the two and a reversal at one speed does not."""
    moving = np.abs(rate) > still
    out = np.where(moving, np.sign(rate), 0.0)
    idx = np.where(moving, np.arange(rate.shape[0]), -1)
    last = np.maximum.accumulate(idx) if idx.size else idx
    return np.asarray(np.where(last >= 0, out[np.maximum(last, 0)], 0.0), dtype=np.float64)


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


def _crossing(x: FloatArray, y: FloatArray, force_n: float, contact_m: float) -> tuple[float, int]:
    """The first ``x`` at which ``y`` (from ``(contact_m, 0)``, first contact) reaches
    ``force_n``, linear between points, and the index of the point reached (NaN, -1: it never
    is)."""
    keep = x > contact_m
    x, y = x[keep], y[keep]
    xs = np.concatenate([[contact_m], x])
    ys = np.concatenate([[0.0], y])
    above = np.flatnonzero(ys >= force_n)
    if above.size == 0 or above[0] == 0:
        return math.nan, -1
    j = int(above[0])
    x0, x1, y0, y1 = xs[j - 1], xs[j], ys[j - 1], ys[j]
    d = float(x0 + (x1 - x0) * (force_n - y0) / (y1 - y0)) if y1 > y0 else float(x1)
    return d, int(np.flatnonzero(keep)[j - 1])


#: First contact is the law's zero of force when the law follows the recording's first loading
#: windows to within this fraction of the stated force; else the log's zero of compression.
CONTACT_FIT_FRAC = 0.05
#: ... and its preload is more than this fraction of the stated force (and 2 standard errors):
#: below it a linear law's D moves less, and a power law's flat start would turn a preload of
#: noise into a contact far from the zero (n = 1.6: 0.2 % of the force moves D by 3 %).
CONTACT_PRELOAD_FRAC = 0.01
#: The first loading windows of each squeeze that judge it (two windows' length).
CONTACT_WINDOWS = 2 * WINDOW_STRIDE_DIV


def contact_compression(chosen: MaterialFit) -> float:
    """The compression (m) at which the chosen law's rate-free force ``F0 + g(d)`` is 0: where a
    law with a preload says the object was first touched (below the log's zero for a positive
    preload: a seating preload, or a compression zero taken one noisy sample off); NaN when the
    law has no such point (Hunt–Crossley below 0, an exponential law whose preload its curve
    cannot cancel)."""
    p = chosen.params
    f0 = p["preload_n"]
    if f0 == 0.0:
        return 0.0
    k = p["stiffness_n_per_m_pow_n" if chosen.model == "hc" else "stiffness_n_per_m"]
    if not k > 0:
        return math.nan
    if chosen.model == "hc":
        return float((-f0 / k) ** (1.0 / p["exponent"])) if f0 < 0 else math.nan
    b = p.get("stiffening_per_m", 0.0) if chosen.model == "exp" else 0.0
    if b > 0:
        arg = 1.0 - f0 * b / k
        return float(math.log(arg) / b) if arg > 0 else math.nan
    return -f0 / k


def _crossing_se(
    x: FloatArray, y: FloatArray, rate: FloatArray, j: int, rate_rel_se: float
) -> float:
    """Standard error of the crossing's compression, m: the windows' scatter about a straight
    line through the :data:`WINDOW_STRIDE_DIV` windows either side of window ``j`` (a window in
    :data:`WINDOW_STRIDE_DIV` independent) and the rate-dependent force taken out there times its
    coefficient's relative error, over the line's slope (NaN: too few windows)."""
    lo, hi = max(j - WINDOW_STRIDE_DIV, 0), min(j + WINDOW_STRIDE_DIV + 1, x.shape[0])
    if hi - lo < 3 or not float(np.ptp(x[lo:hi])) > 0:
        return math.nan
    slope, icpt = np.polyfit(x[lo:hi], y[lo:hi], 1)
    if not slope > 0:
        return math.nan
    resid = y[lo:hi] - (slope * x[lo:hi] + icpt)
    noise = float(np.std(resid, ddof=2)) if hi - lo > 2 else 0.0
    se_y = noise / math.sqrt(max((hi - lo) / WINDOW_STRIDE_DIV, 1.0))
    se_y = math.hypot(se_y, float(abs(rate[j])) * rate_rel_se)
    return se_y / float(slope)


def stated_compression(
    chosen: MaterialFit, data: FitData, grids: Sequence[Grid], force_n: float
) -> tuple[float, float, float]:
    """The compression (m) from first contact at which the recording's loading force, its
    rate-dependent part taken out, first reaches ``force_n``, its standard error (m), and where
    first contact is (m on the log's compression); NaN when no squeeze's loading reaches it.

    First contact: the law's zero of force (:func:`contact_compression`) when its preload is more
    than 2 standard errors and :data:`CONTACT_PRELOAD_FRAC` of the force from 0 and the law
    follows the first :data:`CONTACT_WINDOWS` loading windows to within
    :data:`CONTACT_FIT_FRAC` of the force (a preload the law explains: a seating preload, a zero
    one noisy sample off, or at one speed the viscous force of a ramp), else the log's zero (no
    preload to speak of, or a law that misses the start of the curve: its preload is the
    misfit's, not a contact's).

    Each loading window (in order of compression) gives the recording's rate-free force at its
    mean compression ``x̄``: its measured mean force, less the law's rate-dependent window
    integral (exact: nothing is differentiated, heavy damping costs no accuracy) and less the
    law's curvature over the window (``mean g(d) − g(x̄)``, so a wide window on a stiffening
    curve is not biased); ``d`` is where that sequence, from ``(0, 0)``, first reaches the force
    (linear between windows); the median over the squeezes. The law only takes out what the
    windows cannot see; the curve is the recording's, the force counts from 0 at first contact
    (not from a fitted preload): a grip squeezing with F from first contact sees ``F / d``. The
    error: the larger of the squeezes' scatter and each crossing's own (:func:`_crossing_se`).
    """
    lag = chosen.params.get("lag_s", 0.0)
    lag = lag if math.isfinite(lag) else 0.0
    name = DAMPING_PARAMETERS[chosen.model][0]
    value, value_se = chosen.params.get(name, math.nan), chosen.se.get(name, math.nan)
    rate_rel_se = abs(value_se / value) if value and math.isfinite(value_se) else 0.0
    found: list[float] = []
    errors: list[float] = []
    first: list[FloatArray] = []
    curves: list[tuple[FloatArray, FloatArray, FloatArray]] = []
    for s, g in zip(data.squeezes, grids, strict=True):
        t = np.asarray(g.dt_s * np.arange(g.force_n.shape[0]), dtype=np.float64)
        stop = phase_slice(t, g.force_n, "loading", window_s=data.window_samples * g.dt_s).stop
        sel = s.ends < max(int(stop), 1)
        if not np.any(sel):
            continue
        x = s.mean_compression()
        rate = chosen.rate_window_force(s)
        curvature = chosen.window_prediction(s) - rate
        curvature -= chosen.params["preload_n"] + elastic_force(chosen.model, chosen.params, x)
        y = s.mean_force(lag) - rate - curvature
        order = np.argsort(x[sel], kind="stable")
        curves.append((x[sel][order], y[sel][order], rate[sel][order]))
        resid = (s.mean_force(lag) - chosen.window_prediction(s))[sel]
        first.append(resid[:CONTACT_WINDOWS])
    if not curves:
        return math.nan, math.nan, math.nan
    contact = contact_compression(chosen)
    off = float(np.median(np.abs(np.concatenate(first))))
    f0_se = chosen.se.get("preload_n", math.nan)
    f0 = abs(chosen.params["preload_n"])
    significant = math.isfinite(f0_se) and f0 > max(2.0 * f0_se, CONTACT_PRELOAD_FRAC * force_n)
    if not (math.isfinite(contact) and significant and off <= CONTACT_FIT_FRAC * force_n):
        contact = 0.0
    for xs, ys, rs in curves:
        d, j = _crossing(xs, ys, force_n, contact)
        if math.isfinite(d) and d > contact:
            found.append(d - contact)
            errors.append(_crossing_se(xs, ys, rs, max(j, 0), rate_rel_se))
    if not found:
        return math.nan, math.nan, contact
    d_all, e_all = np.asarray(found), np.asarray(errors)
    own = float(np.sqrt(np.mean(e_all**2)) / math.sqrt(d_all.size))
    spread = float(np.std(d_all, ddof=1) / math.sqrt(d_all.size)) if d_all.size > 1 else 0.0
    return float(np.median(d_all)), max(own, spread) if math.isfinite(own) else spread, contact


def _secant_residual(
    chosen: MaterialFit, data: FitData, force_n: float, d_op: float | None = None
) -> float:
    """How far the chosen law misses the recording where D is stated: the median window residual
    (measured mean force − the law's) over the windows whose mean compression is within
    :data:`SECANT_BAND` of ``d_op`` (the recording's compression at ``force_n``; None: the law's,
    above its preload), as a fraction of ``force_n``; NaN when no window is there (the law is
    extrapolated, nothing to compare)."""
    if d_op is None:
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
    name = DAMPING_PARAMETERS[chosen.model][0]
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
    lag_estimated: bool = False,
) -> ObjectFit:
    """Fit one object's squeezes (module docstring).

    Args:
        squeezes: the object's squeezes (same ``object_id``).
        model: ``kv``, ``hc``, ``sls``, ``exp`` or ``auto`` (all four, chosen by
            :func:`deformctl.characterize.materials.choose`).
        window_s: the averaging window, s (the Savitzky–Golay window the log's rate implies).
        fit_preload: fit a preload ``F0``.
        lag_s: the lag of the force behind the compression, s; None fits it.
        at_force_n: the operating force for D, N; None: F_w from ``weight_n`` and
            ``friction_mu`` when both are known, else the median loading force.
        weight_n, friction_mu: the object's weight and friction (from the log).
        lag_estimated: the force was shifted by a lag estimated from the recording
            (``measure --lag-s auto``): λ is withheld. The estimate is the latency less λ/D
            (:mod:`deformctl.measure.defects`), so the shift leaves the ramps saying λ ≈ D ×
            the estimate's error whatever λ is, and the lag left over is λ/D, which only the
            speed's corners tell from λ (``python -m bench.check_lag_removed``).

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
        g, wl_i = _grid(cut, window_s, rupture)
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
    d_stated, d_stated_se, contact = stated_compression(chosen, data, grids, f_op)
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
    law_d = secant(chosen.params)
    determined = not lag_estimated and _damping_determined(lam, lam_se, law_d, chosen.params, data)
    if identifiable and not lam_held and not determined:
        identifiable, lam, lam_se = False, math.nan, math.nan
    law_se = math.nan if PARAMETERS[chosen.model][0] in held else chosen.derived_se(secant)
    # a damping held at its bound 0 could not take the recording's rate-dependent force out of
    # the loading (a lag read as negative damping): the loading's secant would carry it
    from_recording = math.isfinite(d_stated) and d_stated > 0 and not lam_held
    d_value = f_op / d_stated if from_recording else law_d
    d_se = d_value * d_stated_se / d_stated if from_recording else law_se
    d_all = np.concatenate([s.compression_m for s in data.squeezes])
    f_all = np.concatenate([g.force_n for g in grids])
    rates = _sample_rates(data, grids)
    return ObjectFit(
        fits=fits,
        chosen=chosen,
        data=data,
        grids=tuple(grids),
        deformability_n_per_m=d_value,
        deformability_se_n_per_m=d_se,
        law_deformability_n_per_m=law_d,
        deformability_source="recording" if from_recording else "law",
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
        secant_residual_frac=_secant_residual(
            chosen,
            data,
            f_op if from_recording else above(chosen.params),
            d_stated + contact if from_recording else None,
        ),
        loading_share_below_operating=(
            float(np.mean(loading_force <= f_op)) if loading_force.size else math.nan
        ),
    )
