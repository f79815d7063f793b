"""Material laws of a squeeze: Kelvin–Voigt, Hunt–Crossley, the standard linear solid and an
exponentially stiffening solid.

Each law gives the force ``f`` between the palms from the compression history ``d(t)`` (SI:
N, m, s). Every law carries a preload ``F0`` (a contact preload or a force-sensor offset at
``d = 0``), fitted or fixed at 0:

* ``kv`` (Kelvin–Voigt, the paper's model): ``f = F0 + D d + λ ḋ``.
* ``hc`` (Hunt–Crossley): ``f = F0 + k dⁿ + λ dⁿ ḋ`` with ``n`` in :data:`HC_EXPONENT_BOUNDS`;
  ``n = 1`` is a spring whose damping grows with the compression, ``n > 1`` stiffens.
* ``sls`` (standard linear solid, Zener): a spring ``k1`` in parallel with a Maxwell arm, a
  spring ``k2`` in series with a dashpot ``c = k2 τ``: ``f = F0 + k1 d + σ`` with
  ``σ̇ = k2 ḋ − σ/τ``. Three parameters ``k1, k2, τ``; it relaxes at constant compression
  (``σ`` decays with time constant ``τ``) and creeps under constant force.
* ``exp`` (exponential stiffening, Fung's law of soft tissue):
  ``f = F0 + k0 (e^{B d} − 1)/B + λ e^{B d} ḋ``: ``k0`` is the stiffness at contact, the tangent
  stiffness grows as ``k0 e^{B d}`` and the damping with it; ``B = 0`` is Kelvin–Voigt exactly.
  ``B`` in ``[0, EXP_STIFFENING_MAX / d_ref]``.

**Fitted in integral form.** The fit (:mod:`deformctl.characterize.materials`) never
differentiates the compression: it compares the mean force over short windows with the mean of
each law over the same windows, which needs only integrals of ``d``. The damping terms are exact
derivatives (``λ ḋ = d/dt(λ d)``, ``λ dⁿ ḋ = d/dt(λ dⁿ⁺¹/(n+1))``,
``λ e^{Bd} ḋ = d/dt(λ (e^{Bd} − 1)/B)``), so their window means are
end-point differences (of the compression lightly smoothed, one-sided at the squeeze's ends, so
that position noise is not divided by the window undamped), and the Maxwell arm is an exact
recursion on the compression's increments (exact for a compression linear between samples).
:func:`window_design` builds these window means; no filter edge, corner or sharp reversal
biases them.

**What a grip uses.** :func:`elastic_force` is a law's rate-free force–compression curve (KV and
HC, exp: the spring; SLS: the relaxed spring ``k1``, what a held grip settles to);
:func:`secant_stiffness` is ``(F − F0)/d`` on that curve at a force ``F`` (for KV and SLS the
stiffness itself); :func:`equivalent_damping` is ``∂f/∂ḋ`` at a compression (KV ``λ``; HC
``λ dⁿ``; exp ``λ e^{Bd}``; SLS ``k2 τ``, the Maxwell arm's damping at rates slow against
``1/τ``).

Internal parameters are scaled for the optimiser: compressions are divided by a reference
compression ``d_ref`` (the largest compression fitted), so that HC's ``k`` and ``λ`` do not
change by decades when ``n`` moves; :func:`to_physical` converts to SI.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from deformctl.errors import UsageError
from deformctl.quantities import STIFFNESS_EXPONENT
from deformctl.series import FloatArray

#: Hunt–Crossley exponent bounds (1: linear spring; 3: the stiffest law a soft object shows).
#: The simulator's catalog column ``material_stiffness_exponent`` has the same rule.
HC_EXPONENT_BOUNDS = (STIFFNESS_EXPONENT.low, STIFFNESS_EXPONENT.high)
#: Largest stiffening of the exponential law over the fitted compression, ``B · d_ref`` (the
#: tangent stiffness grows by ``e^{B d_ref}`` from contact to the largest compression: up to e^30;
#: the shared silicone phantoms need 4–7). Its lower bound 0 is Kelvin–Voigt.
EXP_STIFFENING_MAX = 30.0

#: Each law's parameters (SI), in the order :func:`to_physical` returns them, after ``preload_n``.
PARAMETERS: dict[str, tuple[str, ...]] = {
    "kv": ("stiffness_n_per_m", "damping_ns_per_m"),
    "hc": ("stiffness_n_per_m_pow_n", "exponent", "damping_ns_per_m_pow_n_plus_1"),
    "sls": ("stiffness_n_per_m", "arm_stiffness_n_per_m", "relaxation_time_s"),
    "exp": ("stiffness_n_per_m", "stiffening_per_m", "damping_ns_per_m"),
}
#: The law's parameters beyond Kelvin–Voigt's (at their simple value the law is Kelvin–Voigt or a
#: spring: HC ``n = 1``, SLS ``k2 = 0`` or ``τ`` at a bound, exp ``B = 0``).
EXTRA_PARAMETERS: dict[str, tuple[str, ...]] = {
    "kv": (),
    "hc": ("exponent",),
    "sls": ("arm_stiffness_n_per_m", "relaxation_time_s"),
    "exp": ("stiffening_per_m",),
}
#: The parameters that describe damping (not identifiable from a single-speed test).
DAMPING_PARAMETERS: dict[str, tuple[str, ...]] = {
    "kv": ("damping_ns_per_m",),
    "hc": ("damping_ns_per_m_pow_n_plus_1",),
    "sls": ("arm_stiffness_n_per_m", "relaxation_time_s"),
    "exp": ("damping_ns_per_m",),
}


def _expm1_over(b: float, x: FloatArray) -> FloatArray:
    """``(e^{b x} − 1)/b``, ``x`` at ``b = 0``."""
    if b == 0.0:
        return np.asarray(x, dtype=np.float64)
    return np.asarray(np.expm1(b * x) / b, dtype=np.float64)


def cumulative_mean_parts(x: FloatArray, dt_s: float) -> FloatArray:
    """Trapezoid running integral of ``x`` on a uniform grid, ``[n]`` (0 at the first sample)."""
    out = np.empty_like(x)
    out[0] = 0.0
    np.cumsum(0.5 * (x[1:] + x[:-1]) * dt_s, out=out[1:])
    return out


def window_mean(integral: FloatArray, a: np.ndarray, b: np.ndarray, dt_s: float) -> FloatArray:
    """Mean over each window ``[a, b]`` (sample indices) of the signal whose running integral is
    ``integral``."""
    return np.asarray((integral[b] - integral[a]) / ((b - a) * dt_s), dtype=np.float64)


def maxwell_strain(d: FloatArray, dt_s: float, tau_s: float) -> FloatArray:
    """The Maxwell arm's strain ``s`` (m), ``ṡ = ḋ − s/τ``, ``s = 0`` at the first sample.

    Exact for a compression linear between samples: ``s_i = e s_{i−1} + τ (1 − e) Δd_i / h``
    with ``e = exp(−h/τ)``: one first-order IIR pass, solved as the lower-bidiagonal system it is
    (``scipy.linalg``, already loaded by the fits; ``scipy.signal.lfilter`` would cost a command
    0.7 s of import; the two agree to 1e-15). The arm's force is ``σ = k2 s``.
    """
    from scipy.linalg import solve_banded

    if d.shape[0] == 0:
        return np.zeros(0)
    e = math.exp(-dt_s / tau_s)
    gain = tau_s * (1.0 - e) / dt_s
    inc = np.empty_like(d)
    inc[0] = 0.0
    inc[1:] = np.diff(d)
    bands = np.zeros((2, d.shape[0]))
    bands[0] = 1.0
    bands[1, :-1] = -e
    return np.asarray(solve_banded((1, 0), bands, gain * inc, check_finite=False), dtype=np.float64)


def window_design(
    model: str,
    d: FloatArray,
    d_end: FloatArray,
    dt_s: float,
    a: np.ndarray,
    b: np.ndarray,
    shape: float,
) -> FloatArray:
    """Window means of a law's terms (after the preload column), ``[m, 2]``.

    Args:
        model: ``kv``, ``hc``, ``sls`` or ``exp``.
        d: raw compression on a uniform grid, divided by the reference compression.
        d_end: the same compression lightly smoothed, for the damping terms' end points (an
            end-point difference of raw samples carries two samples' noise undivided).
        dt_s: grid interval, s.
        a, b: window start and end sample indices ``[m]``.
        shape: HC's exponent ``n``; SLS's relaxation time ``τ`` (s); exp's ``B`` (per unit of
            ``d``); ignored for KV.

    Returns:
        Columns ``[stiffness term, damping term]``: KV ``[mean d, Δd/T]``; HC
        ``[mean dⁿ, Δ(dⁿ⁺¹)/((n+1) T)]``; SLS ``[mean d, mean s]`` (Maxwell strain); exp
        ``[mean (e^{Bd} − 1)/B, Δ((e^{Bd} − 1)/B)/T]``.
    """
    if model == "kv":
        first = window_mean(cumulative_mean_parts(d, dt_s), a, b, dt_s)
        second = (d_end[b] - d_end[a]) / ((b - a) * dt_s)
    elif model == "hc":
        pw = np.maximum(d, 0.0) ** shape
        first = window_mean(cumulative_mean_parts(pw, dt_s), a, b, dt_s)
        g = np.maximum(d_end, 0.0) ** (shape + 1.0) / (shape + 1.0)
        second = (g[b] - g[a]) / ((b - a) * dt_s)
    elif model == "exp":
        first = window_mean(cumulative_mean_parts(_expm1_over(shape, d), dt_s), a, b, dt_s)
        g = _expm1_over(shape, d_end)
        second = (g[b] - g[a]) / ((b - a) * dt_s)
    elif model == "sls":
        first = window_mean(cumulative_mean_parts(d, dt_s), a, b, dt_s)
        s = maxwell_strain(d, dt_s, shape)
        second = window_mean(cumulative_mean_parts(s, dt_s), a, b, dt_s)
    else:
        raise UsageError(f"unknown model {model!r}")
    return np.column_stack([first, second])


def rate_force(
    model: str, params: Mapping[str, float], d: FloatArray, rate: FloatArray, dt_s: float
) -> FloatArray:
    """The rate-dependent part of a law's force per sample (SI), N ``[n]``.

    KV ``λ ḋ``, HC ``λ dⁿ ḋ``, exp ``λ e^{Bd} ḋ`` (from ``rate``, a smoothed ``ḋ``), SLS
    ``k2 s`` (the Maxwell arm, from ``d`` alone). NaN parameters count as 0.
    """

    def p(name: str) -> float:
        v = params[name]
        return 0.0 if not math.isfinite(v) else v

    if model == "kv":
        return p("damping_ns_per_m") * rate
    if model == "hc":
        dp = np.maximum(d, 0.0)
        return p("damping_ns_per_m_pow_n_plus_1") * dp ** params["exponent"] * rate
    if model == "exp":
        return p("damping_ns_per_m") * np.exp(params["stiffening_per_m"] * d) * rate
    tau = params["relaxation_time_s"]
    if not math.isfinite(tau) or tau <= 0:
        return np.zeros_like(d)
    return p("arm_stiffness_n_per_m") * maxwell_strain(d, dt_s, tau)


def elastic_force(model: str, params: Mapping[str, float], d: FloatArray) -> FloatArray:
    """The rate-free force–compression curve above the preload, N (``d`` in m)."""
    dp = np.maximum(np.asarray(d, dtype=np.float64), 0.0)
    if model == "hc":
        return params["stiffness_n_per_m_pow_n"] * dp ** params["exponent"]
    if model == "exp":
        return params["stiffness_n_per_m"] * _expm1_over(params["stiffening_per_m"], dp)
    return params["stiffness_n_per_m"] * dp


def compression_at_force(model: str, params: Mapping[str, float], force_n: float) -> float:
    """The compression (m) at which :func:`elastic_force` reaches ``force_n`` (above the preload).

    NaN when the force is not above 0 or the stiffness is 0.
    """
    k = params["stiffness_n_per_m_pow_n" if model == "hc" else "stiffness_n_per_m"]
    if not (force_n > 0 and k > 0):
        return math.nan
    if model == "exp":
        b = params["stiffening_per_m"]
        return float(math.log1p(b * force_n / k) / b) if b > 0 else force_n / k
    n = params["exponent"] if model == "hc" else 1.0
    return float((force_n / k) ** (1.0 / n))


def secant_stiffness(model: str, params: Mapping[str, float], force_n: float) -> float:
    """``F / d(F)`` on the elastic curve at a force ``F`` above the preload, N/m.

    KV and SLS: the (relaxed) stiffness, whatever the force. HC: ``k d(F)ⁿ⁻¹``; exp:
    ``F / d(F)``.
    """
    if model not in ("hc", "exp"):
        return float(params["stiffness_n_per_m"])
    d = compression_at_force(model, params, force_n)
    return force_n / d if d > 0 else math.nan


def equivalent_damping(model: str, params: Mapping[str, float], compression_m: float) -> float:
    """The damping a Kelvin–Voigt element would need at this compression, N·s/m.

    KV ``λ``; HC ``λ dⁿ`` (``∂f/∂ḋ``); exp ``λ e^{Bd}``; SLS ``k2 τ`` (the Maxwell arm at rates
    slow against ``1/τ``, the limit in which it is a dashpot).
    """
    if model == "kv":
        return float(params["damping_ns_per_m"])
    if model == "hc":
        d = max(compression_m, 0.0)
        return float(params["damping_ns_per_m_pow_n_plus_1"] * d ** params["exponent"])
    if model == "exp":
        d = max(compression_m, 0.0)
        return float(params["damping_ns_per_m"] * math.exp(params["stiffening_per_m"] * d))
    return float(params["arm_stiffness_n_per_m"] * params["relaxation_time_s"])


def to_physical(model: str, beta: FloatArray, shape: float, d_ref_m: float) -> dict[str, float]:
    """SI parameters from the scaled fit ``beta = [F0, a, b]`` and the shape (``n`` or ``τ``).

    The scaled design divides compressions by ``d_ref_m``: KV ``D = a/d_ref``, ``λ = b/d_ref``;
    HC ``k = a/d_refⁿ``, ``λ = b/d_refⁿ⁺¹``; SLS ``k1 = a/d_ref``, ``k2 = b/d_ref``; exp
    ``k0 = a/d_ref``, ``B = shape/d_ref``, ``λ = b/d_ref``.
    """
    f0, a, b = (float(x) for x in beta)
    if model == "kv":
        return {"preload_n": f0, "stiffness_n_per_m": a / d_ref_m, "damping_ns_per_m": b / d_ref_m}
    if model == "hc":
        return {
            "preload_n": f0,
            "stiffness_n_per_m_pow_n": a / d_ref_m**shape,
            "exponent": shape,
            "damping_ns_per_m_pow_n_plus_1": b / d_ref_m ** (shape + 1.0),
        }
    if model == "exp":
        return {
            "preload_n": f0,
            "stiffness_n_per_m": a / d_ref_m,
            "stiffening_per_m": shape / d_ref_m,
            "damping_ns_per_m": b / d_ref_m,
        }
    return {
        "preload_n": f0,
        "stiffness_n_per_m": a / d_ref_m,
        "arm_stiffness_n_per_m": b / d_ref_m,
        "relaxation_time_s": shape,
    }


def law_force(
    model: str,
    params: Mapping[str, float],
    d: FloatArray,
    rate: FloatArray,
    dt_s: float,
) -> FloatArray:
    """A law's force per sample from a compression and its exact rate (synthetic recordings).

    SLS integrates the Maxwell arm on the samples (exact for ``d`` linear between them; give
    a fine grid for a smooth ``d``).
    """
    f0 = params.get("preload_n", 0.0)
    return f0 + elastic_force(model, params, d) + rate_force(model, params, d, rate, dt_s)
