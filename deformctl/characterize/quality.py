"""When D and λ are doubtful: the quality flags of a coefficients row and what is done about them.

A coefficient a robot will act on must be either right or visibly doubtful. Every fit
(:mod:`deformctl.characterize`) carries its diagnostics (R², standard errors, samples, loading
range, the damping excitation and design condition) and a ``quality`` column: ``ok``, or a comma
list of the flags below, in this order. The thresholds are product decisions, chosen by
measurement on synthetic logs (clean, noisy, with preload, constant-rate, rupture, swapped columns,
wrong sign, wrong units; numbers in each constant's docstring) and stated here once; the README's
"When the numbers are doubtful" section and ``characterize --help`` quote them from here.

================================ ==============================================================
``negative_stiffness``           D ≤ 0: always an error unless ``--allow-flagged``
``negative_damping``             λ below 0 (any amount: λ is never negative with ``ok``; the
                                 lsq fits are bounded, so this is the paper estimator's)
``damping_at_bound``             ``--method paper`` rows written before v3: ``--constrain-damping``
                                 held λ at 0 (lsq fits say ``at_bound``)
``damping_unidentifiable``       λ cannot be told from a constant force or from D, or the
                                 squeezes move at a single speed without a hold (λ = NaN; the
                                 row gives ``hysteresis_energy_j`` when a loop closes); see
                                 :func:`damping_identifiable` and
                                 :func:`deformctl.characterize.stiffness.speed_summary`;
                                 ``--method paper``: monotonic loading
                                 (:data:`PAPER_MONOTONIC_FRAC`)
``low_r2``                       R² below :data:`LOW_R2`
``few_samples``                  fewer than :data:`FEW_SAMPLES_WINDOWS` SG windows of samples
``rupture``                      a squeeze ruptured (it is fitted up to the rupture only)
``at_bound``                     a parameter of the chosen law sits at a physical bound
                                 (stiffness or damping 0, HC's n at 1 or 3, SLS's τ at one
                                 window or ten recordings; ``params_at_bound`` names them)
``nonlinear_stiffness``          the loading curve's tangent stiffness varies by more than
                                 :data:`deformctl.characterize.stiffness.NONLINEAR_RATIO` ×, or
                                 falls over a stretch (a slip, a yield, a buckling dip:
                                 ``tangent_stiffness_spread`` is then null): D is the secant at
                                 ``operating_force_n`` only
``relaxation``                   the force decayed smoothly at constant compression (stress
                                 relaxation, not rupture; ``rupture.find_relaxation``)
``secant_misfit``                where D is stated the law misses the recording by more than
                                 :data:`SECANT_MISFIT_FRAC` of the operating force
``below_squeezes``               a stiffening law (``hc``, ``exp``) states D and λ at a force
                                 with fewer than :data:`BELOW_SQUEEZES_SHARE` of the loading
                                 samples at or below it: the squeezes pass it too fast to say
                                 (squeeze to a few times that force)
``damping_ratio_implausible``    the implied damping ratio ζ = λ / (2 √(D m)) is above 1000
                                 (:data:`deformctl.quantities.IMPLIED_DAMPING_RATIO`) though the
                                 recording's time unit was stated: the line names the time unit
                                 that would make it plausible (with no time unit stated the flag
                                 is ``time_unit_doubtful``)
``not_finite``                   a computed column came out infinite (a defect of an
                                 estimator): it is written as null (:func:`finite_row`)
``logging_gap``, ``coarse_force``, the recording's defects, found by ``measure`` and stored in
``force_lag``, ...               the squeeze log (:mod:`deformctl.squeeze.flags`)
================================ ==============================================================

Policy (:func:`enforce`): each flagged object gives one warning line naming the flags and their
numbers; ``strict`` turns any flag into an error (exit 65, nothing written); negative D is an
error unless ``allow_flagged``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from deformctl.errors import InputDataError, UsageError
from deformctl.squeeze.flags import LAG_ESTIMATED, RECORDING_FLAGS, TIME_UNIT_DOUBTFUL

if TYPE_CHECKING:  # pragma: no cover - a table is handed in; this module does not need pandas
    import pandas as pd

NEGATIVE_STIFFNESS = "negative_stiffness"
NEGATIVE_DAMPING = "negative_damping"
DAMPING_AT_BOUND = "damping_at_bound"
DAMPING_UNIDENTIFIABLE = "damping_unidentifiable"
LOW_R2_FLAG = "low_r2"
FEW_SAMPLES = "few_samples"
RUPTURE = "rupture"
AT_BOUND = "at_bound"
NONLINEAR_STIFFNESS = "nonlinear_stiffness"
RELAXATION = "relaxation"
SECANT_MISFIT = "secant_misfit"
BELOW_SQUEEZES = "below_squeezes"
DAMPING_RATIO_IMPLAUSIBLE = "damping_ratio_implausible"
NOT_FINITE = "not_finite"
#: Every flag, in the order ``quality`` lists them.
FLAGS: tuple[str, ...] = (
    NEGATIVE_STIFFNESS,
    NEGATIVE_DAMPING,
    DAMPING_AT_BOUND,
    DAMPING_UNIDENTIFIABLE,
    LOW_R2_FLAG,
    FEW_SAMPLES,
    RUPTURE,
    AT_BOUND,
    NONLINEAR_STIFFNESS,
    RELAXATION,
    SECANT_MISFIT,
    BELOW_SQUEEZES,
    DAMPING_RATIO_IMPLAUSIBLE,
    NOT_FINITE,
    *RECORDING_FLAGS,
)
OK = "ok"

#: ``secant_misfit`` when, where D is stated, the law misses the recording's window-mean force by
#: more than this fraction of the operating force (``secant_residual_frac``). Measured: synthetic
#: squeezes of each law within 0.3 % at the median loading force and at a tenth of it; the 38
#: shared silicone phantoms (Hunt-Crossley, n at its bound 3) -0.6 to +9.6 % at the median
#: loading force, 129 to 683 % in size at a tenth of it (all 38 flagged there).
SECANT_MISFIT_FRAC = 0.25
#: ``below_squeezes`` when a stiffening law's operating force has fewer than this share of the
#: loading samples at or below it (three linear force ramps to 0.5, 0.75 and 1 × a peak P give
#: 1.44 F/P). Measured on a light, stiff Hunt–Crossley object of the simulator (D 30 N/cm at
#: F_w = 0.65 N, n 2.92), squeezed to P = 1.5 / 3 / 10 / 20 / 500 F_w (share 0.85 / 0.48 / 0.14 /
#: 0.07 / 0.003): D at F_w +0.0 / +1.3 / +71 / +170 / +2,100 %. A slow squeeze stated at its
#: median loading force has half its samples below it. A linear law's D does not depend on the
#: force, so its rows are not judged.
BELOW_SQUEEZES_SHARE = 0.25
#: ``low_r2`` below this R²: more than 10 % of the force variance is not Kelvin–Voigt. Measured:
#: clean and 1 %-noise synthetic squeezes ≥ 0.99, the simulator's Table II objects ≥ 0.9997 and a
#: 73-object population ≥ 0.98, the simulator with 0.01 N + 0.05 mm noise 0.90–0.97; a force that
#: is mostly sensor noise (a wrong wrench axis: 2 % cross-talk) 0.33, a rupture fitted whole −0.7
#: to −0.9 (D then falls to a tenth).
LOW_R2 = 0.9
#: Until schema v3, ``negative_damping`` needed λ below −0.1 N·s/cm and more than 2 standard
#: errors below 0; 11 of 14 force-controlled fruit loadings then wrote λ < 0 with ``ok``. Since
#: v3 any negative λ is flagged (these constants are 0 and kept for old callers).
NEGATIVE_DAMPING_ATOL_NS_PER_CM = 0.0
NEGATIVE_DAMPING_SE_MULT = 0.0
#: ``damping_unidentifiable`` when less than this share of the rate's mean square is independent
#: of a constant force and of d (``damping_excitation``) ... Measured: constant-rate loadings of a
#: testing machine 0.000–0.043 (even with a 2 s acceleration ramp), a force ramp without a hold
#: 0.0004–0.05; the simulator ≥ 0.076 (its most damped object, λ/D = 3 s), synthetic squeezes
#: ≥ 0.39, a load–unload cycle 1.0.
DAMPING_EXCITATION_MIN = 0.05
#: ... and allowing a preload (an intercept) moves λ by more than this fraction. Guards the slow,
#: heavily damped squeezes whose rate is nearly constant but whose λ is well determined (a 1 s ramp
#: and hold at λ/D = 3 s: excitation 0.04, λ moves 1.8 %); on constant-rate loadings λ moves
#: 55–133 %.
DAMPING_PRELOAD_SENSITIVITY = 0.1
#: ``--method paper``: a squeeze whose rate has the other sign on fewer than this share of its
#: damping samples is a monotonic loading; there the residual ratio ``(f − D d)/d'`` has the sign
#: of ``f/d − D``, whose median is D by construction, so λ is pinned near 0 (λ = 0.000 on the
#: simulator's force ramps of its most damped objects). Its λ is not used.
PAPER_MONOTONIC_FRAC = 0.05
#: ``few_samples`` below this many SG windows of samples: with fewer independent windows the fit
#: is dominated by smoothing bias (measured, one haversine squeeze at 1 kHz: 1.5 windows λ +7 %
#: = 10 standard errors, 2.5 windows +1.6 %, 4 windows +0.3 %, under one standard error).
FEW_SAMPLES_WINDOWS = 4.0


def damping_identifiable(excitation: float, preload_sensitivity: float) -> bool:
    """Whether λ can be told from a constant force and from D.

    A constant rate (a testing machine's crosshead) makes ``λ d'`` a constant force,
    indistinguishable from a preload; a rate that follows ``d`` (pure creep) makes it part of
    ``D d`` and the preload. λ is unidentifiable when the rate's share independent of a constant
    and of d (``excitation``) is below :data:`DAMPING_EXCITATION_MIN` and allowing a preload moves
    λ by more than :data:`DAMPING_PRELOAD_SENSITIVITY` (relative).
    """
    if not math.isfinite(excitation):
        return False
    return not (
        excitation < DAMPING_EXCITATION_MIN
        and not preload_sensitivity <= DAMPING_PRELOAD_SENSITIVITY
    )


def assess(
    *,
    deformability_n_per_cm: float,
    damping_ns_per_cm: float,
    damping_se_ns_per_cm: float,
    r2: float,
    n_samples: int,
    window_samples: int,
    damping_unidentifiable: bool = False,
    damping_bound_active: bool = False,
    ruptures: int = 0,
    at_bound: bool = False,
    nonlinear_stiffness: bool = False,
    relaxations: int = 0,
    secant_misfit: bool = False,
    below_squeezes: bool = False,
) -> tuple[str, ...]:
    """The flags of one fit, in :data:`FLAGS` order (empty: ok)."""
    flags: list[str] = []
    if not deformability_n_per_cm > 0:
        flags.append(NEGATIVE_STIFFNESS)
    del damping_se_ns_per_cm  # a negative λ is flagged whatever its standard error
    if math.isfinite(damping_ns_per_cm) and damping_ns_per_cm < 0:
        flags.append(NEGATIVE_DAMPING)
    if damping_bound_active:
        flags.append(DAMPING_AT_BOUND)
    if damping_unidentifiable:
        flags.append(DAMPING_UNIDENTIFIABLE)
    if not r2 >= LOW_R2:
        flags.append(LOW_R2_FLAG)
    if n_samples < FEW_SAMPLES_WINDOWS * window_samples:
        flags.append(FEW_SAMPLES)
    if ruptures > 0:
        flags.append(RUPTURE)
    if at_bound:
        flags.append(AT_BOUND)
    if nonlinear_stiffness:
        flags.append(NONLINEAR_STIFFNESS)
    if relaxations > 0:
        flags.append(RELAXATION)
    if secant_misfit:
        flags.append(SECANT_MISFIT)
    if below_squeezes:
        flags.append(BELOW_SQUEEZES)
    return tuple(flags)


def with_damping_ratio_flag(quality: str, row: Mapping[str, Any], obj: Mapping[str, Any]) -> str:
    """``quality`` with ``damping_ratio_implausible`` (or ``time_unit_doubtful`` when the
    recording's time unit was not stated) when the implied damping ratio of ``row``'s D and λ
    and the object's weight is above 1000 (:func:`deformctl.plausibility.damping_ratio_doubt`)."""
    # imported here: plausibility brings numpy, and every --help reads this module's policy
    # check (tests/cli/test_startup.py)
    from deformctl.plausibility import damping_ratio_doubt, implied_damping_ratio

    zeta = implied_damping_ratio(
        row.get("deformability_n_per_cm"), row.get("damping_ns_per_cm"), obj.get("weight_n")
    )
    doubt = damping_ratio_doubt(zeta, time_unit_stated=time_unit_stated(obj))
    if doubt is None:
        return quality
    flags = list(parse_quality(quality))
    return quality_text(flags if doubt[0] in flags else [*flags, doubt[0]])


def time_unit_stated(obj: Mapping[str, Any]) -> bool:
    """Whether the recording's time unit was known: False for a CSV export whose time column's
    unit was assumed (no header unit, units row or ``--units``), True otherwise (bags and logs
    have stamps in ns; the simulator its own clock)."""
    if obj.get("source") != "csv":
        return True
    csv = obj.get("csv")
    try:
        return str(csv["columns"]["time"]["unit_from"]) != "default"  # type: ignore[index]
    except (KeyError, TypeError):
        return False  # a CSV recording that does not say: not known


def finite_row(row: dict[str, Any]) -> dict[str, Any]:
    """``row`` with every infinite number written as null (NaN) and, when there was one, the
    ``not_finite`` flag in its quality: a computed
    column is finite or null with a flag, never a value the table's writer refuses."""
    bad = [
        k
        for k, v in row.items()
        if isinstance(v, float | int) and not isinstance(v, bool) and math.isinf(float(v))
    ]
    if not bad:
        return row
    out = {**row, **dict.fromkeys(bad, math.nan)}
    flags = list(parse_quality(out.get("quality")))
    if NOT_FINITE not in flags:
        flags.append(NOT_FINITE)
    out["quality"] = quality_text(
        [f for f in FLAGS if f in flags] + [f for f in flags if f not in FLAGS]
    )
    return out


def with_recording_flags(quality: str, recording_flags: object) -> str:
    """``quality`` with the recording's flags (a squeeze log object's ``recording_flags``)."""
    extra = (
        [f for f in recording_flags if f in RECORDING_FLAGS]
        if isinstance(recording_flags, list | tuple)
        else []
    )
    flags = list(parse_quality(quality))
    return quality_text([*flags, *(f for f in extra if f not in flags)])


def quality_text(flags: Sequence[str]) -> str:
    """The ``quality`` column: ``ok`` or the flags joined by commas."""
    return ",".join(flags) if flags else OK


def parse_quality(text: object) -> tuple[str, ...]:
    """The flags of a ``quality`` value (``ok``, missing or empty: none)."""
    if not isinstance(text, str) or text.strip() in ("", OK):
        return ()
    return tuple(part.strip() for part in text.split(",") if part.strip())


def _num(value: Any, fmt: str) -> str:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "?"
    return format(v, fmt) if math.isfinite(v) else "NaN"


def _finite(value: Any) -> bool:
    try:
        return math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


def _pm(value: Any, se: Any) -> str:
    text = _num(value, ".3g")
    try:
        ok = math.isfinite(float(se))
    except (TypeError, ValueError):
        ok = False
    return f"{text} ± {_num(se, '.2g')}" if ok else text


def describe_flag(flag: str, row: Mapping[str, Any]) -> str:
    """One flag with the numbers behind it, e.g. ``low_r2 (R² = 0.41 < 0.9)``."""
    if flag == NEGATIVE_STIFFNESS:
        return f"{flag} (D = {_num(row.get('deformability_n_per_cm'), '.3g')} N/cm ≤ 0)"
    if flag == NEGATIVE_DAMPING:
        lam = _pm(row.get("damping_ns_per_cm"), row.get("damping_se_ns_per_cm"))
        return f"{flag} (λ = {lam} N·s/cm < 0)"
    if flag == DAMPING_AT_BOUND:
        return f"{flag} (λ held at 0 by --constrain-damping; the free fit is negative)"
    if flag == DAMPING_UNIDENTIFIABLE:
        if row.get("method") == "paper":
            return f"{flag} (not identifiable by the paper estimator: monotonic loading)"
        exc = _num(row.get("damping_excitation"), ".2g")
        energy = _num(row.get("hysteresis_energy_j"), ".3g")
        loop = f"; the loop dissipates {energy} J" if energy not in ("NaN", "?") else ""
        if row.get("force_lag_source") == LAG_ESTIMATED:
            return (
                f"{flag} (λ is not determined: the force was shifted by the lag measure "
                f"--lag-s auto estimated, {_num(row.get('force_lag_s'), '.3g')} s, which is the "
                "latency less λ/D and takes λ with it; a latency known from the rig goes to "
                f"measure --lag-s SECONDS{loop})"
            )
        excitation = row.get("damping_excitation")
        if isinstance(excitation, int | float) and excitation >= DAMPING_EXCITATION_MIN:
            lag = row.get("lag_s")
            lagged = isinstance(lag, int | float) and lag > 0
            rests = (
                f", or λ rests on the fitted force lag of {_num(lag, '.3g')} s (a latency known "
                "from the rig goes to measure --lag-s SECONDS)"
                if lagged
                else ""
            )
            return (
                f"{flag} (λ is not determined: a single speed without a hold or a standard "
                f"error too large{rests}{loop})"
            )
        return (
            f"{flag} (λ cannot be told from a preload, from D or from a rate-independent "
            f"force: a single speed without a hold, or rate excitation {exc} < "
            f"{DAMPING_EXCITATION_MIN:g}{loop})"
        )
    if flag == LOW_R2_FLAG:
        return f"{flag} (R² = {_num(row.get('r2'), '.3g')} < {LOW_R2:g})"
    if flag == FEW_SAMPLES:
        return (
            f"{flag} ({row.get('n_samples')} samples < {FEW_SAMPLES_WINDOWS:g} windows of "
            f"{row.get('window_samples')})"
        )
    if flag in (DAMPING_RATIO_IMPLAUSIBLE, TIME_UNIT_DOUBTFUL):
        from deformctl.plausibility import damping_ratio_doubt, implied_damping_ratio

        zeta = implied_damping_ratio(
            row.get("deformability_n_per_cm"), row.get("damping_ns_per_cm"), row.get("weight_n")
        )
        doubt = damping_ratio_doubt(zeta, time_unit_stated=flag == DAMPING_RATIO_IMPLAUSIBLE)
        if doubt is not None:
            return f"{flag} ({doubt[1]})"
    if flag in RECORDING_FLAGS:
        return f"{flag} ({RECORDING_FLAGS[flag]}; found by measure, details in the squeeze log)"
    if flag == RUPTURE:
        count = row.get("ruptures")
        return (
            f"{flag} ({count} squeeze(s); first at {_num(row.get('rupture_time_s'), '.3g')} s, "
            f"{_num(row.get('rupture_force_n'), '.3g')} N; fitted up to it)"
        )
    if flag == AT_BOUND:
        which = row.get("params_at_bound") or "a parameter"
        return f"{flag} ({which} of the {row.get('model', '?')} law at its bound)"
    if flag == NONLINEAR_STIFFNESS and not _finite(row.get("tangent_stiffness_spread")):
        return (
            f"{flag} (the loading curve falls or is flat over a stretch: a slip, a yield or a "
            f"buckling dip before the peak; tangent_stiffness_spread is null; small-strain "
            f"{_num(row.get('deformability_small_strain_n_per_cm'), '.3g')} N/cm; D is the "
            f"secant at {_num(row.get('operating_force_n'), '.3g')} N)"
        )
    if flag == NOT_FINITE:
        return (
            f"{flag} (a computed column came out infinite: written as null; a defect of an "
            "estimator, please report it)"
        )
    if flag == NONLINEAR_STIFFNESS:
        return (
            f"{flag} (tangent stiffness varies {_num(row.get('tangent_stiffness_spread'), '.3g')}× "
            f"over the loading; small-strain "
            f"{_num(row.get('deformability_small_strain_n_per_cm'), '.3g')} N/cm, stiffening "
            f"ratio {_num(row.get('stiffening_ratio'), '.3g')}; D is the secant at "
            f"{_num(row.get('operating_force_n'), '.3g')} N)"
        )
    if flag == RELAXATION:
        drop = row.get("relaxation_force_drop_frac")
        pct = _num(100.0 * float(drop), ".3g") if isinstance(drop, int | float) else "?"
        return f"{flag} (the force fell {pct} % at constant compression: not a rupture)"
    if flag == SECANT_MISFIT:
        frac = row.get("secant_residual_frac")
        pct = _num(100.0 * float(frac), "+.3g") if isinstance(frac, int | float) else "?"
        return (
            f"{flag} (where D is stated, at {_num(row.get('operating_force_n'), '.3g')} N, the "
            f"recording's force is {pct} % of that force off the {row.get('model', '?')} law's: "
            "D is the recording's secant, the law's λ and curve do not hold there)"
        )
    if flag == BELOW_SQUEEZES:
        return (
            f"{flag} (D and λ are stated at {_num(row.get('operating_force_n'), '.3g')} N, with "
            f"fewer than {100 * BELOW_SQUEEZES_SHARE:g} % of the loading samples at or below it "
            f"(peak {_num(row.get('force_max_n'), '.3g')} N): the {row.get('model', '?')} law is "
            "extrapolated there; squeeze to a few times that force)"
        )
    return flag


def describe_row(row: Mapping[str, Any]) -> str:
    """Every flag of a coefficients row with its numbers, comma-separated ('' when ok)."""
    return ", ".join(describe_flag(f, row) for f in parse_quality(row.get("quality")))


def check_policy(strict: bool, allow_flagged: bool) -> None:
    """Refuse ``--strict`` with ``--allow-flagged`` (one fails on any flag, one writes them).

    Raises:
        UsageError: both given (exit 2).
    """
    if strict and allow_flagged:
        raise UsageError("give --strict or --allow-flagged, not both")


def enforce(
    table: pd.DataFrame,
    *,
    strict: bool = False,
    allow_flagged: bool = False,
    path: str | None = None,
) -> list[str]:
    """Apply the policy to a coefficients table; the warning lines of its flagged objects.

    Args:
        table: coefficients rows with ``object_id`` and ``quality`` (and the numbers the flags
            name); rows without ``quality`` (tables written before it existed) are not judged.
        strict: any flag is an error.
        allow_flagged: write objects with negative D (flagged) instead of refusing them.
        path: the squeeze log, named in every line.

    Returns:
        One line per flagged object, ``<path>: object 'X': <flags with numbers>``.

    Raises:
        InputDataError: ``strict`` and an object is flagged, or an object has negative D and not
            ``allow_flagged`` (exit 65); the message names the first such object.
        UsageError: both ``strict`` and ``allow_flagged``.
    """
    check_policy(strict, allow_flagged)
    if "quality" not in table.columns:
        return []
    lines: list[str] = []
    flagged: list[tuple[str, str]] = []
    negative: list[tuple[str, str]] = []
    for row in table.to_dict("records"):
        flags = parse_quality(row.get("quality"))
        if not flags:
            continue
        oid, text = str(row["object_id"]), describe_row(row)
        flagged.append((oid, text))
        if NEGATIVE_STIFFNESS in flags:
            negative.append((oid, text + _why_not_positive(row)))
        lines.append(f"{path}: object {oid!r}: {text}" if path else f"object {oid!r}: {text}")
    if strict and flagged:
        oid, text = flagged[0]
        more = f"; {len(flagged) - 1} more flagged object(s)" if len(flagged) > 1 else ""
        raise InputDataError(f"--strict: object {oid!r} is flagged: {text}{more}", path=path)
    if negative and not allow_flagged:
        oid, text = negative[0]
        more = f"; {len(negative) - 1} more" if len(negative) > 1 else ""
        raise InputDataError(
            f"object {oid!r}: {text} (pass --allow-flagged to write it anyway){more}",
            path=path,
        )
    return lines


def _why_not_positive(row: Mapping[str, Any]) -> str:
    """Why D ≤ 0: a stiffness held at its bound 0 is a law that does not fit the loading (a
    relaxation, a collapse), not a sign; a fitted negative D is a sign."""
    at_bound = str(row.get("params_at_bound") or "")
    if "stiffness" in at_bound and float(row.get("deformability_n_per_cm") or 0.0) == 0.0:
        return (
            f": the {row.get('model', '?')} law's stiffness sits at its bound 0, so no stiffness "
            "was found in the loading (a relaxation or a collapse rather than a squeeze?)"
        )
    return ": the force or the compression has the wrong sign"


def thresholds_help() -> str:
    """The flags and thresholds in one paragraph (``characterize --help``)."""
    return (
        "Quality flags: negative_stiffness (D <= 0; exit 65 unless --allow-flagged), "
        "negative_damping (λ < 0), damping_at_bound (old tables: --constrain-damping held λ at "
        f"0), damping_unidentifiable (λ = NaN: a single speed without a hold, or rate "
        f"excitation < {DAMPING_EXCITATION_MIN:g} and a preload would move λ by > "
        f"{100 * DAMPING_PRELOAD_SENSITIVITY:g} %; --method paper: a monotonic loading, the "
        f"rate of the other sign on < {100 * PAPER_MONOTONIC_FRAC:g} % of its samples), low_r2 "
        f"(R² < {LOW_R2:g}), few_samples (< {FEW_SAMPLES_WINDOWS:g} windows of samples), "
        "rupture (a squeeze ruptured; fitted up to it), at_bound (a parameter of the chosen "
        "law at its bound), nonlinear_stiffness (the loading tangent stiffness varies by more "
        "than 2x, or falls over a stretch), relaxation (the force decayed at constant "
        "compression), secant_misfit "
        f"(where D is stated the law misses the recorded force by > "
        f"{100 * SECANT_MISFIT_FRAC:g} % of the operating force), below_squeezes (a stiffening "
        f"law states D with < {100 * BELOW_SQUEEZES_SHARE:g} % of the loading samples at or "
        "below its force), "
        "damping_ratio_implausible "
        "(ζ = λ / (2 √(D m)) > 1000 with a stated time unit), not_finite (a computed column "
        "came out infinite: written as null); the recording's defects found by "
        "measure: logging_gap, coarse_force, force_lag, energy_returned (a bag whose squeezes "
        "give energy back), and the unit doubts force_unit_doubtful "
        "(peak < 50 mN or > 3 kN, or secant > 5000 N/cm), compression_unit_doubtful (< 20 µm), "
        "time_unit_doubtful (no time unit, < 10 Hz or ζ > 1000)."
    )
