"""Every quantity a command or the library takes, with its one validation rule.

A :class:`Quantity` holds the bounds of one physical quantity or numeric option (μ, W, the sizes,
D, λ, the smoothing window, the squeeze ramp, the search's growth, ...), its unit, its parameter or
column name and its command-line flag. Every place that takes the value checks it here: the
options types the commands build and the library takes (:mod:`deformctl.lift.options`,
:mod:`deformctl.measure.options`, :mod:`deformctl.characterize.options`, ...), the catalog's row
parser (:mod:`deformctl.catalog`, whose bounds these are) and the population generator. So a bad
value gets the same rule and the same words whichever command, or library call, it came through:

* a flag or a library argument: :meth:`Quantity.check` raises a
  :class:`~deformctl.errors.UsageError` (exit 2), ``--friction-mu must be a number in [0.01, 3],
  got 0``;
* a value read from a file: :meth:`Quantity.check_data` raises an
  :class:`~deformctl.errors.InputDataError` (exit 65) naming where it was read, ``object 'A':
  friction_mu = 0 is outside its physical bounds [0.01, 3]``.

A quantity a recording gives (a sample rate, a peak force, a peak compression, a secant
stiffness, an implied damping ratio) has its plausible band here too (:class:`Plausible`, the
section at the end): :mod:`deformctl.plausibility` judges every recording against it.

The catalog's bounds (``schemas/catalog.columns.json`` states the same numbers, checked by
``tests/catalog/test_catalog.py``) are what a gripper can hold and the simulator can integrate:
outside them numpy sees underflow and overflow (a size of 1e-308 cm gives a non-finite lattice,
a weight of 1e-300 N or a damping of 1e308 N·s/cm an indefinite factor) or the run never ends (an
object of 1e6 cm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from os import PathLike
from typing import Any

from deformctl.errors import InputDataError, UsageError

__all__ = [
    "ALPHA_CM",
    "ARM_STIFFNESS_N_PER_CM",
    "AT_FORCE_N",
    "CALIBRATION_SIZE",
    "CG_TOLERANCE_M_S",
    "COVERAGE",
    "DAMPING_NS_PER_CM",
    "DT_S",
    "FORCE_THRESHOLD_FRAC",
    "FRICTION_MU",
    "GRIP_RAMP_S",
    "GRIP_SETTLE_S",
    "GROWTH",
    "HIDDEN_SIZE",
    "HOLD_S",
    "IMPLIED_DAMPING_RATIO",
    "L2_ALPHA",
    "LAG_S",
    "LAW_TRAIN_SIZE",
    "LIFT_ACCEL_M_S2",
    "LIFT_HEIGHT_M",
    "LIFT_HOLD_S",
    "LIFT_JERK_TIME_S",
    "LIFT_SPEED_M_S",
    "MARKER_ID",
    "MARKER_SIZE_CM",
    "MAX_ATTEMPTS",
    "MAX_FORCE_N",
    "MAX_ITER",
    "MAX_LIFT_RATIO",
    "MAX_SQUEEZE_STRAIN",
    "MEMORY_BUDGET_GIB",
    "MIN_GAP_S",
    "MIN_SHEAR_RETARDATION_S",
    "MIN_SQUEEZE_S",
    "NOISE_FORCE_N",
    "NOISE_POSITION_M",
    "PALM_MASS_KG",
    "PARTICLES_PER_SIDE",
    "PEAK_FORCE_N",
    "RAMP_S",
    "RECORDED_PEAK_COMPRESSION_M",
    "RECORDED_PEAK_FORCE_N",
    "RECORDED_RATE_HZ",
    "RECORDED_SECANT_N_PER_CM",
    "RELAXATION_TIME_S",
    "RELEASE_TIME_S",
    "RESTARTS",
    "RIG_TIMEOUT_S",
    "SCENE_HZ",
    "SEED",
    "SHEAR_DAMPING_RATIO",
    "SIM_SLIP_TOLERANCE_M",
    "SIZE_CM",
    "SLIP_TOLERANCE_M",
    "SQUARE_SIZE_CM",
    "SQUEEZES",
    "START_INTERPOLATE",
    "START_MARGIN",
    "STIFFNESS_EXPONENT",
    "STIFFNESS_N_PER_CM",
    "STRAIN",
    "TABLE_MU",
    "TOL",
    "TOLERANCE_REL",
    "TRAIN_SIZE",
    "WEIGHT_N",
    "WINDOW_S",
    "Plausible",
    "Quantity",
]


def _number_text(value: Any) -> str:
    """``0``, ``0.5``, ``nan``, ``1e+308``; a non-number as its repr."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return repr(value)
    return f"{value:g}" if isinstance(value, float) else str(value)


@dataclass(frozen=True)
class Quantity:
    """One quantity's validation rule: its bounds, its unit and its names.

    Attributes:
        name: the parameter and column name (``friction_mu``).
        flag: the command-line flag that gives it (``--friction-mu``).
        unit: the unit, as messages print it after a number (``" N"``, ``" s"``, ``""``).
        low, high: the bounds (``-inf`` / ``inf``: none).
        low_open, high_open: the bound itself is excluded (``> low`` rather than ``>= low``).
        integer: only whole numbers (counts).
        why: the reason for the rule, appended to the message when given.
    """

    name: str
    flag: str
    unit: str = ""
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    integer: bool = False
    why: str = ""

    @property
    def rule(self) -> str:
        """What a value must be: ``a number in [0.01, 3]``, ``a finite number > 0 s``, ..."""
        kind = "an integer" if self.integer else "a finite number"
        if math.isfinite(self.low) and math.isfinite(self.high):
            lb, rb = "(" if self.low_open else "[", ")" if self.high_open else "]"
            kind = "an integer" if self.integer else "a number"
            return f"{kind} in {lb}{self.low:g}, {self.high:g}{rb}{self.unit}"
        if math.isfinite(self.low):
            return f"{kind} {'>' if self.low_open else '>='} {self.low:g}{self.unit}"
        if math.isfinite(self.high):
            return f"{kind} {'<' if self.high_open else '<='} {self.high:g}{self.unit}"
        return kind

    def ok(self, value: Any) -> bool:
        """Whether ``value`` satisfies the rule (a real number, finite, within the bounds)."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        if self.integer and (not isinstance(value, int) and not float(value).is_integer()):
            return False
        v = float(value)
        if not math.isfinite(v):
            return False
        above = v > self.low if self.low_open else v >= self.low
        below = v < self.high if self.high_open else v <= self.high
        return above and below

    def problem(self, value: Any) -> str | None:
        """``must be <rule>, got <value>`` (with the reason), or None when the value is fine."""
        if self.ok(value):
            return None
        why = f" ({self.why})" if self.why else ""
        return f"must be {self.rule}{why}, got {_number_text(value)}"

    def check(self, value: Any, *, label: str | None = None) -> Any:
        """``value`` when it satisfies the rule.

        Args:
            value: the value given (a flag's or a library argument's).
            label: who gave it, for the message (default: the flag).

        Raises:
            UsageError: ``<flag> must be <rule>, got <value>`` (exit 2).
        """
        problem = self.problem(value)
        if problem is not None:
            raise UsageError(f"{label or self.flag} {problem}")
        return int(value) if self.integer else float(value)

    def check_optional(self, value: Any, *, label: str | None = None) -> Any:
        """:meth:`check`, with None (not given: the default applies) passed through."""
        return None if value is None else self.check(value, label=label)

    def data_problem(self, value: float, *, name: str | None = None) -> str | None:
        """``<name> = <value> is outside its physical bounds [low, high]``, or None.

        ``name``: the column read (default :attr:`name`; e.g. ``size_x_cm`` for a size).
        """
        if self.ok(value):
            return None
        column = name or self.name
        if math.isfinite(self.low) and math.isfinite(self.high):
            lb, rb = "(" if self.low_open else "[", ")" if self.high_open else "]"
            bounds = f"{lb}{self.low:g}, {self.high:g}{rb}"
            return f"{column} = {_number_text(value)} is outside its physical bounds {bounds}"
        return f"{column} {self.problem(value)}"

    def check_data(
        self,
        value: float,
        *,
        where: str,
        path: str | PathLike[str] | None = None,
        name: str | None = None,
    ) -> float:
        """``value`` when it satisfies the rule; else a data error naming where it was read.

        Raises:
            InputDataError: ``<where>: <name> = <value> is outside its physical bounds [...]``
                (exit 65).
        """
        problem = self.data_problem(value, name=name)
        if problem is not None:
            raise InputDataError(f"{where}: {problem}", path=path)
        return float(value)

    def check_range(self, value: Any, *, label: str | None = None) -> tuple[float, float]:
        """A ``(low, high)`` range of this quantity (low <= high, each within the rule).

        Raises:
            UsageError: not a pair of numbers, reversed, or an end outside the rule (exit 2).
        """
        who = label or self.flag
        try:
            low, high = (float(v) for v in value)
        except (TypeError, ValueError):
            what = f"{who} must be a (low, high) pair of numbers, got {value!r}"
            raise UsageError(what) from None
        for end in (low, high):
            self.check(end, label=who)
        if low > high:
            raise UsageError(f"{who} must be a range with low <= high, got ({low:g}, {high:g})")
        return low, high


# ---------------------------------------------------------------------------- the object
#: Bounds in the catalog's units (see the module docstring): the catalog columns, the flags of a
#: measured object (``measure --bag/--csv/--images``) and the population ranges.

#: μ: 0.01 <= μ <= 3. Above 3 no palm pair is plausible and F_w = W / (2μ) would promise a grip
#: no real contact gives. Below 0.01 no palm holds an object by friction: the slipperiest dry
#: pair, PTFE on PTFE, gives about 0.04, lubricated metal 0.05-0.1, wet ice about 0.02; only a
#: fluid film (a skate on ice, a journal bearing) goes lower, and a grip on it is no grip. There
#: F_w = W / (2μ) is at least 50 W: a μ of 1e-9 would ask a rig for 5e8 W (a catalog mistake, a
#: μ typed in percent or per mille, not an object).
FRICTION_MU = Quantity("friction_mu", "--friction-mu", "", 0.01, 3.0)
WEIGHT_N = Quantity("weight_n", "--weight-n", " N", 0.001, 5000.0)
SIZE_CM = Quantity("size_cm", "--size-cm", " cm", 0.1, 200.0)
#: D and λ, measured (``characterize``) or the simulator's material values (the catalog).
STIFFNESS_N_PER_CM = Quantity(
    "deformability_n_per_cm", "--deformability-n-per-cm", " N/cm", 0.01, 1e5
)
DAMPING_NS_PER_CM = Quantity("damping_ns_per_cm", "--damping-ns-per-cm", " N·s/cm", 0.0, 1e4)
#: n, the material's stiffness exponent (force ∝ compressionⁿ; 1: linear, Kelvin–Voigt): the
#: bounds of ``characterize``'s Hunt–Crossley fit (:data:`deformctl.characterize.laws.
#: HC_EXPONENT_BOUNDS`), and what the simulator's Hunt–Crossley lattice is calibrated for.
STIFFNESS_EXPONENT = Quantity("material_stiffness_exponent", "--stiffness-exponent", "", 1.0, 3.0)
#: k2, a standard linear solid's Maxwell arm spring (``characterize --model sls``'s
#: ``sls_arm_stiffness_n_per_cm``; 0: no arm, a Kelvin–Voigt material): D's bounds, 0 included.
ARM_STIFFNESS_N_PER_CM = Quantity(
    "material_arm_stiffness_n_per_cm", "--arm-stiffness-n-per-cm", " N/cm", 0.0, 1e5
)
#: τ, the Maxwell arm's relaxation time (``sls_relaxation_time_s``): above 0 (the simulator's
#: arms are stable for any τ), at most 10⁴ s (beyond a squeeze's hours the arm is a spring).
RELAXATION_TIME_S = Quantity(
    "material_relaxation_time_s", "--relaxation-time-s", " s", 0.0, 1e4, low_open=True
)

# ---------------------------------------------------------------------------- measuring
SQUEEZES = Quantity("squeezes", "--squeezes", "", 1, integer=True)
PEAK_FORCE_N = Quantity("peak_force_n", "--peak-force-n", " N", 0.0, low_open=True)
#: The default rule's static strain; the simulator also refuses one at or above its
#: densification limit (``SimSettings.max_squeeze_strain``).
STRAIN = Quantity("strain", "--strain", "", 0.0, 1.0, low_open=True, high_open=True)
RAMP_S = Quantity(
    "ramp_s", "--ramp-s", " s", 0.0, low_open=True, why="a force step does not excite the damping"
)
HOLD_S = Quantity("hold_s", "--hold-s", " s", 0.0)
NOISE_FORCE_N = Quantity("noise_force_n", "--noise-force-n", " N", 0.0)
NOISE_POSITION_M = Quantity("noise_position_m", "--noise-position-m", " m", 0.0)
FORCE_THRESHOLD_FRAC = Quantity(
    "force_threshold_frac", "force_threshold_frac", "", 0.0, 1.0, low_open=True, high_open=True
)
MIN_GAP_S = Quantity("min_gap_s", "min_gap_s", " s", 0.0)
MIN_SQUEEZE_S = Quantity("min_squeeze_s", "min_squeeze_s", " s", 0.0)
#: A CSV export's force lag (``measure --csv --lag-s``): larger shifts are a mistake.
LAG_S = Quantity("lag_s", "--lag-s", " s", -10.0, 10.0)
#: The memory a run may use (``measure --sim`` and ``--csv``, ``lift --sim``): the simulator's
#: settings and a CSV export's reader check it here.
MEMORY_BUDGET_GIB = Quantity("memory_budget_gib", "--memory-budget-gib", " GiB", 0.0, low_open=True)
#: The simulator's lattice spacing (``--alpha-cm``; None: from the particles per side).
ALPHA_CM = Quantity("alpha_cm", "--alpha-cm", " cm", 0.0, low_open=True)
#: The simulator's time step (``--dt-s``): below 10 µs a one-second squeeze is 100,000 steps of
#: recorded state (a 1e-12 s step would ask for hundreds of GiB), above 50 ms the contact and
#: slip events of a lift are not resolved.
DT_S = Quantity("dt_s", "--dt-s", " s", 1e-5, 0.05)
#: The scene's frame rate in a simulated run's log (``--scene-hz``, frames per simulated second;
#: 0: no scene); :func:`deformctl.scene.check_scene_hz` adds its ceiling, the step rate 1/dt.
SCENE_HZ = Quantity("scene_hz", "--scene-hz", " Hz", 0.0, why="0: no scene")
#: The simulator's other settings (:class:`deformctl.sim.SimSettings`, library only): the
#: densification strain, the lattice's particles along the longest side, the CG tolerance, the
#: shear share of the damping and its retardation floor, the palms' mass, the table's μ, and the
#: grip's ramp and settle before a lift.
MAX_SQUEEZE_STRAIN = Quantity("max_squeeze_strain", "max_squeeze_strain", "", 0.0, 1.0, True, True)
PARTICLES_PER_SIDE = Quantity("particles_per_side", "particles_per_side", "", 2, integer=True)
CG_TOLERANCE_M_S = Quantity("cg_tolerance_m_s", "cg_tolerance_m_s", " m/s", 0.0, low_open=True)
SHEAR_DAMPING_RATIO = Quantity(
    "shear_damping_ratio", "shear_damping_ratio", "", 0.0, 1.0, low_open=True
)
MIN_SHEAR_RETARDATION_S = Quantity(
    "min_shear_retardation_s", "min_shear_retardation_s", " s", 0.0, 1.0
)
PALM_MASS_KG = Quantity("palm_mass_kg", "palm_mass_kg", " kg", 0.0)
TABLE_MU = Quantity("table_mu", "table_mu", "", 0.0)
GRIP_RAMP_S = Quantity("grip_ramp_s", "grip_ramp_s", " s", 0.0)
GRIP_SETTLE_S = Quantity("grip_settle_s", "grip_settle_s", " s", 0.0)
MARKER_SIZE_CM = Quantity("marker_size_cm", "--marker-size-cm", " cm", 0.0, low_open=True)
SQUARE_SIZE_CM = Quantity("square_size_cm", "--square-size-cm", " cm", 0.0, low_open=True)
MARKER_ID = Quantity("marker_id", "--marker-id", "", 0, integer=True)

# ---------------------------------------------------------------------------- characterizing
WINDOW_S = Quantity("window_s", "--window-s", " s", 0.0, low_open=True)
#: The force D is stated at (``characterize --at-force-n``); above an object's peak force it is
#: refused where the object is fitted.
AT_FORCE_N = Quantity("at_force_n", "--at-force-n", " N", 0.0, low_open=True)

# ---------------------------------------------------------------------------- lifting
GROWTH = Quantity("growth", "--growth", "", 1.0, low_open=True)
TOLERANCE_REL = Quantity("tolerance_rel", "--tolerance", "", 0.0, 1.0, True, True)
MAX_ATTEMPTS = Quantity("max_attempts", "--max-attempts", "", 1, integer=True)
START_MARGIN = Quantity("start_margin", "--start-margin", "", 1.0)
START_INTERPOLATE = Quantity("start_interpolate", "--start-interpolate", "", 1, integer=True)
RIG_TIMEOUT_S = Quantity("rig_timeout_s", "--rig-timeout", " s", 0.0, low_open=True)
SLIP_TOLERANCE_M = Quantity("slip_tolerance_m", "--slip-tolerance-m", " m", 0.0, low_open=True)
#: A simulated lift's profile (:class:`deformctl.sim.LiftProfile`, ``lift sim --lift-...``): the
#: peak acceleration and cruise speed, the rise (None: half the object's height), the hold after
#: it, and each acceleration ramp (0: the acceleration steps).
LIFT_ACCEL_M_S2 = Quantity("lift_accel_m_s2", "--lift-accel-m-s2", " m/s²", 0.0, low_open=True)
LIFT_SPEED_M_S = Quantity("lift_speed_m_s", "--lift-speed-m-s", " m/s", 0.0, low_open=True)
LIFT_HEIGHT_M = Quantity("lift_height_m", "--lift-height-m", " m", 0.0, low_open=True)
LIFT_HOLD_S = Quantity("lift_hold_s", "--lift-hold-s", " s", 0.0)
LIFT_JERK_TIME_S = Quantity("lift_jerk_time_s", "jerk_time_s", " s", 0.0)
#: How long a support takes to give way at the start of the rise
#: (:class:`deformctl.sim.SupportRelease`; 0: at once).
RELEASE_TIME_S = Quantity("release_time_s", "release_time_s", " s", 0.0)
#: The simulator's slip tolerance (:class:`deformctl.sim.SlipCriterion`, ``lift sim``): 0 is
#: allowed there, since contacts in stick do not slide at all (a held attempt's slip is exactly
#: 0.0), unlike a rig's frames (:data:`SLIP_TOLERANCE_M`), whose marker tracking always jitters.
SIM_SLIP_TOLERANCE_M = Quantity("slip_tolerance_m", "--slip-tolerance-m", " m", 0.0)
#: The force ceiling of a lift (``lift --max-force-n``, the catalog's ``max_force_n`` column, the
#: search's ``max_force_n``; :mod:`deformctl.lift.ceiling`): no attempt requests more.
MAX_FORCE_N = Quantity("max_force_n", "--max-force-n", " N", 0.0, low_open=True)

# ---------------------------------------------------------------------------- training
#: ``train``'s split and network (:class:`deformctl.model.TrainOptions`): two training rows at
#: least (one is no regression), any number of calibration rows, layers of one node or more.
TRAIN_SIZE = Quantity("train_size", "--train-size", "", 2, integer=True)
#: The cap on each other law's training rows (``train --law-train-size``).
LAW_TRAIN_SIZE = Quantity("law_train_size", "--law-train-size", "", 2, integer=True)
CALIBRATION_SIZE = Quantity("calibration_size", "--calibration-size", "", 0, integer=True)
HIDDEN_SIZE = Quantity("hidden", "--hidden", "", 1, integer=True)
SEED = Quantity("seed", "--seed", "", 0, integer=True)
RESTARTS = Quantity("restarts", "restarts", "", 1, integer=True)
MAX_ITER = Quantity("max_iter", "max_iter", "", 1, integer=True)
#: The network's L2 penalty (scikit-learn's ``alpha``) and its solver's stopping tolerance.
L2_ALPHA = Quantity("alpha", "alpha", "", 0.0)
TOL = Quantity("tol", "tol", "", 0.0, low_open=True)

# ---------------------------------------------------------------------------- predicting
#: The probability an upper bound must hold with (``predict --coverage``, the split-conformal
#: bound of :mod:`deformctl.grip.conformal`).
COVERAGE = Quantity("coverage", "--coverage", "", 0.0, 1.0, low_open=True, high_open=True)

# ---------------------------------------------------------------------- a recording's plausibility
#: What a gripper squeeze or a testing machine on a soft object can record.
#: :mod:`deformctl.plausibility` judges every recording against these (``measure --csv`` and
#: ``--bag``; the implied damping ratio in ``characterize``): a value outside ``low``–``high`` is
#: refused (exit 65), one outside ``doubt_low``–``doubt_high`` flagged, and either line names the
#: unit under which the value would be plausible. The limits catch factors of 10³ (a unit slip),
#: not unusual objects.


@dataclass(frozen=True)
class Plausible:
    """The plausible band of a quantity a recording gives.

    Attributes:
        name: what is judged, for messages (``peak force``).
        unit: its SI unit, as messages print it after a number.
        low, high: outside them no reading is a squeeze: refused (exit 65).
        doubt_low, doubt_high: outside them (and inside ``low``–``high``) the value is doubtful:
            flagged ``flag`` with a warning line.
        flag: the quality flag of a doubtful value.
        target: the most typical value; a suggested unit aims at it (nearest in log).
    """

    name: str
    unit: str
    low: float
    high: float
    doubt_low: float
    doubt_high: float
    flag: str
    target: float

    def refused(self, value: float) -> bool:
        """Whether no recording of a squeeze gives ``value`` (outside ``low``–``high``)."""
        return not (self.low <= value <= self.high)

    def doubtful(self, value: float) -> bool:
        """Whether ``value`` is inside ``low``–``high`` but outside the doubt band."""
        return not self.refused(value) and not (self.doubt_low <= value <= self.doubt_high)

    def plausible(self, value: float) -> bool:
        """Whether ``value`` is neither refused nor doubtful (a finite number in the doubt band)."""
        return math.isfinite(value) and self.doubt_low <= value <= self.doubt_high


#: Sample rate, Hz: 1 Hz–100 kHz spans every force sensor and pose topic we know of (a 1 kHz log
#: read in the wrong time unit lands at 1 Hz or 1 MHz: refused). With no time unit stated, a
#: rate below 10 Hz is doubtful: a kHz logger's ms stamps read as seconds land at a few Hz.
RECORDED_RATE_HZ = Plausible(
    "sample rate", " Hz", 1.0, 100_000.0, 10.0, 100_000.0, "time_unit_doubtful", 1000.0
)
#: Peak force, N. Above 10 kN: refused (grippers and testing machines for soft objects stay far
#: below). Below 50 mN: doubtful (a squeeze loads a soft object with more; a kN column read as N,
#: or N values under an ``mN`` label, land 1000 times lower). Above 3 kN: doubtful (N values
#: under a ``kN`` label land 1000 times higher); the shared silicone phantoms, squeezed 20 mm on a
#: testing machine, peak at up to 1151 N (EF50_0T_A2.csv): a margin of 2.6.
RECORDED_PEAK_FORCE_N = Plausible(
    "peak force", " N", 0.0, 10_000.0, 0.05, 3000.0, "force_unit_doubtful", 10.0
)
#: Peak compression, m. Above 0.5 m (or the object's size along the squeeze): refused. Below
#: 20 µm: doubtful (metres under an ``mm`` label land here).
RECORDED_PEAK_COMPRESSION_M = Plausible(
    "peak compression", " m", 0.0, 0.5, 2e-5, 0.5, "compression_unit_doubtful", 0.01
)
#: The secant stiffness peak force / peak compression, N/cm, above which a squeeze of a soft
#: object is doubtful: N values under a ``kN`` label (or mm values under an ``m`` label) make it
#: 1000 times stiffer. The stiffest shared phantom is 575 N/cm (1151 N at 20 mm); a 5 cm block of
#: a 10 MPa rubber is about 6700 N/cm. Flagged as the force's or the compression's unit, whichever
#: a 10³ slip would explain. Caught this way: N values under ``kN`` whose secant then exceeds it
#: (5 N at 3 mm reads 16,700 N/cm); not caught: a slip that stays below it (1 N at 3 mm reads
#: 3,300 N/cm) — no reading tells those from a stiff object.
RECORDED_SECANT_N_PER_CM = Plausible(
    "secant stiffness", " N/cm", 0.0, math.inf, 0.0, 5000.0, "force_unit_doubtful", 20.0
)
#: The damping ratio a fit implies, ζ = λ / (2 √(D m)) with m = W / g (``characterize``). Above
#: 1000 it is doubtful: λ of a recording whose time stamps are 1000 times too long (ms read as s)
#: is 1000 times too high, and ζ with it (the paper's sponge, ζ = 17, reads 17,000). The bundled
#: grip model's training objects reach ζ = 64; a 10 g foam block of D = 5 N/cm and λ = 15 N·s/cm
#: reaches about 330. A time-unit slip on an object with ζ below 1 is not caught (it reads below
#: 1000). There is no low side: ζ = 0 is an undamped object.
IMPLIED_DAMPING_RATIO = Plausible(
    "implied damping ratio", "", 0.0, math.inf, 0.0, 1000.0, "damping_ratio_implausible", 1.0
)
#: The largest plausible L_f / F_w. The lifting force of a deformable object is L_f = F_w + F_d;
#: L_f / F_w is about 2 for an undamped object and falls with damping
#: (docs/explanation/model.md), and the paper's objects lie below 2. Five times that is a unit or
#: catalog mistake (a weight in grams, a μ of 0.005), not an object: ``lift``'s default force
#: ceiling (:mod:`deformctl.lift.ceiling`), the index table's refusal of absurd rows
#: (:func:`deformctl.table.impossible_rows`) and a prediction's plausibility all use it.
MAX_LIFT_RATIO = 10.0
