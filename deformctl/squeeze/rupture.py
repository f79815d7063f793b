"""Where a squeeze stops being a Kelvin–Voigt squeeze: rupture, and the loading/unloading phases.

**Rupture.** A soft natural object squeezed too hard gives way: the force collapses while the
gripper keeps closing, or holds its position while a force-controlled gripper backs off. Fitted
whole, such a squeeze halves D and flips the sign of λ. :func:`find_rupture_index` finds the
point where it happened; ``measure`` cuts every squeeze there and records the point in the log,
``characterize`` does the same for logs that were not cut and flags the object (``rupture``).
The point is a :class:`~deformctl.series.Rupture` (a squeeze log stores it in the object's row,
so the record lives with the series; re-exported here). A rupture is a sample ``i`` after the
running force peak ``p`` where

1. the force has fallen by more than :data:`RUPTURE_DROP_FRAC` of the peak,
   ``f[i] < (1 − RUPTURE_DROP_FRAC) · f[p]`` (with ``f[p]`` at least
   :data:`RUPTURE_MIN_PEAK_FRAC` of the squeeze's peak force, so noise before contact is not a
   peak, and a drop of more than :data:`RUPTURE_NOISE_MULT` force-noise standard deviations);
2. the compression still grows (the smoothed compression at ``i`` exceeds the one at ``p`` by
   more than three position-noise standard deviations and :data:`HOLD_TOL_FRAC` of ``d[p]``),
   **or it holds** (it stayed within that tolerance of ``d[p]`` since the peak) and the force
   fell suddenly: somewhere between ``p`` and ``i`` faster than :data:`RUPTURE_SUDDEN_MULT`
   times the rate at which it rose over the upper half of the loading (both over spans of
   :data:`SUDDEN_SPAN_S`). The hold is the
   force-controlled gripper that backs off after the collapse while its fingers stay put (the
   pattern the shared fruit recordings show; the rule before it required a growing compression
   and missed 8 of 25 such ruptures);
3. the drop is not the object's own Kelvin–Voigt response: the force is more than
   ``RUPTURE_DROP_FRAC · f[p]`` below ``D̂ d[i] + λ̂ d'[i]``, with ``D̂, λ̂ ≥ 0`` fitted to the
   loading before the peak (``d`` smoothed over the squeeze's window, or over the longest window
   a loading shorter than two of them holds: :func:`_loading_window`). Conditions 1 and 2 alone
   also hold for a heavily damped object after its force peak: with ``λ/D`` long against the
   squeeze, the compression lags the force and still grows while the force falls by half
   (measured on the synthetic squeezes of ``tests/characterize/test_fit.py``, λ/D ≥ 0.5 s: 25 of
   240 squeezes). With condition 3 none of them, and none of the simulator's squeezes, is a
   rupture; a force collapse to 30–69 % of the peak with the gripper still closing is found
   within 6–155 ms (``tests/characterize/test_rupture_phases.py``).

A force that falls while the compression recedes (a load–unload cycle, a release) is not a
rupture.

**Rupture force.** The squeeze is cut at the peak ``p`` (the loading ends where the object
began to give way), but the rupture reported (time, force, compression) is the **onset of the
collapse**: the first fall after ``p`` of more than :data:`RUPTURE_DROP_FRAC` of the force
within :data:`COLLAPSE_S`, and the knee before its steep part (:func:`_collapse_onset`). A
fruit often yields first (the force falls slowly from its peak while the jaws close on) and
breaks later at a lower force; that break is the force it could bear, not the peak before it
nor a later peak of the crushed fruit. When the force fell by less than
:data:`ONSET_FALL_FRAC` between the peak and the onset (the usual collapse straight from the
peak), the onset is the peak. Measured on seeded fruit squeezes
(``python -m deformctl.testing.fruit check --draws 500``, ~77 Hz, a sensor lag of 0.1-0.25 s,
half of them yielding first): a rupture on 99 % of the collapses by more than half, its force
within 10 % of the onset force on 99 %, median error 0.7 %.

**Safe force.** The largest grip force deemed safe for an object that ruptured is its rupture
force less :data:`SAFE_FORCE_MARGIN` (15 %) of it (:func:`safe_force_n`; ``predict``'s
``max_safe_force_n``): the margin covers the detector's error (95th percentile 4.6 %, largest
26 % over those draws) and a fruit's spread between squeezes.

**Relaxation.** A force that decays *smoothly* while the compression holds (a testing machine
holding its crosshead on a viscoelastic object) is stress relaxation, not rupture:
:func:`find_relaxation` reports it (``characterize`` flags it ``relaxation``) and nothing is
cut. It is a hold of at least :data:`RELAXATION_HOLD_S` under load during which the smoothed
force falls by more than :data:`RELAXATION_FRAC` of its value at the start of the hold.

**Phases.** ``loading`` is a squeeze up to its peak force, ``unloading`` from its peak force to
its end, ``all`` the whole squeeze. The peak is a plateau when the force is held, so it is
judged on the SG-smoothed force: loading ends at the first sample within
:data:`PHASE_PEAK_TOL` of the smoothed maximum, unloading starts at the last one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import overload

import numpy as np

from deformctl.series import FloatArray, Rupture, SqueezeSeries, ruptures_from_object
from deformctl.signals import noise_std, sg_smooth, sg_window_length, uniform_grid
from deformctl.squeeze.phase import check_phase
from deformctl.units import s_to_ns

__all__ = [
    "HOLD_TOL_FRAC",
    "PHASE_PEAK_TOL",
    "RELAXATION_FRAC",
    "RELAXATION_HOLD_S",
    "RUPTURE_DROP_FRAC",
    "RUPTURE_MIN_PEAK_FRAC",
    "RUPTURE_NOISE_MULT",
    "RUPTURE_SUDDEN_MULT",
    "SAFE_FORCE_MARGIN",
    "Relaxation",
    "Rupture",
    "Smoothed",
    "cut_rupture",
    "cut_rupture_smoothed",
    "find_relaxation",
    "find_rupture_index",
    "phase_slice",
    "ruptures_from_object",
    "safe_force_n",
    "slice_squeeze",
]

#: A rupture is a force drop of more than this fraction of the running peak force while the
#: compression still grows (and that the Kelvin–Voigt fit of the loading does not predict).
RUPTURE_DROP_FRAC = 0.3
#: Only peaks of at least this fraction of the squeeze's peak force can rupture (noise before
#: contact makes many small running peaks).
RUPTURE_MIN_PEAK_FRAC = 0.25
#: ... and the drop must exceed this many force-noise standard deviations (a force that is
#: mostly sensor noise, e.g. a wrong wrench axis, has noise "peaks" that fall by 30 %).
RUPTURE_NOISE_MULT = 5.0
#: Condition 2: the compression "holds" when it stays within this fraction of its value at the
#: peak (or three position-noise standard deviations, whichever is larger).
HOLD_TOL_FRAC = 0.01
#: ... and then the force must fall at least this many times faster than it rose over the upper
#: half of the loading (a collapse, not a relaxation or a controlled release: the synthetic
#: rupture with back-off falls 10x faster, a standard linear solid relaxing at a hold at most
#: 0.6x, a release ramp 1x; ``tests/characterize/test_rupture.py``).
RUPTURE_SUDDEN_MULT = 5.0
#: ... both rates measured over this span, s (module docstring, :func:`_sudden`).
SUDDEN_SPAN_S = 0.02
#: ... and over at least this many samples (at ~77 Hz the noise of two-sample means made slow
#: relaxations look sudden: 3 of 707 holds of ``python -m deformctl.testing.fruit check``,
#: seeds 1-3, 1000 draws each; 1 with four samples).
_SUDDEN_MIN_SAMPLES = 4
#: Relaxation: a hold under load of at least this long, s ...
RELAXATION_HOLD_S = 0.2
#: ... whose smoothed force falls by more than this fraction of its value at the hold's start.
RELAXATION_FRAC = 0.05
#: The safe force is the rupture force less this fraction of it (module docstring, "Safe force").
SAFE_FORCE_MARGIN = 0.15
#: The onset of the collapse (:func:`_collapse_onset`): force means over this span, s ...
ONSET_SMOOTH_S = 0.06
#: ... a collapse loses more than RUPTURE_DROP_FRAC of the force within this span, s (the fruit
#: recordings: 50-92 % within 0.1-0.4 s) ...
COLLAPSE_S = 0.4
#: ... the knee sought within this span before the collapse's steep fall, s ...
ONSET_WINDOW_S = 0.5
#: ... and a peak the force fell from by less than this fraction before the collapse is the
#: onset (the usual collapse straight from the force peak).
ONSET_FALL_FRAC = 0.05
#: SG polynomial order of the smoothing used for rupture and phase detection.
_POLYORDER = 3
#: Condition 3's loading fit smooths the compression over the squeeze's SG window; a loading
#: shorter than two windows (a fast squeeze to collapse: 0.9 s of loading at 77 Hz against a
#: 0.47 s window) is smoothed over the longest window it holds, down to this many samples
#: (:func:`_loading_window`; below it the peak is not judged).
_MIN_LOADING_WINDOW = 2 * _POLYORDER + 3
#: The most candidate peaks examined per squeeze (each costs one small bounded fit).
_MAX_PEAKS = 20
#: Phases: the force peak is the stretch within this fraction of the smoothed maximum force.
PHASE_PEAK_TOL = 0.01


@overload
def safe_force_n(rupture_force_n: float) -> float: ...
@overload
def safe_force_n(rupture_force_n: FloatArray) -> FloatArray: ...
def safe_force_n(rupture_force_n: float | FloatArray) -> float | FloatArray:
    """The largest grip force deemed safe for an object that ruptured at ``rupture_force_n``
    (a float or an array): ``(1 − SAFE_FORCE_MARGIN) · rupture_force_n`` (NaN stays NaN)."""
    return (1.0 - SAFE_FORCE_MARGIN) * rupture_force_n


def _running_peak_index(force_n: FloatArray) -> np.ndarray:
    """For each sample, the index of the largest force so far (the latest one on ties)."""
    idx = np.arange(force_n.shape[0])
    running = np.maximum.accumulate(force_n)
    return np.asarray(np.maximum.accumulate(np.where(force_n >= running, idx, 0)))


def _kv_loading_fit(d: FloatArray, v: FloatArray, f: FloatArray) -> tuple[float, float] | None:
    """``(k, c) ≥ 0`` of ``f ≈ k d + c d'`` on the loading samples (bounded least squares)."""
    from scipy.optimize import lsq_linear

    x = np.column_stack([d, v])
    scale = np.sqrt(np.mean(x * x, axis=0))
    if not np.all(scale > 0):
        return None
    res = lsq_linear(x / scale, f, bounds=(0.0, np.inf))
    k, c = (res.x / scale).tolist()
    return float(k), float(c)


@dataclass(frozen=True)
class Smoothed:
    """A squeeze's compression on its uniform grid, SG-smoothed as the rupture search did it.

    The estimators smooth the compression of a squeeze that did not rupture the same way (same
    grid, window and order), so they reuse these arrays instead of filtering twice.

    Attributes:
        dt_s: the grid's sample interval, s.
        window_samples: the SG window, samples.
        polyorder: the SG polynomial order.
        compression_m: smoothed compression on the grid, m, ``[n]``.
        rate_m_per_s: its time derivative, m/s, ``[n]``.
    """

    dt_s: float
    window_samples: int
    polyorder: int
    compression_m: FloatArray
    rate_m_per_s: FloatArray


def find_rupture_index(
    time_s: FloatArray, force_n: FloatArray, compression_m: FloatArray, *, window_s: float
) -> int | None:
    """Index (into the input arrays) of the force peak at which the squeeze ruptured, or None.

    See the module docstring for the criterion. The input may be non-uniformly sampled; it is
    judged on a uniform grid (``window_s`` is the SG window used to smooth ``d`` and ``d'``).
    """
    found = _find_rupture(time_s, force_n, compression_m, window_s=window_s)[0]
    return None if found is None else found.peak


def _find_rupture(
    time_s: FloatArray, force_n: FloatArray, compression_m: FloatArray, *, window_s: float
) -> tuple[_Found | None, Smoothed | None]:
    """:func:`find_rupture_index`, and the smoothed compression it judged (None if too short)."""
    n_in = force_n.shape[0]
    if n_in < 10:
        return None, None
    dt_s, grid, (f, comp) = uniform_grid(time_s, force_n, compression_m)
    n = f.shape[0]
    wl = sg_window_length(window_s, dt_s, _POLYORDER)
    if n < 4 * wl:
        return None, None
    d, v = sg_smooth(comp, wl, _POLYORDER, dt_s)
    smoothed = Smoothed(dt_s, wl, _POLYORDER, d, v)
    peak_idx = _running_peak_index(f)
    running = f[peak_idx]
    sigma = noise_std(comp)
    floor = max(
        RUPTURE_MIN_PEAK_FRAC * float(np.max(f)),
        RUPTURE_NOISE_MULT * noise_std(f) / RUPTURE_DROP_FRAC,
    )
    dropped = (f < (1.0 - RUPTURE_DROP_FRAC) * running) & (running >= floor)
    # growth and holds on the raw compression's short local means: a long smoothing window
    # rounds the corner of a ramp that stops at the peak and overshoots after it
    m = max(2, round(SUDDEN_SPAN_S / dt_s))
    d_loc = np.convolve(comp, np.ones(m) / m, mode="same")
    tol = np.maximum(3.0 * sigma / math.sqrt(m), HOLD_TOL_FRAC * np.abs(d_loc[peak_idx]))
    growing = d_loc > d_loc[peak_idx] + tol
    near = d_loc >= d_loc[peak_idx] - tol
    shorter: dict[int, tuple[FloatArray, FloatArray]] = {wl: (d, v)}
    tried: set[int] = set()
    for i in np.flatnonzero(dropped & near):
        p = int(peak_idx[i])
        if p in tried:
            continue
        if len(tried) >= _MAX_PEAKS:
            break
        tried.add(p)
        w = _loading_window(wl, p)
        if w is None:  # too little loading before the peak to judge
            continue
        if w not in shorter:
            shorter[w] = sg_smooth(comp, w, _POLYORDER, dt_s)
        dw, vw = shorter[w]
        lo, hi = w // 2, p - w // 2
        kc = _kv_loading_fit(dw[lo:hi], vw[lo:hi], f[lo:hi])
        if kc is None:
            continue
        after = slice(p, n)
        held = np.minimum.accumulate(near[after])  # still near d[p] at every sample so far
        predicted = kc[0] * dw[after] + kc[1] * vw[after]
        shortfall = predicted - f[after] > RUPTURE_DROP_FRAC * f[p]
        grows = growing[after] & dropped[after]
        holds = held & dropped[after]
        if np.any(shortfall & grows):
            j = p + int(np.argmax(shortfall & grows))
            return _found(time_s, grid, f, dt_s, p, j), smoothed
        if np.any(shortfall & holds):
            j = p + int(np.argmax(shortfall & holds))
            if _sudden(f, dt_s, p, j):
                return _found(time_s, grid, f, dt_s, p, j), smoothed
    return None, smoothed


def _loading_window(wl: int, p: int) -> int | None:
    """The SG window (samples) of the loading fit of condition 3 before a peak at grid sample
    ``p``: ``wl``, or, when the loading is shorter than two of them, the longest odd window
    that leaves a window's worth of samples clear of the filter's edges (``p ≥ 2w − 1``); None
    below :data:`_MIN_LOADING_WINDOW` samples (too little loading to judge)."""
    if p >= 2 * wl - 1:
        return wl
    w = (p + 1) // 2
    w -= 1 - w % 2
    return w if w >= _MIN_LOADING_WINDOW else None


@dataclass(frozen=True)
class _Found:
    """A rupture on the grid: the peak ``p`` the squeeze is cut at, and the collapse's onset
    (input sample, and its force: the peak's raw sample or the short local mean at the onset)."""

    peak: int
    onset: int
    onset_force_n: float | None


def _found(
    time_s: FloatArray, grid: FloatArray, f: FloatArray, dt_s: float, p: int, j: int
) -> _Found:
    o, fo = _collapse_onset(f, dt_s, p)
    return _Found(_back_to_input(time_s, grid, p), _back_to_input(time_s, grid, o), fo)


def _collapse_onset(f: FloatArray, dt_s: float, p: int) -> tuple[int, float | None]:
    """The onset of the collapse after the peak ``p`` (module docstring, "Rupture force").

    On the force's local means over :data:`ONSET_SMOOTH_S`: the collapse is the first sample
    from ``p`` on after which the force falls by more than :data:`RUPTURE_DROP_FRAC` of its value
    within :data:`COLLAPSE_S`; its steep fall is the first sample in that span falling at least
    half as fast as the steepest; the onset is the knee before it: the sample of the
    :data:`ONSET_WINDOW_S` before the steep fall (not before ``p``) that lies farthest above the
    chord to it. Without such a collapse (a slow yield), or when the force fell from the peak by
    less than :data:`ONSET_FALL_FRAC` before the onset, the onset is the peak itself (returned
    with force None: the peak's own sample).
    """
    n = f.shape[0]
    m = max(3, round(ONSET_SMOOTH_S / dt_s))
    kernel = np.ones(m) / m
    fs = np.convolve(f, kernel, mode="same") / np.convolve(np.ones(n), kernel, mode="same")
    w = max(2, round(COLLAPSE_S / dt_s))
    if n - p < w + 1:
        return p, None
    ahead = np.lib.stride_tricks.sliding_window_view(fs[p:], w + 1).min(axis=1)
    start = fs[p : p + ahead.shape[0]]
    fast = np.flatnonzero(start - ahead > RUPTURE_DROP_FRAC * np.maximum(start, 0.0))
    if fast.size == 0:
        return p, None
    i = p + int(fast[0])
    rate = np.gradient(fs, dt_s)
    seg = rate[i : i + w + 1]
    k = i + int(np.argmax(seg <= 0.5 * float(np.min(seg))))
    a = max(p, k - max(2, round(ONSET_WINDOW_S / dt_s)))
    idx = np.arange(a, k + 1)
    chord = fs[a] + (fs[k] - fs[a]) * (idx - a) / max(k - a, 1)
    o = a + int(np.argmax(fs[a : k + 1] - chord))
    if fs[p] - fs[o] <= ONSET_FALL_FRAC * fs[p]:
        return p, None
    return o, float(fs[o])


def _back_to_input(time_s: FloatArray, grid: FloatArray, p: int) -> int:
    """The input sample at or before grid sample ``p``."""
    return int(np.searchsorted(time_s, grid[p], side="right") - 1)


def _sudden(f: FloatArray, dt_s: float, p: int, j: int) -> bool:
    """Whether the force fell between ``p`` and ``j`` faster than :data:`RUPTURE_SUDDEN_MULT`
    times its rise over the upper half of the loading before ``p``.

    Rates are changes of the force's mean over :data:`SUDDEN_SPAN_S` (at least
    :data:`_SUDDEN_MIN_SAMPLES` samples)
    across one such span: a collapse within tens of milliseconds stands out, while the sensor's
    noise, averaged over the span, does not.
    """
    m = max(_SUDDEN_MIN_SAMPLES, round(SUDDEN_SPAN_S / dt_s))
    if f.shape[0] < 2 * m + 2:
        return True
    local = np.convolve(f, np.ones(m) / m, mode="valid")  # local[i]: mean of f[i : i + m]
    below = np.flatnonzero(f[:p] < 0.5 * f[p])
    start = int(below[-1]) if below.size else 0
    rise_idx = np.arange(start, max(start, p - 2 * m))
    fall_idx = np.arange(max(p - m, 0), min(j, local.shape[0] - m))
    if rise_idx.size == 0 or fall_idx.size == 0:
        return True
    rise = float(np.median(local[rise_idx + m] - local[rise_idx]))
    fall = float(np.max(local[fall_idx] - local[fall_idx + m]))
    return rise <= 0 or fall > RUPTURE_SUDDEN_MULT * rise


def cut_rupture(
    s: SqueezeSeries, *, window_s: float, recording_offset_s: float | None = None
) -> tuple[SqueezeSeries, Rupture | None]:
    """The squeeze up to its rupture (inclusive) and the rupture; the squeeze itself if none."""
    cut, rupture, _ = cut_rupture_smoothed(
        s, window_s=window_s, recording_offset_s=recording_offset_s
    )
    return cut, rupture


def cut_rupture_smoothed(
    s: SqueezeSeries, *, window_s: float, recording_offset_s: float | None = None
) -> tuple[SqueezeSeries, Rupture | None, Smoothed | None]:
    """:func:`cut_rupture`, and the squeeze's smoothed compression when it did not rupture
    (None when it did, or was too short to judge)."""
    found, smoothed = _find_rupture(s.time_s, s.force_n, s.compression_m, window_s=window_s)
    if found is None:
        return s, None, smoothed
    o = found.onset
    rupture = Rupture(
        squeeze_index=s.squeeze_index,
        time_s=float(s.time_s[o]),
        force_n=float(s.force_n[o]) if found.onset_force_n is None else found.onset_force_n,
        compression_m=float(s.compression_m[o]),
        recording_time_s=None
        if recording_offset_s is None
        else float(recording_offset_s + s.time_s[o]),
    )
    return slice_squeeze(s, slice(0, found.peak + 1)), rupture, None


@dataclass(frozen=True)
class Relaxation:
    """A hold under load during which the force decayed smoothly (stress relaxation).

    Attributes:
        squeeze_index: the squeeze.
        time_s: start of the hold since the start of the squeeze, s.
        duration_s: length of the hold, s.
        force_start_n: smoothed force at the start of the hold, N.
        force_drop_n: how much it fell by the end of the hold, N.
    """

    squeeze_index: int
    time_s: float
    duration_s: float
    force_start_n: float
    force_drop_n: float

    @property
    def drop_frac(self) -> float:
        """The drop as a fraction of the force at the start of the hold."""
        return self.force_drop_n / self.force_start_n if self.force_start_n > 0 else float("nan")


def find_relaxation(s: SqueezeSeries, *, window_s: float) -> Relaxation | None:
    """The hold of a squeeze whose force relaxed the most (module docstring), or None.

    A hold is a stretch of at least :data:`RELAXATION_HOLD_S` and two SG windows where the
    smoothed compression moves slower than 2 % of its fastest rate, above 10 % of its peak; it
    relaxes when the smoothed force, half a window inside each end, falls by more than
    :data:`RELAXATION_FRAC` of its value at the start and by more than
    :data:`RUPTURE_NOISE_MULT` force-noise standard deviations.
    """
    if len(s) < 10:
        return None
    dt_s, grid, (f, comp) = uniform_grid(s.time_s, s.force_n, s.compression_m)
    n = f.shape[0]
    wl = sg_window_length(window_s, dt_s, _POLYORDER)
    if n < 4 * wl:
        return None
    d, v = sg_smooth(comp, wl, _POLYORDER, dt_s)
    fs, _ = sg_smooth(f, wl, _POLYORDER, dt_s)
    top = float(np.max(np.abs(v)))
    if not top > 0:
        return None
    still = (np.abs(v) < 0.02 * top) & (d > 0.1 * float(np.max(d)))
    min_len = max(round(RELAXATION_HOLD_S / dt_s), 2 * wl)
    floor = RUPTURE_NOISE_MULT * noise_std(f)
    best: Relaxation | None = None
    edges = np.diff(np.concatenate([[0], still.astype(np.int8), [0]]))
    half = wl // 2
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        if b - a < min_len:
            continue
        i0, i1 = a + half, b - 1 - half
        start, end = float(fs[i0]), float(fs[i1])
        drop = start - end
        if start > 0 and drop > RELAXATION_FRAC * start and drop > floor:
            cand = Relaxation(
                squeeze_index=s.squeeze_index,
                time_s=float(grid[a] - grid[0]),
                duration_s=float(grid[b - 1] - grid[a]),
                force_start_n=start,
                force_drop_n=drop,
            )
            if best is None or cand.drop_frac > best.drop_frac:
                best = cand
    return best


def slice_squeeze(s: SqueezeSeries, sl: slice) -> SqueezeSeries:
    """Samples ``sl`` of a squeeze, its time restarting at 0 (compression keeps its zero; the
    source clock, when known, moves to the first kept sample)."""
    t = s.time_s[sl]
    opt = {
        name: None if getattr(s, name) is None else getattr(s, name)[sl]
        for name in ("commanded_force_n", "palm_left_x_m", "palm_right_x_m")
    }
    start_ns = s.start_time_ns
    if start_ns is not None and t.size:
        start_ns += s_to_ns(float(t[0] - s.time_s[0]))
    return SqueezeSeries(
        object_id=s.object_id,
        squeeze_index=s.squeeze_index,
        time_s=t - t[0],
        force_n=s.force_n[sl],
        compression_m=s.compression_m[sl],
        start_time_ns=start_ns,
        **opt,
    )


def phase_slice(time_s: FloatArray, force_n: FloatArray, phase: str, *, window_s: float) -> slice:
    """The samples of ``phase`` (``loading``, ``unloading`` or ``all``) of one squeeze.

    Raises:
        UsageError: an unknown phase.
    """
    check_phase(phase)
    n = force_n.shape[0]
    if phase == "all" or n < 3:
        return slice(0, n)
    dt_s, grid, (f,) = uniform_grid(time_s, force_n)
    wl = min(sg_window_length(window_s, dt_s, _POLYORDER), f.shape[0] - (1 - f.shape[0] % 2))
    smooth = sg_smooth(f, wl, _POLYORDER, dt_s)[0] if wl > _POLYORDER + 1 else f
    peak = float(np.max(smooth))  # (a force that never turns positive has a negative peak)
    top = np.flatnonzero(smooth >= peak - PHASE_PEAK_TOL * abs(peak))  # a peak ≤ 0 too
    if top.size == 0:  # NaN samples: no peak to cut at
        return slice(0, n)
    if phase == "loading":
        end_t = grid[int(top[0])]
        return slice(0, int(np.searchsorted(time_s, end_t, side="right")))
    start_t = grid[int(top[-1])]
    return slice(max(int(np.searchsorted(time_s, start_t, side="left")), 0), n)
