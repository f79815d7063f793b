"""Seeded synthetic fruit squeezes: force-controlled squeezes to collapse, and shapes that are not.

A gripper squeezing fruit raises its commanded force until the fruit breaks. At the break the
force collapses (by a fraction ``collapse_frac`` within ``collapse_s``) while the jaws keep
closing; then the controller backs off. The force sensor lags the jaw position (latency
``lag_s``). Each draw is one :class:`FruitSqueeze`: the recording (a
:class:`~deformctl.series.SqueezeSeries`, sampled at ~77 Hz with jittered time stamps and seeded
noise) and its truth. Shapes (:data:`SHAPES`):

* ``collapse``: a force ramp (with 0-2 slips before the break: the force dips by 5-20 % while the
  jaws jump) to a peak; in half of the draws the fruit then yields (the force falls slowly from
  the peak, 1.2-3.5x the break force, while the jaws close on); then the collapse by 35-92 %
  within 0.1-0.4 s, with the jaws closing on (or, in a fifth of the draws, stopped), and the
  back-off 0-0.4 s after the controller sees it (the jaws hold or recede a little).
* ``collapse_reload``: the same, but after the collapse the jaws crush on and the force rises
  again, to 1-3.5x the break force, before the back-off: the later, higher peak is not the
  rupture force.
* ``relaxation`` (no rupture): a standard linear solid pressed at constant speed and held; the
  force decays smoothly by 10-60 % (time constant 0.3-3 s), then is released or not.
* ``backoff`` (no rupture): a force ramp, an optional hold at constant force (the jaws creep),
  then the controller lowers the force within 0.1-1 s while the jaws open (no collapse).

The truth of a rupture shape is its **onset force**: the force at the onset of the collapse (the
break force), and where the onset appears in the recording (``onset_time_s``: the break plus
the sensor's lag). :func:`check` runs the rupture detector of ``characterize`` and ``measure``
(:func:`deformctl.squeeze.rupture.cut_rupture`, with the window ``characterize`` uses at the
recording's rate) over many draws and counts what it finds; the command line prints it::

    python -m deformctl.testing.fruit check --draws 500 --seed 0
    python -m deformctl.testing.fruit check --draws 500 --through-csv   # as measure --csv reads
    python -m deformctl.testing.fruit csv 9 -o kiwi.csv                  # one draw as a CSV export

Every random choice comes from ``numpy.random.default_rng([seed, draw])``.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np

from deformctl.series import FloatArray, Rupture, SqueezeSeries

__all__ = [
    "RUPTURE_SHAPES",
    "SHAPES",
    "CheckResult",
    "FruitSqueeze",
    "check",
    "fruit_squeeze",
    "fruit_squeezes",
    "main",
    "write_csv",
]

#: The shapes a draw can take; the first two rupture.
SHAPES = ("collapse", "collapse_reload", "relaxation", "backoff")
RUPTURE_SHAPES = ("collapse", "collapse_reload")
#: Generation grid: this many sub-steps per sample.
_FINE = 10
#: The collapses the targets are about: those that lose more than this fraction of the force.
BIG_COLLAPSE_FRAC = 0.5


@dataclass(frozen=True)
class FruitSqueeze:
    """One synthetic squeeze and its truth.

    Attributes:
        series: the recording (time s, force N, compression m).
        shape: one of :data:`SHAPES`.
        onset_force_n: the force at the onset of the collapse, N (NaN: no rupture).
        onset_time_s: when that onset appears in the recording (break + lag), s (NaN: none).
        collapse_frac: the fraction of the onset force lost in the collapse (NaN: none).
        lag_s: the force sensor's latency behind the position, s.
        rate_hz: the mean sample rate, Hz.
        params: the other drawn values (for a report).
    """

    series: SqueezeSeries
    shape: str
    onset_force_n: float
    onset_time_s: float
    collapse_frac: float
    lag_s: float
    rate_hz: float
    params: dict[str, float] = field(default_factory=dict)

    @property
    def ruptures(self) -> bool:
        """Whether the truth is a rupture."""
        return self.shape in RUPTURE_SHAPES


def _ease(x: FloatArray) -> FloatArray:
    """Raised cosine from 0 (x ≤ 0) to 1 (x ≥ 1)."""
    return 0.5 - 0.5 * np.cos(math.pi * np.clip(x, 0.0, 1.0))


def _ease_out(x: FloatArray) -> FloatArray:
    """1 − (1 − x)²: starts at full speed, ends at rest."""
    c = np.clip(x, 0.0, 1.0)
    return 1.0 - (1.0 - c) ** 2


def _elastic_compression(f: FloatArray, f_ref: float, d_ref: float, n: float) -> FloatArray:
    """Compression of ``f = k d^n`` through ``(d_ref, f_ref)``, m."""
    return d_ref * np.power(np.maximum(f, 0.0) / f_ref, 1.0 / n)


def _sample(
    t_fine: FloatArray,
    force: FloatArray,
    comp: FloatArray,
    rng: np.random.Generator,
    *,
    rate_hz: float,
    lag_s: float,
    force_noise_n: float,
    position_noise_m: float,
    object_id: str,
) -> SqueezeSeries:
    """Sample on jittered time stamps (±2 % of a sample interval), the force ``lag_s`` late."""
    n = int(t_fine[-1] * rate_hz)
    t = (np.arange(n) + rng.uniform(-0.02, 0.02, n)) / rate_hz
    t = np.clip(t, 0.0, t_fine[-1])
    t[0] = 0.0
    f = np.interp(t - lag_s, t_fine, force, left=force[0])
    d = np.interp(t, t_fine, comp)
    return SqueezeSeries(
        object_id=object_id,
        squeeze_index=0,
        time_s=t,
        force_n=f + rng.normal(0.0, force_noise_n, n),
        compression_m=d + rng.normal(0.0, position_noise_m, n),
    )


def _slips(
    t: FloatArray, rng: np.random.Generator, t_load: float
) -> tuple[FloatArray, FloatArray, int]:
    """0-2 slips during the ramp: a force multiplier (dips of 5-20 %) and a jaw offset, m."""
    mult = np.ones_like(t)
    offset = np.zeros_like(t)
    count = int(rng.integers(0, 3))
    starts = np.sort(rng.uniform(0.25, 0.7, count)) * t_load
    for t_s in starts:
        fall = rng.uniform(0.03, 0.1)
        recover = rng.uniform(0.2, 0.5)
        depth = rng.uniform(0.05, 0.2)
        bump = np.where(
            t < t_s + fall, _ease((t - t_s) / fall), 1.0 - _ease((t - t_s - fall) / recover)
        )
        mult *= 1.0 - depth * bump
        offset += rng.uniform(0.05e-3, 0.3e-3) * _ease((t - t_s) / fall)
    return mult, offset, count


def _collapse(rng: np.random.Generator, h: float, lag: float, reload: bool) -> dict[str, object]:
    """A force-controlled squeeze to collapse (true time; the lag is applied when sampling).

    The force ramps to a peak; half of the draws then yield first (the force falls by 17-71 %,
    over 1-3 s per unit of the ratio of peak to break force, while the jaws close on), and the
    fruit breaks at ``f_b``: the collapse.
    """
    f_b = rng.uniform(1.2, 8.0)  # the break force: the force at the onset of the collapse, N
    d_y = rng.uniform(2e-3, 8e-3)  # compression at the peak, m
    n_law = rng.uniform(1.0, 2.0)
    t_load = rng.uniform(1.5, 6.0)
    yields = rng.uniform() < 0.5
    f_pk = f_b * rng.uniform(1.2, 3.5) if yields else f_b  # the peak before the break
    # a yield slower than a collapse: at most ~1/3 of the peak force per second
    t_dec = rng.uniform(1.0, 3.0) * f_pk / f_b if yields else 0.0
    d_dec = rng.uniform(0.1, 0.5) * d_y if yields else 0.0
    t_c = rng.uniform(0.1, 0.4)  # collapse duration
    phi = rng.uniform(0.35, 0.92)  # fraction of the onset force lost
    jaw_travel = rng.uniform(0.02, 0.6) * d_y
    # the jaws keep closing while the (late) force falls; now and then they stop first
    t_j = lag + t_c * rng.uniform(0.8, 1.5) if rng.uniform() < 0.8 else t_c * rng.uniform(0.5, 1)
    f_low = f_b * (1.0 - phi)
    t_rl = rng.uniform(0.5, 3.0) if reload else 0.0
    f_2 = rng.uniform(1.0, 3.5) * f_b if reload else f_low
    d_2 = rng.uniform(0.3, 1.0) * d_y if reload else 0.0
    t_bo = rng.uniform(0.2, 1.0)
    f_end_frac = rng.uniform(0.0, 0.3)
    recede = rng.uniform(0.0, 0.2) * d_y
    rest = rng.uniform(0.3, 1.0)
    t_b = t_load + t_dec  # the break
    t_end_c = t_b + t_c
    # the controller backs off after the later peak, or once it sees the collapse (late by lag)
    after_s = rng.uniform(0.0, 0.3) if reload else rng.uniform(0.0, 0.4)
    t_bo0 = (t_end_c + t_rl if reload else t_b + lag) + after_s
    duration = max(t_bo0, t_end_c) + t_bo + rest + lag
    t = np.arange(round(duration / h) + 1, dtype=np.float64) * h
    f0 = 0.03 * f_pk
    mult, offset, slips = _slips(t, rng, t_load)
    f = (f0 + (f_pk - f0) * np.clip(t / t_load, 0.0, 1.0)) * mult
    d = _elastic_compression(f, f_pk, d_y, n_law) + offset
    d_at_y = float(d_y + offset[-1])
    if yields:
        xd = (t - t_load) / t_dec
        f = np.where(t > t_load, f_pk - (f_pk - f_b) * _ease(xd), f)
        d = np.where(t > t_load, d_at_y + d_dec * np.clip(xd, 0.0, 1.0), d)
    after = t > t_b
    f = np.where(after, f_b * (1.0 - phi * _ease((t - t_b) / t_c)), f)
    # the jaws close until the controller backs off
    closing = np.minimum(t, t_bo0 if not reload else np.inf) - t_b
    d = np.where(after, d_at_y + d_dec + jaw_travel * _ease_out(closing / t_j), d)
    if reload:
        xr = (t - t_end_c) / t_rl
        f = np.where(t > t_end_c, f_low + (f_2 - f_low) * np.clip(xr, 0, 1) ** 1.5, f)
        d = d + d_2 * _ease(xr)
    # the back-off: the force falls to f_end_frac of what it is, the jaws recede a little
    xb = _ease((t - t_bo0) / t_bo)
    f_at = np.interp(t_bo0, t, f)
    f = np.where(t > t_bo0, np.minimum(f, f_at) * (1.0 - (1.0 - f_end_frac) * xb), f)
    d = d - recede * xb
    return {
        "t": t, "f": f, "d": d, "scale_n": max(f_pk, f_2), "onset_force_n": f_b,
        "onset_time_s": t_b + lag, "collapse_frac": phi,
        "params": {"n_law": n_law, "load_s": t_load, "peak_before_n": f_pk, "yield_s": t_dec,
                   "collapse_s": t_c, "jaw_s": t_j, "jaw_travel_m": jaw_travel,
                   "slips": slips, "reload_peak_n": f_2},
    }  # fmt: skip


def _relaxation(rng: np.random.Generator, h: float, lag: float) -> dict[str, object]:
    """A standard linear solid pressed at constant speed and held (then maybe released)."""
    from deformctl.characterize.laws import law_force

    f_max = rng.uniform(1.2, 8.0)
    d_max = rng.uniform(2e-3, 8e-3)
    t_load = rng.uniform(1.0, 5.0)
    hold = rng.uniform(2.0, 6.0)
    chi = rng.uniform(0.1, 0.6)
    tau = rng.uniform(0.3, 3.0)
    release = rng.uniform(0.5, 2.0) if rng.uniform() < 0.5 else 0.0
    rest = rng.uniform(0.2, 0.8) if release else 0.0
    duration = t_load + hold + release + rest + lag
    t = np.arange(round(duration / h) + 1, dtype=np.float64) * h
    corner = 0.05
    up = np.clip(t / corner, 0, 1) - np.clip((t - t_load) / corner, 0, 1)
    v = up * d_max / t_load
    if release:
        t_r = t_load + hold
        v -= (np.clip((t - t_r) / corner, 0, 1) - np.clip((t - t_r - release) / corner, 0, 1)) * (
            d_max / release
        )
    d = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * h)])
    params = {
        "stiffness_n_per_m": 1.0 - chi,
        "arm_stiffness_n_per_m": chi,
        "relaxation_time_s": tau,
    }
    f = law_force("sls", params, d, v, h)
    f = f * (f_max / float(np.max(f)))
    return {
        "t": t, "f": f, "d": d, "scale_n": f_max, "onset_force_n": math.nan,
        "onset_time_s": math.nan, "collapse_frac": math.nan,
        "params": {"relaxation_frac": chi, "relaxation_time_s": tau, "load_s": t_load,
                   "hold_s": hold, "release_s": release},
    }  # fmt: skip


def _backoff(rng: np.random.Generator, h: float, lag: float) -> dict[str, object]:
    """A force ramp, an optional hold at constant force, and a back-off without collapse."""
    f_max = rng.uniform(1.2, 8.0)
    d_max = rng.uniform(2e-3, 8e-3)
    n_law = rng.uniform(1.0, 2.0)
    t_load = rng.uniform(1.5, 6.0)
    hold = rng.uniform(0.0, 2.0)
    creep = rng.uniform(0.0, 0.05) * d_max
    t_bo = rng.uniform(0.1, 1.0)
    f_end_frac = rng.uniform(0.0, 0.2)
    keep = rng.uniform(0.0, 0.5)  # share of the elastic recovery the jaws do not follow
    rest = rng.uniform(0.3, 1.0)
    duration = t_load + hold + t_bo + rest + lag
    t = np.arange(round(duration / h) + 1, dtype=np.float64) * h
    f0 = 0.03 * f_max
    mult, offset, slips = _slips(t, rng, t_load)
    f = (f0 + (f_max - f0) * np.clip(t / t_load, 0.0, 1.0)) * mult
    d_el = _elastic_compression(f, f_max, d_max, n_law) + offset
    d_el = d_el + creep * _ease_out((t - t_load) / max(hold, 1e-9)) * (hold > 0)
    t_bo0 = t_load + hold
    xb = (t - t_bo0) / t_bo
    f = np.where(t > t_bo0, f_max * (1.0 - (1.0 - f_end_frac) * _ease(xb)), f)
    d_top = float(np.interp(t_bo0, t, d_el))
    d_rec = _elastic_compression(f, f_max, d_max, n_law) + offset
    d = np.where(t > t_bo0, d_top - (d_top - d_rec) * (1.0 - keep), d_el)
    return {
        "t": t, "f": f, "d": d, "scale_n": f_max, "onset_force_n": math.nan,
        "onset_time_s": math.nan, "collapse_frac": math.nan,
        "params": {"n_law": n_law, "load_s": t_load, "hold_s": hold, "backoff_s": t_bo,
                   "kept_frac": keep, "slips": slips},
    }  # fmt: skip


def fruit_squeeze(seed: int, draw: int = 0, *, shape: str | None = None) -> FruitSqueeze:
    """Draw ``draw`` of seed ``seed``: a random shape (or ``shape``) with random parameters.

    Raises:
        ValueError: an unknown shape.
    """
    rng = np.random.default_rng([seed, draw])
    chosen = SHAPES[int(rng.integers(len(SHAPES)))] if shape is None else shape
    if chosen not in SHAPES:
        raise ValueError(f"unknown shape {chosen!r}; one of {', '.join(SHAPES)}")
    rate = rng.uniform(70.0, 85.0)
    lag = rng.uniform(0.1, 0.25)
    h = 1.0 / (rate * _FINE)
    if chosen in RUPTURE_SHAPES:
        g = _collapse(rng, h, lag, reload=chosen == "collapse_reload")
    elif chosen == "relaxation":
        g = _relaxation(rng, h, lag)
    else:
        g = _backoff(rng, h, lag)
    scale = float(g["scale_n"])  # type: ignore[arg-type]
    force_noise = rng.uniform(0.003, 0.012) * scale + 0.003
    series = _sample(
        g["t"], g["f"], g["d"], rng, rate_hz=rate, lag_s=lag, force_noise_n=force_noise,  # type: ignore[arg-type]
        position_noise_m=rng.uniform(5e-6, 2e-5), object_id=f"fruit-{seed}-{draw}",
    )  # fmt: skip
    params = dict(g["params"])  # type: ignore[call-overload]
    params["force_noise_n"] = force_noise
    return FruitSqueeze(
        series=series,
        shape=chosen,
        onset_force_n=float(g["onset_force_n"]),  # type: ignore[arg-type]
        onset_time_s=float(g["onset_time_s"]),  # type: ignore[arg-type]
        collapse_frac=float(g["collapse_frac"]),  # type: ignore[arg-type]
        lag_s=lag,
        rate_hz=rate,
        params=params,
    )


def fruit_squeezes(draws: int, seed: int = 0) -> Iterator[FruitSqueeze]:
    """Draws ``0 … draws − 1`` of ``seed``."""
    for i in range(draws):
        yield fruit_squeeze(seed, i)


@dataclass
class CheckResult:
    """What the rupture detector found on a set of draws (counts; ``errors`` relative)."""

    draws: int = 0
    big: int = 0  #: collapses by more than BIG_COLLAPSE_FRAC
    big_found: int = 0
    big_force_ok: int = 0  #: ... found, force within 10 % of the onset force
    small: int = 0  #: collapses by less
    small_found: int = 0
    collapses_called_relaxation: int = 0
    safe_above_onset: int = 0  #: found ruptures whose safe force exceeds the onset force
    sign_flipped: int = 0  #: through_csv: draws whose force sign the reader flipped (wrongly)
    not_rupture: dict[str, int] = field(default_factory=dict)
    false_rupture: dict[str, int] = field(default_factory=dict)
    force_errors: list[float] = field(default_factory=list)
    misses: list[tuple[int, str]] = field(default_factory=list)

    def lines(self) -> list[str]:
        """The report, one line per number."""
        err = np.abs(np.asarray(self.force_errors)) if self.force_errors else np.array([math.nan])
        out = [
            f"draws: {self.draws}",
            f"collapses > {BIG_COLLAPSE_FRAC:.0%}: rupture found on {self.big_found}/{self.big} "
            f"({_pct(self.big_found, self.big)}); force within 10 % of the onset force on "
            f"{self.big_force_ok}/{self.big} ({_pct(self.big_force_ok, self.big)})",
            f"collapses of 35-{BIG_COLLAPSE_FRAC:.0%}: rupture found on {self.small_found}/"
            f"{self.small} ({_pct(self.small_found, self.small)})",
            f"rupture force error vs the onset force (found collapses): median "
            f"{float(np.median(err)):.1%}, 95th percentile {float(np.percentile(err, 95)):.1%}, "
            f"max {float(np.max(err)):.1%}",
            f"safe force (max_safe_force_n) above the onset force: {self.safe_above_onset}",
            f"collapses flagged relaxation: {self.collapses_called_relaxation}",
        ]
        if self.sign_flipped:
            out.append(f"force sign flipped (wrongly) by the CSV reader: {self.sign_flipped}")
        for shape, n in self.not_rupture.items():
            bad = self.false_rupture.get(shape, 0)
            out.append(f"false ruptures on {shape}: {bad}/{n} ({_pct(bad, n)})")
        return out


def _pct(a: int, b: int) -> str:
    return f"{100.0 * a / b:.1f} %" if b else "n/a"


def _through_csv(
    fs: FruitSqueeze, folder: str
) -> tuple[SqueezeSeries, Rupture | None, float, bool]:
    """The draw written as a CSV export and read back by ``measure --csv``'s reader (no
    options): its first squeeze (cut at a rupture), the rupture, its position rate, and whether
    the reader flipped the force's sign (every draw's compressive force is positive)."""
    import os

    from deformctl.measure.csv.options import CsvOptions
    from deformctl.measure.stage import read_recording

    path = os.path.join(folder, f"{fs.series.object_id}.csv")
    write_csv(fs, path)
    rec = read_recording(path, CsvOptions(), fs.series.object_id)
    os.remove(path)
    rate = rec.position_rate_hz or fs.rate_hz
    flipped = bool(rec.details.get("force_sign", {}).get("flipped", False))
    return rec.squeezes[0], (rec.ruptures[0] if rec.ruptures else None), float(rate), flipped


def check(
    draws: int, seed: int = 0, *, keep_misses: int = 20, through_csv: bool = False
) -> CheckResult:
    """Run the rupture detector (and the relaxation finder on what it keeps) over the draws:
    on the series themselves, or (``through_csv``) on what ``measure --csv`` makes of each
    written as a CSV export (its force sign, lag and cut included)."""
    import tempfile

    from deformctl.squeeze.rupture import cut_rupture, find_relaxation, safe_force_n
    from deformctl.squeeze.window import default_window_s

    res = CheckResult()
    folder = tempfile.TemporaryDirectory(prefix="fruit-") if through_csv else None
    for i in range(draws):
        fs = fruit_squeeze(seed, i)
        if folder is not None:
            cut, rupture, rate, flipped = _through_csv(fs, folder.name)
            window = default_window_s(rate)
            res.sign_flipped += flipped
        else:
            window = default_window_s(fs.rate_hz)
            cut, rupture = cut_rupture(fs.series, window_s=window)
        res.draws += 1
        if not fs.ruptures:
            res.not_rupture[fs.shape] = res.not_rupture.get(fs.shape, 0) + 1
            if rupture is not None:
                res.false_rupture[fs.shape] = res.false_rupture.get(fs.shape, 0) + 1
                if len(res.misses) < keep_misses:
                    res.misses.append((i, fs.shape))
            continue
        big = fs.collapse_frac > BIG_COLLAPSE_FRAC
        if find_relaxation(cut, window_s=window) is not None:
            res.collapses_called_relaxation += 1
        if big:
            res.big += 1
        else:
            res.small += 1
        if rupture is None:
            if big and len(res.misses) < keep_misses:
                res.misses.append((i, fs.shape))
            continue
        rel = rupture.force_n / fs.onset_force_n - 1.0
        res.force_errors.append(rel)
        if safe_force_n(rupture.force_n) > fs.onset_force_n:
            res.safe_above_onset += 1
        if big:
            res.big_found += 1
            res.big_force_ok += abs(rel) <= 0.1
        else:
            res.small_found += 1
    if folder is not None:
        folder.cleanup()
    return res


def write_csv(fs: FruitSqueeze, path: str) -> None:
    """The draw as a CSV export a gripper's logger might write: ``Time (s)``, ``Load (N)``,
    ``Compression (mm)`` (the jaws' travel since contact)."""
    s = fs.series
    rows = np.column_stack([s.time_s, s.force_n, 1e3 * s.compression_m])
    np.savetxt(
        path,
        rows,
        fmt="%.6f",
        delimiter=",",
        header="Time (s),Load (N),Compression (mm)",
        comments="",
    )


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m deformctl.testing.fruit check [--draws N] [--seed S]``, ``show DRAW`` or
    ``csv DRAW -o FILE [--shape SHAPE]``."""
    parser = argparse.ArgumentParser(prog="python -m deformctl.testing.fruit")
    sub = parser.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="run the rupture detector over seeded draws")
    c.add_argument("--draws", type=int, default=500)
    c.add_argument("--seed", type=int, default=0)
    c.add_argument("--misses", action="store_true", help="list the draws it got wrong")
    c.add_argument(
        "--through-csv",
        action="store_true",
        help="write each draw as a CSV export and read it as measure --csv does",
    )
    s = sub.add_parser("show", help="one draw's truth")
    s.add_argument("draw", type=int)
    s.add_argument("--seed", type=int, default=0)
    w = sub.add_parser("csv", help="write one draw as a CSV export (Time, Load, Compression)")
    w.add_argument("draw", type=int)
    w.add_argument("-o", "--output", required=True)
    w.add_argument("--seed", type=int, default=0)
    w.add_argument("--shape", choices=SHAPES, default=None)
    args = parser.parse_args(argv)
    if args.command == "csv":
        fs = fruit_squeeze(args.seed, args.draw, shape=args.shape)
        write_csv(fs, args.output)
        print(f"{args.output}: {fs.shape}, onset force {fs.onset_force_n:.4g} N")
        return 0
    if args.command == "show":
        fs = fruit_squeeze(args.seed, args.draw)
        print(
            f"shape {fs.shape}, onset {fs.onset_force_n:.4g} N at {fs.onset_time_s:.3f} s, "
            f"collapse {fs.collapse_frac:.2f}, lag {fs.lag_s:.3f} s, rate {fs.rate_hz:.1f} Hz, "
            f"{len(fs.series)} samples"
        )
        print(", ".join(f"{k} {v:.4g}" for k, v in fs.params.items()))
        return 0
    if args.draws < 1:
        parser.error("--draws must be at least 1")
    res = check(args.draws, args.seed, through_csv=args.through_csv)
    for line in res.lines():
        print(line)
    if args.misses:
        for i, shape in res.misses:
            print(f"wrong: draw {i} ({shape})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
