"""The material fit: one law (kv, hc, sls, exp) fitted to an object's squeezes; ``auto``'s choice.

Data. Each squeeze is on a uniform grid with its raw compression ``d`` and force ``f``. The fit
compares, over windows of :attr:`FitData.window_samples` samples that start every
``window/4`` samples and tile the squeeze to its last sample, the mean measured force with the
mean of the law (:func:`deformctl.characterize.laws.window_design`). The window means are exact
integrals of the law, so no sample is trimmed at either end and no derivative is taken. Windows
whose compression never reaches :data:`MIN_COMPRESSION_FRAC` of the squeeze's peak (the palms
in free air before contact) are left out.

Parameters. Every law has a preload ``F0`` (free, or 0), two linear parameters and, for HC, SLS
and exp, a shape (``n``; ``τ``; ``B``); a lag ``L`` of the force behind the compression (the
recording's latency) is fitted in ``[0, L_max]`` or fixed. For a given shape and lag the linear
parameters are a bounded linear least-squares problem (stiffness and damping terms ≥ 0,
``scipy.optimize.lsq_linear``); the shape and lag are found on a grid and refined by Powell's
method on that profile, within their bounds (:data:`HC_EXPONENT_BOUNDS`, ``τ`` between one
window and ten times the recording (a shorter ``τ`` is a low-pass on a dashpot, not a
relaxation the windows can see), ``B d_ref`` up to :data:`EXP_STIFFENING_MAX`, ``L`` below
:data:`LAG_MAX_S`). A parameter left at its
bound is named in :attr:`MaterialFit.at_bound`.

Errors and evidence. Standard errors are Newey–West (Bartlett weights, bandwidth one window,
within each squeeze) over the free parameters, from the residuals' Jacobian (the linear columns
exactly, shape and lag by central differences). The windows overlap, so the evidence counts
independent windows, ``n_eff = samples / window``: with ``σ̂²`` the mean squared window
residual, ``AIC = n_eff ln σ̂² + 2p`` and ``BIC = n_eff ln σ̂² + p ln n_eff`` (``p`` counts the
law's parameters, the preload and the lag when fitted); ``n_eff`` is the same for every law.
``auto`` identifies before choosing (:func:`choose`): Kelvin–Voigt, unless a richer law that
nests it (HC ``n = 1``, SLS ``k2 = 0`` or ``τ`` at a bound, exp ``B = 0``) has its extra
parameters off their bounds, a stiffness above 0, and a BIC lower by :data:`BIC_MARGIN`
(measured in ``tests/characterize/test_materials.py`` and ``test_law_choice.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from deformctl.characterize.laws import (
    DAMPING_PARAMETERS,
    EXP_STIFFENING_MAX,
    EXTRA_PARAMETERS,
    HC_EXPONENT_BOUNDS,
    PARAMETERS,
    cumulative_mean_parts,
    to_physical,
    window_design,
    window_mean,
)
from deformctl.characterize.material_options import MODELS
from deformctl.errors import InputDataError
from deformctl.series import FloatArray
from deformctl.signals import quarter_window_length, savgol

#: Windows whose compression stays below this fraction of the squeeze's peak are not fitted.
MIN_COMPRESSION_FRAC = 0.02
#: Largest lag of the force behind the compression fitted, s (and at most a tenth of a squeeze).
#: Measured latencies of real rigs: 0.17 s (a force-controlled gripper's sensor and controller).
LAG_MAX_S = 0.3
#: Windows start every ``window // WINDOW_STRIDE_DIV`` samples.
WINDOW_STRIDE_DIV = 4
#: Grid of the HC exponent and of the SLS relaxation time before refining.
_GRID_N = 6
#: Grid of the lag before refining.
_GRID_LAG = 4
#: Step of the refinement's central differences, as a fraction of a bounded parameter's range.
_FD_UNIT = 1e-5
#: Relative step of the central differences of the shape and lag columns.
_FD_REL = 1e-4


@dataclass(frozen=True)
class FitSqueeze:
    """One squeeze ready for the window fit.

    Attributes:
        squeeze_index: its index in the log.
        dt_s: uniform grid interval, s.
        time_s: grid times from 0, s ``[n]``.
        force_n: force on the grid, N ``[n]``.
        compression_m: raw compression on the grid, m ``[n]``.
        starts, ends: window start and end sample indices ``[m]`` (windows in contact only).
        end_compression_m: the compression lightly smoothed (cubic Savitzky–Golay over a quarter
            window, one-sided at the ends), for the damping terms' end points, m ``[n]``.
    """

    squeeze_index: int
    dt_s: float
    time_s: FloatArray
    force_n: FloatArray
    compression_m: FloatArray
    starts: np.ndarray
    ends: np.ndarray
    end_compression_m: FloatArray

    @property
    def duration_s(self) -> float:
        """Length of the squeeze, s."""
        return float(self.time_s[-1] - self.time_s[0])

    def mean_force(self, lag_s: float = 0.0) -> FloatArray:
        """Window means of the measured force ``lag_s`` later than each window, N ``[m]``.

        The force answers the compression ``lag_s`` earlier, so the window ``[a, b]`` of the
        compression is compared with the force over ``[a + lag, b + lag]``: the running integral
        of the force, interpolated (smooth in the lag), and continued past the last sample with
        the mean force of the last few samples.
        """
        integral = cumulative_mean_parts(self.force_n, self.dt_s)
        if lag_s == 0.0:
            return window_mean(integral, self.starts, self.ends, self.dt_s)
        tail = float(np.mean(self.force_n[-5:]))
        t_end = float(self.time_s[-1])
        t = np.append(self.time_s, t_end + LAG_MAX_S + 1.0)
        c = np.append(integral, integral[-1] + tail * (LAG_MAX_S + 1.0))
        hi = np.interp(self.time_s[self.ends] + lag_s, t, c)
        lo = np.interp(self.time_s[self.starts] + lag_s, t, c)
        return np.asarray((hi - lo) / ((self.ends - self.starts) * self.dt_s), dtype=np.float64)

    def mean_compression(self) -> FloatArray:
        """Window means of the compression, m ``[m]``."""
        return window_mean(
            cumulative_mean_parts(self.compression_m, self.dt_s), self.starts, self.ends, self.dt_s
        )

    def mean_rate(self) -> FloatArray:
        """Window means of the compression rate, m/s ``[m]`` (end-point differences)."""
        d = self.end_compression_m
        return np.asarray(
            (d[self.ends] - d[self.starts]) / ((self.ends - self.starts) * self.dt_s),
            dtype=np.float64,
        )

    def mean_time(self) -> FloatArray:
        """Window centres, s ``[m]``."""
        return np.asarray(0.5 * (self.time_s[self.starts] + self.time_s[self.ends]))


def windows(n: int, window_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Start and end indices of windows of ``window_samples`` intervals tiling ``[0, n − 1]``.

    They start every ``window // WINDOW_STRIDE_DIV`` samples; the last one ends at the last
    sample, so the samples at both ends are fitted.
    """
    w = min(window_samples, n - 1)
    stride = max(1, w // WINDOW_STRIDE_DIV)
    starts = np.arange(0, n - w, stride)
    starts = np.unique(np.append(starts, n - 1 - w))
    return starts.astype(np.int64), (starts + w).astype(np.int64)


def end_smoothed(compression_m: FloatArray, window: int) -> FloatArray:
    """The compression for the damping terms' end points: a cubic Savitzky–Golay fit over a
    quarter window (at least 5 samples), one-sided at the ends (``mode="interp"``)."""
    n = compression_m.shape[0]
    length = quarter_window_length(window)
    if n < length:
        return compression_m
    return savgol(compression_m, length, 3)


def fit_squeeze(
    squeeze_index: int, dt_s: float, force_n: FloatArray, compression_m: FloatArray, window: int
) -> FitSqueeze:
    """A squeeze on its uniform grid with its contact windows (see the module docstring)."""
    n = force_n.shape[0]
    a, b = windows(n, window)
    peak = float(np.max(compression_m))
    running_max = np.maximum.accumulate(compression_m)
    contact = running_max[b] >= MIN_COMPRESSION_FRAC * peak
    return FitSqueeze(
        end_compression_m=end_smoothed(compression_m, window),
        squeeze_index=squeeze_index,
        dt_s=dt_s,
        time_s=dt_s * np.arange(n, dtype=np.float64),
        force_n=force_n,
        compression_m=compression_m,
        starts=a[contact],
        ends=b[contact],
    )


@dataclass(frozen=True)
class FitData:
    """An object's squeezes for the window fit.

    Attributes:
        squeezes: the squeezes.
        window_samples: the window, samples (the Savitzky–Golay window the log's rate implies).
        fit_preload: fit the preload ``F0`` (else 0).
        lag_s: the lag of the force behind the compression, s; None fits it.
        damping: fit the law's rate-dependent part (KV and HC ``λ``, SLS's Maxwell arm); False
            when it cannot be identified (a single speed): the law is then its spring alone.
    """

    squeezes: tuple[FitSqueeze, ...]
    window_samples: int
    fit_preload: bool
    lag_s: float | None = None
    damping: bool = True

    @property
    def reference_compression_m(self) -> float:
        """The largest compression, m (compressions are scaled by it in the fit)."""
        return max(float(np.max(s.compression_m)) for s in self.squeezes)

    @property
    def lag_max_s(self) -> float:
        """The largest lag fitted, s."""
        shortest = min(s.duration_s for s in self.squeezes)
        return min(LAG_MAX_S, 0.1 * shortest)

    @property
    def n_windows(self) -> int:
        """Windows fitted."""
        return sum(int(s.starts.shape[0]) for s in self.squeezes)

    @property
    def n_eff(self) -> float:
        """Independent windows: samples covered by the windows over the window length."""
        total = 0.0
        for s in self.squeezes:
            if s.starts.size:
                total += (int(s.ends[-1]) - int(s.starts[0]) + 1) / self.window_samples
        return total

    def target(self, lag_s: float = 0.0) -> FloatArray:
        """Window means of the force ``lag_s`` later, all squeezes, N ``[m]``."""
        return np.concatenate([s.mean_force(lag_s) for s in self.squeezes])


@dataclass(frozen=True)
class MaterialFit:
    """One law fitted to an object's squeezes.

    Attributes:
        model: ``kv``, ``hc`` or ``sls``.
        params: SI parameters (:data:`deformctl.characterize.laws.PARAMETERS`, plus
            ``preload_n`` and ``lag_s``).
        se: their standard errors (NaN for a parameter fixed or at its bound).
        at_bound: the physical parameters left at a bound.
        rss: sum of squared window residuals, N².
        n_windows: windows fitted.
        n_eff: independent windows.
        n_params: parameters counted by the evidence.
        r2: R² of the window means.
        residual_rms_n: per squeeze (in input order), RMS window residual, N.
        aic, bic: the information criteria (module docstring).
        covariance: covariance of ``free`` (internal parameters, see :meth:`derived_se`).
        free: names of the free internal parameters.
        internal: internal parameter values (scaled design; see
            :func:`deformctl.characterize.laws.to_physical`).
        reference_compression_m: the compression scale of the internal parameters, m.
    """

    model: str
    params: dict[str, float]
    se: dict[str, float]
    at_bound: tuple[str, ...]
    rss: float
    n_windows: int
    n_eff: float
    n_params: int
    r2: float
    residual_rms_n: tuple[float, ...]
    aic: float
    bic: float
    covariance: FloatArray = field(repr=False)
    free: tuple[str, ...] = ()
    internal: dict[str, float] = field(default_factory=dict, repr=False)
    reference_compression_m: float = 1.0

    def _window_columns(self, squeeze: FitSqueeze) -> FloatArray:
        shape = self.internal.get("shape", 1.0)
        shape_value = math.exp(shape) if self.model == "sls" else shape
        d_ref = self.reference_compression_m
        return window_design(
            self.model,
            squeeze.compression_m / d_ref,
            squeeze.end_compression_m / d_ref,
            squeeze.dt_s,
            squeeze.starts,
            squeeze.ends,
            shape_value,
        )

    def rate_window_force(self, squeeze: FitSqueeze) -> FloatArray:
        """The law's rate-dependent force over the windows of one squeeze, N ``[m]`` (0 when the
        damping was not fitted)."""
        b = self.internal["b"]
        if not math.isfinite(b) or b == 0.0 or not math.isfinite(self.params["preload_n"]):
            return np.zeros(squeeze.starts.shape[0])
        return np.asarray(b * self._window_columns(squeeze)[:, 1], dtype=np.float64)

    def window_prediction(self, squeeze: FitSqueeze) -> FloatArray:
        """The law's mean force over the windows of one squeeze, N ``[m]`` (compare with
        ``squeeze.mean_force(lag)``)."""
        cols = self._window_columns(squeeze)
        b = self.internal["b"] if math.isfinite(self.internal["b"]) else 0.0
        return np.asarray(
            self.internal["f0"] + self.internal["a"] * cols[:, 0] + b * cols[:, 1],
            dtype=np.float64,
        )

    def derived_se(self, func: Callable[[dict[str, float]], float]) -> float:
        """Standard error of a function of the SI parameters (delta method over the free ones)."""
        if not self.free or not np.all(np.isfinite(self.covariance)):
            return math.nan
        base = func(self.params)
        if not math.isfinite(base):
            return math.nan
        grad = np.zeros(len(self.free))
        for i, name in enumerate(self.free):
            h = _FD_REL * max(abs(self.internal[name]), 1e-12)
            up = dict(self.internal)
            up[name] += h
            dn = dict(self.internal)
            dn[name] -= h
            d_ref = self.reference_compression_m
            grad[i] = (
                func(_physical_full(self.model, up, d_ref))
                - func(_physical_full(self.model, dn, d_ref))
            ) / (2 * h)
        var = float(grad @ self.covariance @ grad)
        return math.sqrt(var) if var >= 0 else math.nan


def _physical(model: str, internal: dict[str, float], d_ref: float) -> dict[str, float]:
    beta = np.array([internal["f0"], internal["a"], internal["b"]])
    shape = internal.get("shape", 1.0)
    out = to_physical(model, beta, shape, d_ref)
    out["lag_s"] = internal.get("lag", 0.0)
    return out


class _Problem:
    """One law on one object's windows: the design for a shape, the target for a lag, and the
    bounded solve of the linear parameters."""

    def __init__(self, model: str, data: FitData) -> None:
        self.model = model
        self.data = data
        self.d_ref = data.reference_compression_m
        self.scaled = [s.compression_m / self.d_ref for s in data.squeezes]
        self.scaled_end = [s.end_compression_m / self.d_ref for s in data.squeezes]
        self.designs: dict[float, FloatArray] = {}
        self.targets: dict[float, FloatArray] = {}
        self.shape_bounds: tuple[float, float] | None = None
        if model == "hc":
            self.shape_bounds = HC_EXPONENT_BOUNDS
        elif model == "exp":
            self.shape_bounds = (0.0, EXP_STIFFENING_MAX)
        elif model == "sls" and data.damping:
            dt = min(s.dt_s for s in data.squeezes)
            total = sum(s.duration_s for s in data.squeezes)
            self.shape_bounds = (math.log(data.window_samples * dt), math.log(10.0 * total))
        self.lag_bounds = None if data.lag_s is not None else (0.0, data.lag_max_s)

    def target(self, lag: float) -> FloatArray:
        """Window means of the force ``lag`` after each window, ``[m]``."""
        if lag not in self.targets:
            if len(self.targets) > 256:
                self.targets.clear()
            self.targets[lag] = self.data.target(lag)
        return self.targets[lag]

    def design(self, shape: float) -> FloatArray:
        """``[m, 3]``: the preload column and the law's two columns for a shape."""
        if shape not in self.designs:
            if len(self.designs) > 256:
                self.designs.clear()
            shape_value = math.exp(shape) if self.model == "sls" else shape
            if self.model == "sls" and not self.data.damping:
                shape_value = 1.0  # the arm is not fitted
            blocks = []
            for s, d, d_end in zip(self.data.squeezes, self.scaled, self.scaled_end, strict=True):
                cols = window_design(self.model, d, d_end, s.dt_s, s.starts, s.ends, shape_value)
                blocks.append(np.column_stack([np.ones(cols.shape[0]), cols]))
            self.designs[shape] = np.vstack(blocks)
        return self.designs[shape]

    def solve(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, float]:
        """Bounded least squares of the linear parameters; ``(beta [3], rss)``.

        The stiffness and damping terms are ≥ 0 and the preload is free: with two bounded
        variables the exact solution is the best feasible one of the four unconstrained fits
        with each subset of them held at 0 (normal equations of the unit-RMS columns).
        """
        raw = x.T @ x
        scale = np.sqrt(np.diag(raw))
        scale = np.where(scale > 0, scale, 1.0)
        gram = raw / np.outer(scale, scale)
        rhs = (x.T @ y) / scale
        first = 0 if self.data.fit_preload else 1
        best: tuple[float, FloatArray] | None = None
        subsets = ((1, 2), (1,), (2,), ()) if self.data.damping else ((1,), ())
        for keep in subsets:
            idx = list(range(first, 1)) + list(keep)
            coef = np.zeros(3)
            if idx:
                sub = gram[np.ix_(idx, idx)]
                try:
                    coef[idx] = np.linalg.solve(sub, rhs[idx])
                except np.linalg.LinAlgError:
                    coef[idx] = np.linalg.lstsq(sub, rhs[idx], rcond=None)[0]
            if coef[1] < 0 or coef[2] < 0:
                continue
            gain = 2.0 * float(coef @ rhs) - float(coef @ gram @ coef)
            if best is None or gain > best[0]:
                best = (gain, coef)
            if keep == subsets[0]:
                break  # the unconstrained fit is feasible: it is the optimum
        assert best is not None  # the empty subset is always feasible
        beta = np.asarray(best[1] / scale, dtype=np.float64)
        resid = y - x @ beta
        return beta, float(resid @ resid)

    def residuals(self, shape: float, lag: float) -> FloatArray:
        """Window residuals with the linear parameters solved, ``[m]``."""
        x, y = self.design(shape), self.target(lag)
        beta, _ = self.solve(x, y)
        return np.asarray(y - x @ beta, dtype=np.float64)

    def profile(self, shape: float, lag: float) -> float:
        return self.solve(self.design(shape), self.target(lag))[1]


def _grid(bounds: tuple[float, float] | None, count: int, fixed: float) -> np.ndarray:
    if bounds is None:
        return np.array([fixed])
    return np.linspace(bounds[0], bounds[1], count)


def _refine(problem: _Problem, shape0: float, lag0: float) -> tuple[float, float]:
    """Gauss–Newton (trust region, ``scipy.optimize.least_squares``) on the profile residuals
    of the shape and lag from the best grid point, within their bounds."""
    from scipy.optimize import least_squares

    sb, lb = problem.shape_bounds, problem.lag_bounds
    names = [n for n, b in (("shape", sb), ("lag", lb)) if b is not None]
    if not names:
        return shape0, lag0
    bounds = [sb if n == "shape" else lb for n in names]
    x0 = np.array([shape0 if n == "shape" else lag0 for n in names])

    def unpack(x: FloatArray) -> tuple[float, float]:
        values = dict(zip(names, (float(v) for v in x), strict=True))
        return values.get("shape", shape0), values.get("lag", lag0)

    def residuals(x: FloatArray) -> FloatArray:
        return problem.residuals(*unpack(x))

    lo = np.array([b[0] for b in bounds if b is not None])
    hi = np.array([b[1] for b in bounds if b is not None])
    span = hi - lo

    def scaled(u: FloatArray) -> FloatArray:  # the unit box → the bounds
        return np.asarray(lo + span * u, dtype=np.float64)

    def jac(u: FloatArray) -> FloatArray:  # central differences of absolute step in the unit box
        cols = []
        for i in range(u.shape[0]):
            h = _FD_UNIT
            up, dn = u.copy(), u.copy()
            up[i] = min(u[i] + h, 1.0)
            dn[i] = max(u[i] - h, 0.0)
            cols.append((residuals(scaled(up)) - residuals(scaled(dn))) / (up[i] - dn[i]))
        return np.column_stack(cols)

    res = least_squares(
        lambda u: residuals(scaled(u)),
        np.clip((x0 - lo) / span, 0.0, 1.0),
        jac=jac,
        bounds=(0.0, 1.0),
        method="trf",
        xtol=1e-10,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=50,
    )
    res.x = scaled(res.x)
    best = unpack(res.x)
    if problem.profile(*best) <= problem.profile(shape0, lag0):
        return best
    return shape0, lag0


def _hac_meat(u: FloatArray, lags: int) -> FloatArray:
    meat = u.T @ u
    for lag in range(1, min(lags, u.shape[0] - 1) + 1):
        g = u[lag:].T @ u[:-lag]
        meat += (1.0 - lag / (lags + 1)) * (g + g.T)
    return np.asarray(meat, dtype=np.float64)


def fit_material(model: str, data: FitData) -> MaterialFit:
    """Fit one law to an object's squeezes (module docstring).

    Raises:
        InputDataError: fewer windows than parameters.
    """
    if model not in MODELS:
        raise ValueError(f"unknown model {model!r}")
    problem = _Problem(model, data)
    n_lin = (3 if data.fit_preload else 2) - (not data.damping)
    n_params = n_lin + (problem.shape_bounds is not None) + (problem.lag_bounds is not None)
    if data.n_windows < n_params + 2:
        raise InputDataError(
            f"only {data.n_windows} windows of {data.window_samples} samples to fit {n_params} "
            "parameters"
        )
    fixed_lag = data.lag_s if data.lag_s is not None else 0.0
    shapes = _grid(problem.shape_bounds, _GRID_N, 1.0)
    lag_count = _GRID_LAG
    if problem.lag_bounds is not None:  # at least every half window: the profile's basin width
        window_s = data.window_samples * min(s.dt_s for s in data.squeezes)
        lag_count = max(_GRID_LAG, math.ceil(problem.lag_bounds[1] / (0.5 * window_s)) + 1)
    lags = _grid(problem.lag_bounds, lag_count, fixed_lag)
    best = min(((problem.profile(s, g), s, g) for s in shapes for g in lags), key=lambda t: t[0])
    shape, lag = _refine(problem, best[1], best[2])
    x, y = problem.design(shape), problem.target(lag)
    beta, rss = problem.solve(x, y)
    resid = y - x @ beta

    internal = {"f0": float(beta[0]), "a": float(beta[1]), "b": float(beta[2])}
    if model != "kv":
        internal["shape"] = shape
    internal["lag"] = lag
    # which internal parameters are free (not fixed, not at a bound)
    tol = 1e-6
    at_bound_internal: list[str] = []
    if beta[1] <= tol * max(abs(beta).max(), 1e-300):
        at_bound_internal.append("a")
    if data.damping and beta[2] <= tol * max(abs(beta).max(), 1e-300):
        at_bound_internal.append("b")
    if problem.shape_bounds is not None:
        lo, hi = problem.shape_bounds
        if min(shape - lo, hi - shape) <= 1e-4 * (hi - lo):
            at_bound_internal.append("shape")
    free = [p for p in ("f0", "a", "b") if not (p == "f0" and not data.fit_preload)]
    free = [p for p in free if p not in at_bound_internal and (p != "b" or data.damping)]
    if problem.shape_bounds is not None and "shape" not in at_bound_internal:
        free.append("shape")
    if problem.lag_bounds is not None and lag > 1e-6 and lag < problem.lag_bounds[1] - 1e-6:
        free.append("lag")

    cov = _covariance(problem, x, beta, shape, lag, resid, free)
    params = _physical_full(model, internal, problem.d_ref)
    se = _parameter_se(model, params, internal, free, cov, problem.d_ref)
    if not data.damping:  # not fitted: no value
        for name in DAMPING_PARAMETERS[model]:
            params[name] = se[name] = math.nan
    names = {"a": PARAMETERS[model][0], "b": PARAMETERS[model][-1]}
    if model == "hc":
        names["shape"] = "exponent"
    elif model == "exp":
        names["shape"] = "stiffening_per_m"
    elif model == "sls":
        names["b"] = "arm_stiffness_n_per_m"
        names["shape"] = "relaxation_time_s"
    at_bound = tuple(names[p] for p in at_bound_internal)

    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - rss / ss_tot if ss_tot > 0 else math.nan
    rms: list[float] = []
    start = 0
    for s in data.squeezes:
        m = int(s.starts.shape[0])
        r = resid[start : start + m]
        rms.append(float(np.sqrt(np.mean(r * r))) if m else math.nan)
        start += m
    # the same evidence for every law: n_eff must not grow with the law's parameters
    n_eff = max(data.n_eff, 2.0)
    sigma2 = max(rss / max(data.n_windows, 1), 1e-300)
    log_term = n_eff * math.log(sigma2)
    return MaterialFit(
        model=model,
        params=params,
        se=se,
        at_bound=at_bound,
        rss=rss,
        n_windows=data.n_windows,
        n_eff=data.n_eff,
        n_params=n_params,
        r2=r2,
        residual_rms_n=tuple(rms),
        aic=log_term + 2.0 * n_params,
        bic=log_term + n_params * math.log(n_eff),
        covariance=cov,
        free=tuple(free),
        internal=internal,
        reference_compression_m=problem.d_ref,
    )


def _columns(
    problem: _Problem, x: FloatArray, beta: FloatArray, shape: float, lag: float, free: list[str]
) -> FloatArray:
    """−∂(residual)/∂(free internal parameter), ``[m, p]`` (the lag moves the target)."""
    cols = []
    for name in free:
        if name == "f0":
            cols.append(x[:, 0])
        elif name == "a":
            cols.append(x[:, 1])
        elif name == "b":
            cols.append(x[:, 2])
        elif name == "shape":
            h = _FD_REL * max(abs(shape), 1e-3)
            up, dn = problem.design(shape + h), problem.design(shape - h)
            cols.append((up @ beta - dn @ beta) / (2.0 * h))
        else:
            h = _FD_REL * max(abs(lag), 1e-3)
            hi, lo = lag + h, max(lag - h, 0.0)
            cols.append(-(problem.target(hi) - problem.target(lo)) / (hi - lo))
    return np.column_stack(cols) if cols else np.zeros((x.shape[0], 0))


def _covariance(
    problem: _Problem,
    x: FloatArray,
    beta: FloatArray,
    shape: float,
    lag: float,
    resid: FloatArray,
    free: list[str],
) -> FloatArray:
    """Newey–West covariance of the free internal parameters (module docstring)."""
    if not free:
        return np.zeros((0, 0))
    jac = _columns(problem, x, beta, shape, lag, free)
    scale = np.sqrt(np.mean(jac * jac, axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    js = jac / scale
    p = js.shape[1]
    meat = np.zeros((p, p))
    data = problem.data
    stride = max(1, min(data.window_samples, 10**9) // WINDOW_STRIDE_DIV)
    lags = 2 * math.ceil(data.window_samples / stride)
    start = 0
    for s in data.squeezes:
        m = int(s.starts.shape[0])
        meat += _hac_meat(js[start : start + m] * resid[start : start + m, None], lags)
        start += m
    m_all = js.shape[0]
    bread = np.linalg.pinv(js.T @ js)
    cov = bread @ meat @ bread * (m_all / max(m_all - p, 1))
    return np.asarray(cov / np.outer(scale, scale), dtype=np.float64)


def _parameter_se(
    model: str,
    params: dict[str, float],
    internal: dict[str, float],
    free: list[str],
    cov: FloatArray,
    d_ref: float,
) -> dict[str, float]:
    """Standard errors of the SI parameters (delta method; NaN for the fixed ones)."""
    out = dict.fromkeys(params, math.nan)
    if not free:
        return out
    for name in params:
        grad = np.zeros(len(free))
        base = params[name]
        for i, p in enumerate(free):
            h = _FD_REL * max(abs(internal[p]), 1e-12)
            up = dict(internal)
            up[p] += h
            dn = dict(internal)
            dn[p] -= h
            fu = _physical_full(model, up, d_ref)[name]
            fd = _physical_full(model, dn, d_ref)[name]
            grad[i] = (fu - fd) / (2 * h)
        if not np.any(grad) or not math.isfinite(base):
            continue
        var = float(grad @ cov @ grad)
        out[name] = math.sqrt(var) if var >= 0 else math.nan
    return out


def _physical_full(model: str, internal: dict[str, float], d_ref: float) -> dict[str, float]:
    """:func:`_physical` with SLS's shape as ``log τ``."""
    if model == "sls":
        inner = dict(internal)
        inner["shape"] = math.exp(internal["shape"])
        return _physical(model, inner, d_ref)
    return _physical(model, internal, d_ref)


def degenerate(fit: MaterialFit) -> bool:
    """A fit no grip can use: its stiffness (KV's ``D``, HC's ``k``, SLS's ``k1``, exp's ``k0``)
    at its lower bound 0, or not a positive number."""
    name = PARAMETERS[fit.model][0]
    value = fit.params.get(name, math.nan)
    return name in fit.at_bound or not (math.isfinite(value) and value > 0)


def extra_unidentified(fit: MaterialFit) -> tuple[str, ...]:
    """The law's parameters beyond Kelvin–Voigt's
    (:data:`deformctl.characterize.laws.EXTRA_PARAMETERS`) that the data do not identify: at a
    bound (HC's ``n`` at 1 or 3, SLS's arm at 0 or ``τ`` at a bound, exp's ``B`` at 0 or its
    largest value) or not fitted (SLS's arm without damping)."""
    return tuple(
        p
        for p in EXTRA_PARAMETERS[fit.model]
        if p in fit.at_bound or not math.isfinite(fit.params.get(p, math.nan))
    )


#: ``auto`` chooses a law richer than Kelvin–Voigt only when its BIC is lower by at least this:
#: a Bayes factor of e⁵ ≈ 150 ("very strong" on Kass and Raftery's scale; for one extra parameter
#: a likelihood-ratio test at p < 0.002). The confusion matrices it gives are in
#: docs/explanation/materials.md (tests/characterize/test_law_choice.py, test_materials.py).
BIC_MARGIN = 10.0


def choose(fits: Sequence[MaterialFit], margin: float = BIC_MARGIN) -> MaterialFit:
    """The law ``auto`` reports: identify before choosing.

    Kelvin–Voigt is the default. A richer law (HC, SLS, exp; each nests Kelvin–Voigt: ``n = 1``
    up to its damping's form, ``k2 = 0`` or ``τ → ∞``, ``B = 0``) replaces it only when

    * it is not degenerate (:func:`degenerate`: its stiffness above 0),
    * its extra parameters are identified (:func:`extra_unidentified`: none at a bound, none left
      unfitted; a parameter at its bound means the simpler law), and
    * its BIC is lower than Kelvin–Voigt's by at least ``margin`` (:data:`BIC_MARGIN`);

    among those, the smallest BIC. A degenerate Kelvin–Voigt fit is replaced by the best
    non-degenerate law without a margin; when every law is degenerate, Kelvin–Voigt is reported
    (its stiffness named in ``at_bound``, so the row is flagged). One fit: that fit.
    """
    if len(fits) == 1:
        return fits[0]
    order: dict[str, int] = {m: i for i, m in enumerate(MODELS)}

    def key(f: MaterialFit) -> tuple[float, int]:
        return (f.bic, order[f.model])

    base = next((f for f in fits if f.model == "kv"), None)
    richer = [
        f for f in fits if f.model != "kv" and not degenerate(f) and not extra_unidentified(f)
    ]
    if base is not None and not degenerate(base):
        decisive = [f for f in richer if base.bic - f.bic >= margin]
        return min(decisive, key=key) if decisive else base
    if richer:
        return min(richer, key=key)
    sound = [f for f in fits if not degenerate(f)]
    if sound:
        return min(sound, key=key)
    return base if base is not None else min(fits, key=key)
