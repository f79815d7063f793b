"""Unit and geometry sanity of a rig recording: refuse what cannot be a squeeze, name the cause.

``measure --csv`` and ``measure --bag`` check every recording before writing a squeeze log. Each
check below refuses (exit 65) with one line that names the likely cause and the fix: a unit
that makes the numbers implausible (``did you mean --units compression=mm?``), a force that lies
on another axis of the wrench (``force is on z, not x: pass --axis z``), a position that grows
the wrong way (``pass --position-increases-when closing``). The limits are generous on purpose:
they catch factors of 10³ (a unit mistake), not unusual objects.

================================ =============================================================
sample rate                      outside :data:`MIN_RATE_HZ`–:data:`MAX_RATE_HZ`
peak force                       above :data:`MAX_PEAK_FORCE_N`
peak compression                 larger than the object along the squeeze axis (when its size is
                                 known) or than :data:`MAX_COMPRESSION_M`
force axis                       another component of the wrench spans more than
                                 :data:`AXIS_DOMINANCE` × the one of ``--axis``
compression sign                 negative over the loaded samples (force ≥ :data:`SIGN_FORCE_FRAC`
                                 of its peak)
================================ =============================================================

A value that a unit slip may explain but that can be right is flagged instead (:func:`unit_doubts`,
:func:`damping_ratio_doubt`): ``force_unit_doubtful``, ``compression_unit_doubtful``,
``time_unit_doubtful`` and ``damping_ratio_implausible``, each with a warning line naming the unit
that would make it plausible; ``characterize`` adds them to the object's ``quality``, so the
coefficients are never ``ok``. A doubtful value that no recognised unit makes plausible is refused.
The numbers live with their quantities in :mod:`deformctl.quantities` (``RECORDED_*``,
``IMPLIED_DAMPING_RATIO``, ``MAX_LIFT_RATIO``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np

from deformctl.errors import InputDataError
from deformctl.quantities import (
    IMPLIED_DAMPING_RATIO,
    RECORDED_PEAK_COMPRESSION_M,
    RECORDED_PEAK_FORCE_N,
    RECORDED_RATE_HZ,
    RECORDED_SECANT_N_PER_CM,
)
from deformctl.series import FloatArray
from deformctl.squeeze.flags import COMPRESSION_UNIT_DOUBTFUL, TIME_UNIT_DOUBTFUL
from deformctl.units import UNITS

# The numbers live with their quantities (:mod:`deformctl.quantities`, "a recording's
# plausibility"); these names are the limits as this module's checks and messages use them.
MIN_RATE_HZ = RECORDED_RATE_HZ.low
MAX_RATE_HZ = RECORDED_RATE_HZ.high
MAX_PEAK_FORCE_N = RECORDED_PEAK_FORCE_N.high
MAX_COMPRESSION_M = RECORDED_PEAK_COMPRESSION_M.high
#: The force is "mostly on another axis" when another component's range (1st to 99th
#: percentile) is more than this multiple of the chosen axis's range.
AXIS_DOMINANCE = 2.0
#: The compression sign is judged on the samples whose force is at least this fraction of the
#: peak: where the object is squeezed, d must be positive.
SIGN_FORCE_FRAC = 0.5
#: Suggested units aim at these magnitudes: a 1 kHz sensor, a 10 N squeeze, a compression of a
#: tenth of the object (or 1 cm when its size is unknown).
_TARGET_RATE_HZ = RECORDED_RATE_HZ.target
_TARGET_FORCE_N = RECORDED_PEAK_FORCE_N.target
_TARGET_STRAIN = 0.1
_TARGET_COMPRESSION_M = RECORDED_PEAK_COMPRESSION_M.target
#: The units a hint may suggest: the slips of a factor 10³ (an imperial unit is not a slip).
SUGGESTED_UNITS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "ms": 1e-3, "µs": 1e-6},
    "force": {"N": 1.0, "kN": 1e3, "mN": 1e-3},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "µm": 1e-6},
}

PathArg = str | PathLike[str]


def suggest_unit(
    raw: float,
    factors: Mapping[str, float],
    *,
    to_value: Callable[[float], float],
    ok: Callable[[float], bool],
    target: float,
) -> str | None:
    """The unit under which ``raw`` (a magnitude read from the file) would be plausible.

    Args:
        raw: the magnitude in the file's numbers (before any unit factor).
        factors: unit → factor to SI.
        to_value: SI value → the quantity judged (e.g. a sample interval → a rate).
        ok: whether a judged value is plausible.
        target: the most typical judged value; the plausible unit nearest to it (in log) wins.

    Returns:
        The unit name, or None when no unit makes the value plausible.
    """
    best: tuple[float, str] | None = None
    seen: set[float] = set()
    for unit, factor in factors.items():
        if factor in seen:  # aliases (us / µs)
            continue
        seen.add(factor)
        value = to_value(raw * factor)
        if not (math.isfinite(value) and value > 0 and ok(value)):
            continue
        score = abs(math.log(value / target))
        if best is None or score < best[0]:
            best = (score, unit)
    return None if best is None else best[1]


def rate_ok(rate_hz: float) -> bool:
    """Whether a sample rate is plausible (:data:`MIN_RATE_HZ`–:data:`MAX_RATE_HZ`)."""
    return MIN_RATE_HZ <= rate_hz <= MAX_RATE_HZ


def check_sample_rate(rate_hz: float, *, what: str, path: PathArg, hint: str) -> None:
    """Refuse an implausible sample rate of stream ``what``; ``hint`` names the likely fix.

    Raises:
        InputDataError: the rate is outside :data:`MIN_RATE_HZ`–:data:`MAX_RATE_HZ`.
    """
    if not rate_ok(rate_hz):
        raise InputDataError(
            f"{what}: sample rate {rate_hz:.3g} Hz is implausible (outside "
            f"{MIN_RATE_HZ:g} Hz–{MAX_RATE_HZ / 1e3:g} kHz): {hint}",
            path=path,
        )


def check_peak_force(peak_n: float, *, what: str, path: PathArg, hint: str) -> None:
    """Refuse a peak force above :data:`MAX_PEAK_FORCE_N`; ``hint`` names the likely fix.

    Raises:
        InputDataError: the peak force is implausible.
    """
    if peak_n > MAX_PEAK_FORCE_N:
        raise InputDataError(
            f"{what}: peak force {peak_n:.3g} N is implausible (above {MAX_PEAK_FORCE_N / 1e3:g} "
            f"kN): {hint}",
            path=path,
        )


def compression_limit_m(size_x_cm: float | None) -> float:
    """The largest plausible compression: the object's size along x, at most 0.5 m."""
    if size_x_cm is None or not math.isfinite(size_x_cm) or size_x_cm <= 0:
        return MAX_COMPRESSION_M
    return min(MAX_COMPRESSION_M, size_x_cm / 100.0)


def compression_target_m(size_x_cm: float | None) -> float:
    """The typical compression a suggested unit aims at (a tenth of the object, or 1 cm)."""
    if size_x_cm is None or not math.isfinite(size_x_cm) or size_x_cm <= 0:
        return _TARGET_COMPRESSION_M
    return _TARGET_STRAIN * size_x_cm / 100.0


def check_peak_compression(
    peak_m: float, *, size_x_cm: float | None, what: str, path: PathArg, hint: str
) -> None:
    """Refuse a peak compression larger than the object (or 0.5 m); ``hint`` names the fix.

    Raises:
        InputDataError: the peak compression is implausible.
    """
    limit = compression_limit_m(size_x_cm)
    if peak_m > limit:
        than = (
            f"larger than the object ({size_x_cm:g} cm along x)"
            if limit < MAX_COMPRESSION_M
            else f"above {MAX_COMPRESSION_M:g} m"
        )
        raise InputDataError(
            f"{what}: peak compression {peak_m:.3g} m is implausible ({than}): {hint}", path=path
        )


def force_range(component: FloatArray) -> float:
    """The span of one force component, 1st to 99th percentile (robust to spikes), N."""
    if component.size == 0:
        return 0.0
    lo, hi = np.percentile(component, [1.0, 99.0])
    return float(hi - lo)


def check_force_axis(vectors: FloatArray, axis: str, *, what: str, path: PathArg) -> None:
    """Refuse a wrench whose force lies mostly on another axis than ``axis``.

    Args:
        vectors: force vectors ``[n, 3]`` (x, y, z), N.
        axis: the chosen axis.
        what: the stream, for the message.
        path: the recording.

    Raises:
        InputDataError: another component spans more than :data:`AXIS_DOMINANCE` × the chosen
            one (``force is on z, not x: pass --axis z``).
    """
    names = ("x", "y", "z")
    spans = {a: force_range(vectors[:, i]) for i, a in enumerate(names)}
    other = max((a for a in names if a != axis), key=lambda a: spans[a])
    if spans[other] > AXIS_DOMINANCE * spans[axis]:
        detail = ", ".join(f"{a} {spans[a]:.3g} N" for a in names)
        raise InputDataError(
            f"{what}: force is on {other}, not {axis}: pass --axis {other} (force range: {detail})",
            path=path,
        )


def compression_has_wrong_sign(compression_m: FloatArray, force_n: FloatArray) -> bool:
    """Whether d is negative where the object is squeezed (force ≥ 50 % of its peak)."""
    peak = float(np.max(force_n)) if force_n.size else 0.0
    if not peak > 0:
        return False
    loaded = force_n >= SIGN_FORCE_FRAC * peak
    return bool(np.median(compression_m[loaded]) < 0)


# -- the "too small" side: flags, since a small reading can be right -----------------------------

MIN_PEAK_FORCE_N = RECORDED_PEAK_FORCE_N.doubt_low
DOUBTFUL_PEAK_FORCE_N = RECORDED_PEAK_FORCE_N.doubt_high
MIN_PEAK_COMPRESSION_M = RECORDED_PEAK_COMPRESSION_M.doubt_low
MIN_UNSTATED_RATE_HZ = RECORDED_RATE_HZ.doubt_low
MAX_SECANT_N_PER_CM = RECORDED_SECANT_N_PER_CM.doubt_high
MAX_DAMPING_RATIO = IMPLIED_DAMPING_RATIO.doubt_high


@dataclass(frozen=True)
class Reading:
    """How one stream's numbers were read.

    Attributes:
        what: the stream, for messages (``column 'Load (N)'``, ``topic '/wrench'``).
        unit: the unit applied (``N``, ``mm``, ``s``).
        si: its factor to SI.
        stated: the unit was given (a header, a units row, ``--units``, a message type whose
            unit is fixed) rather than assumed.
    """

    what: str
    unit: str
    si: float
    stated: bool = True


def _units_of(dimension: str) -> dict[str, float]:
    """Every recognised unit of ``dimension`` (:data:`deformctl.units.UNITS`), name → SI factor."""
    return {name: unit.si for name, unit in UNITS[dimension].items()}


def _reading_clause(unit: str | None) -> str:
    return f"; plausible in {unit}: is the unit right?" if unit else "; is the unit right?"


def unit_doubts(
    *,
    rate_hz: float,
    peak_force_n: float,
    peak_compression_m: float,
    readings: Mapping[str, Reading],
    path: PathArg | None = None,
) -> list[tuple[str, str, dict[str, float]]]:
    """The "too small" (and "rather large") side of the plausibility checks, as flags.

    The bands are :mod:`deformctl.quantities`' (``RECORDED_*``): a sample rate below 10 Hz with
    no time unit stated, a peak force below 50 mN or above 3 kN, a peak compression below 20 µm,
    and (when neither peak is doubtful) a secant stiffness peak force / peak compression above
    5000 N/cm. Each line names the stream and the unit (a 10³ slip: s/ms/µs, N/kN/mN,
    m/cm/mm/µm) under which the value would be plausible.

    Args:
        rate_hz: the force's sample rate.
        peak_force_n, peak_compression_m: the recording's peaks, SI.
        readings: ``time``, ``force`` and ``length``: how each stream was read.
        path: the recording, for the refusal.

    Returns:
        ``(flag, line, numbers)`` per doubt; empty for a plausible recording.

    Raises:
        InputDataError: a doubtful value that no recognised unit of its dimension (``lbf``,
            ``in``, ``h`` and the rest of :data:`deformctl.units.UNITS`) makes plausible: no
            reading of it is a squeeze (exit 65, naming the stream and the units tried).
    """
    out: list[tuple[str, str, dict[str, float]]] = []

    def suggest(kind: str, value_si: float, judge: Any, to_value: Any = None) -> str | None:
        reading = readings[kind]
        unit = suggest_unit(
            value_si / reading.si,
            SUGGESTED_UNITS[kind],
            to_value=to_value or (lambda v: v),
            ok=judge.plausible,
            target=judge.target,
        )
        return None if unit == reading.unit else unit

    def no_reading(kind: str, value_si: float, judge: Any, text: str, to_value: Any = None) -> None:
        reading, every = readings[kind], _units_of(kind)
        as_value = to_value or (lambda v: v)
        unit = suggest_unit(
            value_si / reading.si, every, to_value=as_value, ok=judge.plausible, target=judge.target
        )
        if unit is None:
            raise InputDataError(
                f"{reading.what}: {text} is implausible under every {kind} unit "
                f"({', '.join(every)}): no reading of it is a squeeze",
                path=path,
            )

    time, force, length = readings["time"], readings["force"], readings["length"]
    if not time.stated and math.isfinite(rate_hz) and 0 < rate_hz < MIN_UNSTATED_RATE_HZ:
        rate = RECORDED_RATE_HZ
        no_reading("time", 1.0 / rate_hz, rate, f"sample rate {rate_hz:.3g} Hz", lambda dt: 1 / dt)
        clause = _reading_clause(suggest("time", 1.0 / rate_hz, rate, lambda dt: 1 / dt))
        text = (
            f"{time.what}: time unit not stated and the sample rate is {rate_hz:.3g} Hz (below "
            f"{MIN_UNSTATED_RATE_HZ:g} Hz){clause}"
        )
        out.append((rate.flag, text, {"rate_hz": rate_hz}))
    force_odd = compression_odd = False
    peak, judge = peak_force_n, RECORDED_PEAK_FORCE_N
    if math.isfinite(peak) and 0 < peak < judge.doubt_low:
        no_reading("force", peak, judge, f"peak force {peak:.3g} N")
        force_odd = True
        clause = _reading_clause(suggest("force", peak, judge))
        text = (
            f"{force.what}: peak force {peak:.3g} N is below {judge.doubt_low * 1e3:g} mN{clause}"
        )
        out.append((judge.flag, text, {"peak_force_n": peak}))
    elif judge.doubt_high < peak <= judge.high:
        force_odd = True
        clause = _reading_clause(suggest("force", peak, judge))
        text = (
            f"{force.what}: peak force {peak:.3g} N is above {judge.doubt_high / 1e3:g} kN for a "
            f"soft object{clause}"
        )
        out.append((judge.flag, text, {"peak_force_n": peak}))
    peak, judge = peak_compression_m, RECORDED_PEAK_COMPRESSION_M
    if math.isfinite(peak) and 0 < peak < judge.doubt_low:
        no_reading("length", peak, judge, f"peak compression {peak * 1e6:.3g} µm")
        compression_odd = True
        clause = _reading_clause(suggest("length", peak, judge))
        text = (
            f"{length.what}: peak compression {peak * 1e6:.3g} µm is below "
            f"{judge.doubt_low * 1e6:g} µm{clause}"
        )
        out.append((judge.flag, text, {"peak_compression_m": peak}))
    if not (force_odd or compression_odd):
        secant = _secant_doubt(peak_force_n, peak_compression_m, readings)
        if secant is not None:
            out.append(secant)
    return out


def _secant_doubt(
    force_n: float, compression_m: float, readings: Mapping[str, Reading]
) -> tuple[str, str, dict[str, float]] | None:
    """The secant-stiffness doubt (:data:`~deformctl.quantities.RECORDED_SECANT_N_PER_CM`)."""
    if not (math.isfinite(force_n) and math.isfinite(compression_m) and compression_m > 0):
        return None
    judge = RECORDED_SECANT_N_PER_CM
    secant = force_n / compression_m / 100.0  # N/cm
    if not judge.doubtful(secant):
        return None
    force, length = readings["force"], readings["length"]
    forces, lengths = RECORDED_PEAK_FORCE_N, RECORDED_PEAK_COMPRESSION_M

    def fix(reading: Reading, kind: str, ok: Any) -> str | None:
        unit = suggest_unit(
            1.0 / reading.si, SUGGESTED_UNITS[kind], to_value=lambda k: k, ok=ok, target=1.0
        )
        return None if unit == reading.unit else unit

    def force_ok(k: float) -> bool:
        return judge.plausible(force_n * k / compression_m / 100) and forces.plausible(force_n * k)

    def length_ok(k: float) -> bool:
        return judge.plausible(force_n / (compression_m * k) / 100) and lengths.plausible(
            compression_m * k
        )

    force_fix = fix(force, "force", force_ok)
    length_fix = fix(length, "length", length_ok)
    fixes = [f"the force in {force_fix}"] if force_fix else []
    fixes += [f"the compression in {length_fix}"] if length_fix else []
    clause = f"; plausible with {' or '.join(fixes)}: is a unit right?" if fixes else ""
    flag = COMPRESSION_UNIT_DOUBTFUL if length_fix and not force_fix else judge.flag
    return (
        flag,
        f"{force.what} / {length.what}: secant stiffness {secant:.3g} N/cm (peak force "
        f"{force_n:.3g} N at {compression_m * 1e3:.3g} mm) is above {judge.doubt_high:g} N/cm "
        f"for a soft object{clause or '; is a unit right?'}",
        {"secant_n_per_cm": secant},
    )


def implied_damping_ratio(
    deformability_n_per_cm: object, damping_ns_per_cm: object, weight_n: object
) -> float:
    """ζ = λ / (2 √(D m)), m = W / g, SI inside (NaN when an input is missing or D, W ≤ 0)."""
    from deformctl.units import GRAVITY_M_S2, N_PER_CM, NS_PER_CM

    try:
        d, lam, w = (
            float(v)  # type: ignore[arg-type]
            for v in (deformability_n_per_cm, damping_ns_per_cm, weight_n)
        )
    except (TypeError, ValueError):
        return math.nan
    if not (math.isfinite(d) and math.isfinite(lam) and math.isfinite(w) and d > 0 and w > 0):
        return math.nan
    return lam * NS_PER_CM / (2.0 * math.sqrt(d * N_PER_CM * w / GRAVITY_M_S2))


def damping_ratio_doubt(zeta: float, *, time_unit_stated: bool) -> tuple[str, str] | None:
    """The flag and the text of an implausible implied damping ratio, or None.

    ζ above :data:`MAX_DAMPING_RATIO` (:data:`~deformctl.quantities.IMPLIED_DAMPING_RATIO`):
    ``time_unit_doubtful`` when the recording's time unit was not stated, else
    ``damping_ratio_implausible``; the text names the factor (10³, 10⁶) by which shorter time
    stamps would make ζ plausible, and the slip it is when the stamps were read as seconds (ms,
    µs): λ scales with the time unit, D does not. (The coefficients row does not keep the
    recording's time unit, so the slip is named from seconds.)
    """
    judge = IMPLIED_DAMPING_RATIO
    if math.isnan(zeta) or not judge.doubtful(zeta):  # an infinite ζ is doubtful too
        return None
    unit = suggest_unit(
        zeta, SUGGESTED_UNITS["time"], to_value=lambda z: z, ok=judge.plausible, target=judge.target
    )
    if unit and unit != "s":
        times = round(1.0 / SUGGESTED_UNITS["time"][unit])
        hint = f"plausible with time stamps {times:,} times shorter ({unit} read as s?)"
    else:
        hint = "no time unit fixes it"
    flag = judge.flag if time_unit_stated else TIME_UNIT_DOUBTFUL
    stated = "" if time_unit_stated else "time unit not stated and "
    return flag, (
        f"{stated}implied damping ratio ζ = λ / (2 √(D m)) = {zeta:.3g} is above "
        f"{judge.doubt_high:g}; {hint}: is the time unit right?"
    )
