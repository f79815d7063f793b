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
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from os import PathLike

import numpy as np

from deformctl.errors import InputDataError
from deformctl.series import FloatArray

#: Sample rates outside this range (Hz) mean a wrong time unit: 1 Hz–100 kHz spans every force
#: sensor and pose topic we know of; a 1 kHz log read in the wrong unit lands at 1 Hz or 1 MHz.
MIN_RATE_HZ = 1.0
MAX_RATE_HZ = 100_000.0
#: A peak force above this (N) means a wrong force unit (grippers and testing machines for soft
#: objects stay far below 10 kN).
MAX_PEAK_FORCE_N = 10_000.0
#: A peak compression above this (m) means a wrong length unit, whatever the object.
MAX_COMPRESSION_M = 0.5
#: The force is "mostly on another axis" when another component's range (1st to 99th
#: percentile) is more than this multiple of the chosen axis's range.
AXIS_DOMINANCE = 2.0
#: The compression sign is judged on the samples whose force is at least this fraction of the
#: peak: where the object is squeezed, d must be positive.
SIGN_FORCE_FRAC = 0.5
#: The largest plausible L_f / F_w. The lifting force of a deformable object is
#: L_f = F_w + F_d; L_f / F_w is about 2 for an undamped object and falls with damping
#: (docs/explanation/model.md), and the paper's objects lie below 2. Five times that is a unit or
#: catalog mistake (a weight in grams, a μ of 0.005), not an object: ``lift``'s default force
#: ceiling (:mod:`deformctl.lift.ceiling`), the index table's refusal of absurd rows
#: (:func:`deformctl.table.impossible_rows`) and a prediction's plausibility all use it.
MAX_LIFT_RATIO = 10.0
#: Suggested units aim at these magnitudes: a 1 kHz sensor, a 10 N squeeze, a compression of a
#: tenth of the object (or 1 cm when its size is unknown).
_TARGET_RATE_HZ = 1000.0
_TARGET_FORCE_N = 10.0
_TARGET_STRAIN = 0.1
_TARGET_COMPRESSION_M = 0.01

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


# -- the "too small" side (issue 34 point 1): flags, since a small reading can be right ---------

#: A peak force below this (N) is doubtful: a gripper squeeze or a testing machine on a soft
#: object loads it with at least 50 mN; a kN column read as N (or N values under an ``mN`` label)
#: lands 1000 times lower.
MIN_PEAK_FORCE_N = 0.05
#: A peak force above this (N, and up to :data:`MAX_PEAK_FORCE_N`, refused beyond) is doubtful:
#: N values under a ``kN`` label land 1000 times higher. The shared silicone phantoms, squeezed
#: 20 mm on a testing machine, peak at up to 1151 N (EF50_0T_A2.csv): 3 kN leaves them a margin
#: of 2.6; N values under ``kN`` with a peak below 3 N are not caught (no reading tells them).
DOUBTFUL_PEAK_FORCE_N = 3000.0
#: A peak compression below this (m) is doubtful: metres under an ``mm`` label land here.
MIN_PEAK_COMPRESSION_M = 2e-5
#: With no time unit stated, a sample rate below this (Hz) is doubtful: a kHz logger's ms
#: stamps read as seconds land at a few Hz.
MIN_UNSTATED_RATE_HZ = 10.0
DOUBT_FLAGS = ("force_unit_doubtful", "compression_unit_doubtful", "time_unit_doubtful")


def unit_doubts(
    *,
    rate_hz: float,
    time_unit_stated: bool,
    peak_force_n: float,
    peak_compression_m: float,
    suggest: Callable[[str, float], str | None],
) -> list[tuple[str, str, dict[str, float]]]:
    """The "too small" (and "rather large") side of the plausibility checks, as flags.

    Args:
        rate_hz: the force's sample rate.
        time_unit_stated: the time column's unit was given (header, units row, ``--units``).
        peak_force_n, peak_compression_m: the recording's peaks, SI.
        suggest: ``suggest(kind, value)`` -> the unit under which ``value`` (kind ``time``
            (a sample interval, s), ``force`` or ``length``) would be plausible, or None.

    Returns:
        ``(flag, line, numbers)`` per doubt; each line names the unit that would make the value
        plausible. Empty for a plausible recording.
    """
    out: list[tuple[str, str, dict[str, float]]] = []

    def unit_clause(kind: str, value: float) -> str:
        unit = suggest(kind, value)
        return f"; plausible in {unit}: is the unit right?" if unit else "; is the unit right?"

    if not time_unit_stated and math.isfinite(rate_hz) and rate_hz < MIN_UNSTATED_RATE_HZ:
        out.append((
            "time_unit_doubtful",
            f"time unit not stated and the sample rate is {rate_hz:.3g} Hz (below "
            f"{MIN_UNSTATED_RATE_HZ:g} Hz){unit_clause('time', 1.0 / rate_hz)}",
            {"rate_hz": rate_hz},
        ))  # fmt: skip
    if math.isfinite(peak_force_n) and 0 < peak_force_n < MIN_PEAK_FORCE_N:
        out.append((
            "force_unit_doubtful",
            f"peak force {peak_force_n:.3g} N is below {MIN_PEAK_FORCE_N * 1e3:g} mN"
            f"{unit_clause('force', peak_force_n)}",
            {"peak_force_n": peak_force_n},
        ))  # fmt: skip
    elif DOUBTFUL_PEAK_FORCE_N < peak_force_n <= MAX_PEAK_FORCE_N:
        out.append((
            "force_unit_doubtful",
            f"peak force {peak_force_n:.3g} N is above {DOUBTFUL_PEAK_FORCE_N / 1e3:g} kN for a "
            f"soft object{unit_clause('force', peak_force_n)}",
            {"peak_force_n": peak_force_n},
        ))  # fmt: skip
    if math.isfinite(peak_compression_m) and 0 < peak_compression_m < MIN_PEAK_COMPRESSION_M:
        out.append((
            "compression_unit_doubtful",
            f"peak compression {peak_compression_m * 1e6:.3g} µm is below "
            f"{MIN_PEAK_COMPRESSION_M * 1e6:g} µm{unit_clause('length', peak_compression_m)}",
            {"peak_compression_m": peak_compression_m},
        ))  # fmt: skip
    return out
