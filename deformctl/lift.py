"""Iterative lifting: search for the minimum lifting force L_f of one object.

The seed paper grips an object of weight ``W`` with the rigid-object force ``F_w = W / (2 mu)``
(two palms, friction coefficient ``mu``), lifts it, checks for slip, and raises the grip force by
20 % until the object comes up. The force that first lifts is the object's lifting force
``L_f = F_w + F_d``, where ``F_d >= 0`` is the surplus the deformation demands.

The search here does not care where a trial runs. A *trial runner* (:class:`TrialRunner`) takes a
grip force and an attempt index and returns a :class:`deformctl.series.TrialOutcome`; the built-in
simulator and an external rig (:class:`deformctl.rig.RigRunner`) are both runners, so the same code
drives a simulation and a real robot.

Two protocols:

``paper``
    Try ``F_w * growth**k`` for ``k = 0, 1, 2, ...`` until a trial lifts; report that force. Its
    bracket is ``(F_w * growth**(k-1), F_w * growth**k]``, so the answer is at most ``growth``
    times the true threshold (20 % for ``growth = 1.2``).

``refine`` (default)
    Bracket exactly as ``paper`` does (the same forces in the same order, so the paper's last
    bracket is reproduced), then bisect between the last force that slipped (``low``) and the
    first that lifted (``high``) until ``(high - low) / high <= tolerance_rel``. The reported L_f is
    ``high``: the smallest force that was actually tried *and* lifted. A force that was not tried
    is never reported.

Both start at ``F_w``; the search never tries a force below it (the paper defines ``L_f >= F_w``).
If ``F_w`` itself lifts, ``L_f = F_w`` with bracket ``(F_w, F_w)`` and ``converged = True``.

Rule for a search that runs out of attempts (``max_attempts`` counts every trial, bracketing and
bisection alike):

* nothing lifted: ``converged = False``, ``lift_force_n = NaN``, ``f_d_n = NaN``,
  ``bracket_n = (last force tried, inf)``; ``message`` names the object and the last force tried.
* something lifted but the bisection did not reach the tolerance (``refine`` only):
  ``converged = False``, ``lift_force_n`` = the smallest force that lifted (a tried upper bound),
  ``bracket_n = (low, high)``.

The search uses the *commanded* force in its bookkeeping; runners are expected to echo it in
``TrialOutcome.grip_force_n``. It assumes that lifting is monotone in the grip force (more force
never slips where less force lifted); with a noisy real rig the bisection still terminates, but its
answer is only as good as that assumption.

If the runner raises a :class:`deformctl.errors.DeformctlError` (a crashed rig, a simulator that
blew up), the search raises :class:`SearchAbortedError` (or :class:`RigSearchAbortedError` for a
:class:`~deformctl.errors.RigError`), whose ``partial`` attribute is the result so far, so the
caller can still write every attempt to the log.

Many objects (the ``lift`` stage): :func:`lift_catalog` runs one search per catalog object with a
runner from a :class:`RunnerFactory` (:func:`rig_runner_factory` for an external rig,
:func:`deformctl.lift_sim.sim_runner_factory` for the simulator) and returns a
:class:`CatalogLiftResult`: the lift_results table, every attempt (for the lift log) and the
failures, which it records instead of raising, so the caller can write everything before it
decides the exit code.

Example:
    >>> from deformctl.series import TrialOutcome
    >>> def runner(grip_force_n: float, attempt_index: int) -> TrialOutcome:
    ...     return TrialOutcome(grip_force_n, grip_force_n >= 7.0, 0.0)
    >>> result = find_min_lift_force(runner, weight_n=5.0, friction_mu=0.5, object_id="A")
    >>> result.f_w_n, result.converged, 7.0 <= result.lift_force_n <= 7.0 / (1 - 0.01)
    (5.0, True, True)
"""

from __future__ import annotations

import math
import os
import shlex
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

import numpy as np
import pandas as pd

from deformctl.artifacts.mcaplog import LiftAttempt
from deformctl.artifacts.schema import validate_frame
from deformctl.errors import DeformctlError, InputDataError, RigError, SearchError, UsageError
from deformctl.rig import RigAttemptError, RigRunner, SlipFromFrames
from deformctl.series import TrialOutcome

SearchProtocol = Literal["refine", "paper"]
PROTOCOLS: tuple[SearchProtocol, ...] = ("refine", "paper")

DEFAULT_GROWTH = 1.2  #: the paper's +20 % per attempt
DEFAULT_TOLERANCE_REL = 0.01  #: refine stops when (high - low) / high <= 1 %
DEFAULT_MAX_ATTEMPTS = 50  #: covers F_w * 1.2**40 (about 1500 x F_w) plus the bisection

__all__ = [
    "DEFAULT_GROWTH",
    "DEFAULT_MAX_ATTEMPTS",
    "DEFAULT_TOLERANCE_REL",
    "PROTOCOLS",
    "RIG_SLIP_CRITERION",
    "CatalogLiftResult",
    "LiftProgress",
    "LiftSearchResult",
    "ObjectFailure",
    "RigSearchAbortedError",
    "RunnerFactory",
    "SearchAbortedError",
    "SearchProtocol",
    "TrialRunner",
    "catalog_records",
    "check_liftable",
    "find_min_lift_force",
    "lift_catalog",
    "rig_object",
    "rig_runner_factory",
    "rigid_grip_force_n",
    "select_objects",
    "validate_search_options",
]


class TrialRunner(Protocol):
    """Anything that runs one lift attempt: ``runner(grip_force_n, attempt_index) -> TrialOutcome``.

    Arguments are positional. ``grip_force_n`` is the normal force each palm applies, N (> 0).
    ``attempt_index`` is the 0-based index of this attempt within the object's search (the search
    calls 0, 1, 2, ... in order). The runner lifts the object by its protocol (the paper: half the
    object's height), decides whether it slipped, and returns a
    :class:`~deformctl.series.TrialOutcome` with ``grip_force_n`` equal to the commanded force,
    ``lifted``, ``slip_m`` (NaN when unknown) and, when it records one, the attempt's time series.

    A runner reports a failure it cannot recover from (a rig that crashed, a simulation that went
    non-finite) by raising a :class:`~deformctl.errors.DeformctlError`; every other exception is
    treated as a bug and propagates unchanged.

    A plain function ``def run(grip_force_n: float, attempt_index: int) -> TrialOutcome`` is a
    ``TrialRunner``.
    """

    def __call__(self, grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        """Run one attempt at ``grip_force_n`` (N) and report what happened."""
        ...


@dataclass(frozen=True)
class LiftSearchResult:
    """The outcome of one lifting-force search, in the manner of scipy's ``RootResults``.

    Attributes:
        object_id: catalog id of the object.
        lift_force_n: L_f, N: the smallest grip force that was tried and lifted; NaN when no
            attempt lifted (see the module docstring for the rule).
        f_w_n: F_w = W / (2 mu), N, the rigid-object force the search starts at.
        f_d_n: F_d = L_f - F_w, N (NaN when L_f is NaN).
        attempts: number of trials run (``len(trials)``).
        bracket_n: ``(low, high)``, N: the largest force that slipped below ``high`` and the
            smallest that lifted; ``(F_w, F_w)`` when F_w lifted; ``(last tried, inf)`` when nothing
            lifted.
        converged: True when a force lifted and (``refine``) the bracket met the tolerance.
        protocol: ``"refine"`` or ``"paper"``.
        tolerance_rel: the relative bracket width ``refine`` aims for (recorded; ``paper`` does
            not use it).
        growth: the ramp factor between bracketing attempts.
        trials: every attempt's outcome, in the order run.
        message: one line for a human: what was found, or why not (names the object and, when
            nothing lifted, the last force tried).
        weight_n: the object's weight W, N.
        friction_mu: the palm/object friction coefficient mu.
        max_attempts: the attempt budget the search had.
        ramp_attempts: how many of ``trials`` belong to the paper ramp (the rest are bisection).
    """

    object_id: str
    lift_force_n: float
    f_w_n: float
    f_d_n: float
    attempts: int
    bracket_n: tuple[float, float]
    converged: bool
    protocol: SearchProtocol
    tolerance_rel: float
    growth: float
    trials: tuple[TrialOutcome, ...]
    message: str
    weight_n: float = math.nan
    friction_mu: float = math.nan
    max_attempts: int = DEFAULT_MAX_ATTEMPTS
    ramp_attempts: int = 0

    @property
    def lifted(self) -> bool:
        """True when at least one attempt lifted the object."""
        return any(t.lifted for t in self.trials)

    @property
    def last_force_n(self) -> float:
        """The grip force of the last attempt run, N (NaN before any attempt)."""
        return self.trials[-1].grip_force_n if self.trials else math.nan

    @property
    def paper_bracket_n(self) -> tuple[float, float]:
        """The bracket the paper ramp ended with: (last slipped ramp force, first lifted), N.

        ``(F_w, F_w)`` when F_w lifted; ``(last ramp force, inf)`` when the ramp never lifted.
        """
        ramp = self.trials[: self.ramp_attempts]
        if not ramp:
            return (math.nan, math.nan)
        if not ramp[-1].lifted:
            return (ramp[-1].grip_force_n, math.inf)
        if len(ramp) == 1:
            return (ramp[0].grip_force_n, ramp[0].grip_force_n)
        return (ramp[-2].grip_force_n, ramp[-1].grip_force_n)

    def summary(self) -> dict[str, object]:
        """The scalar fields as a JSON-friendly dict (no trials), keyed like the lift_results table.

        The keys shared with ``schemas/lift_results.columns.json`` come first and carry the same
        names; ``growth``, ``max_attempts``, ``last_force_n`` and ``message`` follow. Values are
        the result's own (an unbounded bracket keeps ``inf``); :meth:`table_row` makes a row.
        """
        return {
            "object_id": self.object_id,
            "weight_n": self.weight_n,
            "friction_mu": self.friction_mu,
            "f_w_n": self.f_w_n,
            "lift_force_n": self.lift_force_n,
            "f_d_n": self.f_d_n,
            "attempts": self.attempts,
            "converged": self.converged,
            "protocol": self.protocol,
            "bracket_low_n": self.bracket_n[0],
            "bracket_high_n": self.bracket_n[1],
            "tolerance_rel": self.tolerance_rel,
            "growth": self.growth,
            "max_attempts": self.max_attempts,
            "last_force_n": self.last_force_n,
            "message": self.message,
        }

    def table_row(self, *, runner: str, error: str | None = None) -> dict[str, object]:
        """One row of the lift_results table (``schemas/lift_results.columns.json``).

        Differences from :meth:`summary`: an unbounded ``bracket_high_n`` (nothing lifted) is NaN,
        as the table holds no infinities; ``tolerance_rel`` is NaN for ``paper``, which does not
        use it; ``runner`` and ``error`` are added; ``message``, ``growth``, ``max_attempts``
        and ``last_force_n`` are dropped (the table holds only its spec's columns; the search
        settings are in the file's provenance).

        Args:
            runner: the trial runner's name (``"rig"``, ``"sim"``).
            error: the row's error text; None picks ``message`` when the search did not
                converge and None when it did.
        """
        row = self.summary()
        for key in ("message", "growth", "max_attempts", "last_force_n"):
            del row[key]
        if not math.isfinite(self.bracket_n[1]):
            row["bracket_high_n"] = math.nan
        if self.protocol == "paper":
            row["tolerance_rel"] = math.nan
        row["runner"] = runner
        row["error"] = error if error is not None else (None if self.converged else self.message)
        return row


class SearchAbortedError(SearchError):
    """A search stopped because its runner failed; ``partial`` holds the attempts so far.

    ``partial`` is a :class:`LiftSearchResult` with ``converged = False`` built from the trials
    that completed before the failure (the failed attempt is not among them). ``__cause__`` is the
    runner's error.
    """

    def __init__(self, message: str, *, partial: LiftSearchResult) -> None:
        self.partial = partial
        super().__init__(message)


class RigSearchAbortedError(SearchAbortedError, RigError):
    """A search stopped because the external rig failed (crash, time-out, bad answer)."""


def rigid_grip_force_n(weight_n: float, friction_mu: float) -> float:
    """F_w = W / (2 mu), N: the force two palms need to hold a rigid object of weight W at rest."""
    return weight_n / (2.0 * friction_mu)


def validate_search_options(
    *, protocol: str, growth: float, tolerance_rel: float, max_attempts: int
) -> None:
    """Check the search options that do not depend on the object.

    Raises:
        UsageError: ``protocol`` unknown, ``growth`` not a finite number > 1, ``tolerance_rel``
            not in (0, 1), or ``max_attempts`` not an integer >= 1 (exit 2).
    """
    if protocol not in PROTOCOLS:
        raise UsageError(f"protocol must be one of {', '.join(PROTOCOLS)}, got {protocol!r}")
    if not (math.isfinite(growth) and growth > 1):
        raise UsageError(f"growth must be a finite number > 1, got {growth!r}")
    if not (math.isfinite(tolerance_rel) and 0 < tolerance_rel < 1):
        raise UsageError(f"tolerance must be a relative value in (0, 1), got {tolerance_rel!r}")
    if isinstance(max_attempts, bool) or not isinstance(max_attempts, int) or max_attempts < 1:
        raise UsageError(f"max attempts must be an integer >= 1, got {max_attempts!r}")


def _validate(
    *,
    weight_n: float,
    friction_mu: float,
    protocol: str,
    growth: float,
    tolerance_rel: float,
    max_attempts: int,
    object_id: str,
) -> None:
    where = f"object {object_id!r}: "
    if not (math.isfinite(weight_n) and weight_n > 0):
        raise UsageError(f"{where}weight must be a finite number > 0 N, got {weight_n!r}")
    if not (math.isfinite(friction_mu) and friction_mu > 0):
        raise UsageError(f"{where}friction mu must be a finite number > 0, got {friction_mu!r}")
    validate_search_options(
        protocol=protocol, growth=growth, tolerance_rel=tolerance_rel, max_attempts=max_attempts
    )


@dataclass
class _Search:
    """Mutable bookkeeping of one search; turned into a frozen result by :meth:`result`."""

    object_id: str
    weight_n: float
    friction_mu: float
    f_w_n: float
    protocol: SearchProtocol
    growth: float
    tolerance_rel: float
    max_attempts: int
    trials: list[TrialOutcome]
    ramp_attempts: int = 0
    low_n: float = math.nan  # largest force that slipped below high_n
    high_n: float = math.nan  # smallest force that lifted

    def result(self, *, converged: bool, message: str) -> LiftSearchResult:
        lifted = math.isfinite(self.high_n)
        lift_force_n = self.high_n if lifted else math.nan
        if lifted:
            bracket = (self.low_n if math.isfinite(self.low_n) else self.high_n, self.high_n)
        else:
            last = self.trials[-1].grip_force_n if self.trials else math.nan
            bracket = (last, math.inf)
        return LiftSearchResult(
            object_id=self.object_id,
            lift_force_n=lift_force_n,
            f_w_n=self.f_w_n,
            f_d_n=lift_force_n - self.f_w_n,
            attempts=len(self.trials),
            bracket_n=bracket,
            converged=converged,
            protocol=self.protocol,
            tolerance_rel=self.tolerance_rel,
            growth=self.growth,
            trials=tuple(self.trials),
            message=message,
            weight_n=self.weight_n,
            friction_mu=self.friction_mu,
            max_attempts=self.max_attempts,
            ramp_attempts=self.ramp_attempts,
        )


def find_min_lift_force(
    runner: TrialRunner,
    *,
    weight_n: float,
    friction_mu: float,
    protocol: SearchProtocol = "refine",
    growth: float = DEFAULT_GROWTH,
    tolerance_rel: float = DEFAULT_TOLERANCE_REL,
    max_attempts: int = DEFAULT_MAX_ATTEMPTS,
    object_id: str = "object",
) -> LiftSearchResult:
    """Find the minimum grip force that lifts one object, by iterative lifting.

    Args:
        runner: the trial runner (see :class:`TrialRunner`); called with positional
            ``(grip_force_n, attempt_index)``, attempt indices 0, 1, 2, ...
        weight_n: the object's weight W, N (> 0).
        friction_mu: palm/object friction coefficient mu (> 0).
        protocol: ``"refine"`` (default) or ``"paper"``; see the module docstring.
        growth: factor between successive ramp forces (> 1; the paper's 1.2).
        tolerance_rel: ``refine`` stops when ``(high - low) / high <= tolerance_rel``; in (0, 1).
        max_attempts: the most trials to run in total (>= 1).
        object_id: the object's catalog id, used in messages and the result.

    Returns:
        A :class:`LiftSearchResult`. A search that runs out of attempts returns
        ``converged = False`` (it does not raise); the caller decides the exit code.

    Raises:
        UsageError: a parameter out of range (one-line message).
        SearchAbortedError: the runner raised a :class:`~deformctl.errors.DeformctlError`;
            ``err.partial`` holds the attempts so far (:class:`RigSearchAbortedError` when the
            runner's error is a :class:`~deformctl.errors.RigError`).
    """
    _validate(
        weight_n=weight_n,
        friction_mu=friction_mu,
        protocol=protocol,
        growth=growth,
        tolerance_rel=tolerance_rel,
        max_attempts=max_attempts,
        object_id=object_id,
    )
    s = _Search(
        object_id=object_id,
        weight_n=float(weight_n),
        friction_mu=float(friction_mu),
        f_w_n=rigid_grip_force_n(float(weight_n), float(friction_mu)),
        protocol=protocol,
        growth=float(growth),
        tolerance_rel=float(tolerance_rel),
        max_attempts=max_attempts,
        trials=[],
    )
    obj = f"object {object_id!r}"

    def attempt(force_n: float) -> bool:
        index = len(s.trials)
        try:
            outcome = runner(force_n, index)
        except DeformctlError as err:
            kept = f"{index} attempt{'' if index == 1 else 's'} kept"
            if isinstance(err, RigAttemptError):  # names the object, attempt and force itself
                detail = str(err)
            else:
                detail = f"{obj}: attempt {index} at {force_n:.6g} N: {err}"
            why = f"search aborted, {kept}: {detail}"
            partial = s.result(converged=False, message=why)
            cls = RigSearchAbortedError if isinstance(err, RigError) else SearchAbortedError
            raise cls(why, partial=partial) from err
        if not isinstance(outcome, TrialOutcome):
            raise TypeError(f"trial runner returned {type(outcome).__name__}, not TrialOutcome")
        s.trials.append(outcome)
        if outcome.lifted:
            s.high_n = force_n if not math.isfinite(s.high_n) else min(s.high_n, force_n)
        elif not math.isfinite(s.low_n) or force_n > s.low_n:
            s.low_n = force_n
        return bool(outcome.lifted)

    # Phase 1: the paper's ramp F_w * growth**k until a force lifts.
    k = 0
    while True:
        try:
            force_n = s.f_w_n * s.growth**k
        except OverflowError:
            force_n = math.inf
        if not math.isfinite(force_n):  # only with a huge budget and growth
            return s.result(
                converged=False,
                message=f"{obj}: did not lift; the ramp overflowed after {len(s.trials)} attempts",
            )
        lifted = attempt(force_n)
        s.ramp_attempts = len(s.trials)
        if lifted:
            break
        if len(s.trials) >= max_attempts:
            return s.result(
                converged=False,
                message=(
                    f"{obj}: did not lift within {max_attempts} attempts; "
                    f"last force tried {force_n:.6g} N slipped (F_w = {s.f_w_n:.6g} N)"
                ),
            )
        k += 1

    if s.protocol == "paper" or len(s.trials) == 1:
        return s.result(converged=True, message=_found_message(obj, s))

    # Phase 2 (refine): bisect the last ramp bracket (low slipped, high lifted).
    while (s.high_n - s.low_n) / s.high_n > s.tolerance_rel:
        if len(s.trials) >= max_attempts:
            return s.result(
                converged=False,
                message=(
                    f"{obj}: bracket [{s.low_n:.6g}, {s.high_n:.6g}] N did not reach "
                    f"tolerance {s.tolerance_rel:g} within {max_attempts} attempts; "
                    f"smallest force that lifted {s.high_n:.6g} N"
                ),
            )
        mid_n = 0.5 * (s.low_n + s.high_n)
        if not s.low_n < mid_n < s.high_n:  # the bracket is as narrow as floats allow
            return s.result(
                converged=False,
                message=(
                    f"{obj}: tolerance {s.tolerance_rel:g} is below floating-point resolution "
                    f"at {s.high_n:.6g} N"
                ),
            )
        attempt(mid_n)
    return s.result(converged=True, message=_found_message(obj, s))


def _found_message(obj: str, s: _Search) -> str:
    low = s.low_n if math.isfinite(s.low_n) else s.high_n
    return (
        f"{obj}: lifted at L_f = {s.high_n:.6g} N (F_w = {s.f_w_n:.6g} N, "
        f"bracket [{low:.6g}, {s.high_n:.6g}] N) after {len(s.trials)} attempts ({s.protocol})"
    )


# ------------------------------------------------------------- many objects: the `lift` stage

LiftProgress = Callable[[str, int, int], None]
"""``progress(object_id, objects_done, objects_total)``, called after each object of a catalog."""

RIG_SLIP_CRITERION = "rig"  #: ``slip_criterion`` of rows whose outcome the rig reported itself
#: ``slip_criterion`` when deformctl judges rig frames (a rig answering ``lifted`` still decides).
FRAMES_SLIP_CRITERION = "frames"
_PROFILE_COLUMNS = ("lift_accel_m_s2", "lift_speed_m_s", "lift_height_m", "slip_tolerance_m")


def _no_row_fields(obj: Mapping[str, Any]) -> Mapping[str, object]:
    return {}


@dataclass(frozen=True)
class RunnerFactory:
    """Builds one trial runner per catalog object: what :func:`lift_catalog` searches with.

    Every runner kind (the external rig now, the built-in simulator next to it) is one factory,
    so the stage code does not care which one runs the attempts.

    Attributes:
        name: the runner's name, stored in the table's ``runner`` column (``"rig"``, ``"sim"``).
        make: ``make(obj) -> TrialRunner`` for one object; ``obj`` is the object's catalog row as
            a dict (see :func:`catalog_records`: paper units, NaN as None).
        row_fields: ``row_fields(obj) -> {column: value}``: the table columns this runner fills
            for the object (lift profile ``lift_accel_m_s2``, ``lift_speed_m_s``,
            ``lift_height_m``, ``slip_tolerance_m``, ``slip_criterion``).
        stop_on_failure: when a runner fails for one object (raises a
            :class:`~deformctl.errors.DeformctlError`), the remaining objects are not run.
        settings: JSON-serialisable settings of the runner, for the outputs' provenance.
        check: ``check(catalog, path)``: refuse catalog rows this runner cannot run (e.g. the
            simulator needs material values) by raising a
            :class:`~deformctl.errors.DeformctlError`; :func:`lift_catalog` calls it before any
            attempt. None: no runner-specific check.
    """

    name: str
    make: Callable[[Mapping[str, Any]], TrialRunner]
    row_fields: Callable[[Mapping[str, Any]], Mapping[str, object]] = _no_row_fields
    stop_on_failure: bool = True
    settings: Mapping[str, Any] = field(default_factory=dict)
    check: Callable[[pd.DataFrame, str | None], None] | None = None


def rig_object(obj: Mapping[str, Any]) -> dict[str, Any]:
    """The object description a :class:`~deformctl.rig.RigRunner` sends: id, W, mu, size (cm).

    Args:
        obj: a catalog row (``object_id``, ``weight_n``, ``friction_mu``, ``size_{x,y,z}_cm``).
    """
    out: dict[str, Any] = {
        "object_id": str(obj["object_id"]),
        "weight_n": float(obj["weight_n"]),
        "friction_mu": float(obj["friction_mu"]),
    }
    size = [obj.get(f"size_{axis}_cm") for axis in "xyz"]
    if all(isinstance(v, int | float) and math.isfinite(v) for v in size):
        out["size_cm"] = [float(v) for v in size if v is not None]
    return out


def rig_runner_factory(
    command: str | Sequence[str],
    *,
    timeout_s: float,
    cwd: str | os.PathLike[str] | None = None,
    slip_from_frames: SlipFromFrames | None = None,
) -> RunnerFactory:
    """A :class:`RunnerFactory` for an external rig command (see :mod:`deformctl.rig`).

    Each object gets its own :class:`~deformctl.rig.RigRunner`; the command runs once per attempt.
    A rig failure stops the run (``stop_on_failure``): a crashed driver usually means the robot
    needs attention, so deformctl does not go on commanding it.

    Args:
        command: the rig command, a string (split like a shell line, never run by a shell) or
            an argument list.
        timeout_s: the longest one attempt may take, s (finite, > 0).
        cwd: the directory the command runs in; the current directory when None.
        slip_from_frames: judges rig answers that carry frames but no ``lifted`` (e.g.
            ``functools.partial(deformctl.vision.slip_from_frames, palm_marker_ids=(1, 2),
            marker_size_cm=2.4)``); its bound keywords go into the settings, its ``tolerance_m``
            into the rows' ``slip_tolerance_m``.

    Raises:
        UsageError: an empty or unparsable command (unbalanced quotes), or a bad timeout.
    """
    if isinstance(command, str):
        try:
            argv = shlex.split(command)
        except ValueError as err:
            raise UsageError(f"rig command cannot be parsed ({err}): {command!r}") from None
    else:
        argv = [str(a) for a in command]
    if not argv:
        raise UsageError("rig command is empty")
    if isinstance(timeout_s, bool) or not (
        isinstance(timeout_s, int | float) and math.isfinite(timeout_s) and timeout_s > 0
    ):
        raise UsageError(f"rig timeout must be a finite number > 0 s, got {timeout_s!r}")

    def make(obj: Mapping[str, Any]) -> TrialRunner:
        return RigRunner(
            argv,
            timeout_s=float(timeout_s),
            object=rig_object(obj),
            cwd=cwd,
            slip_from_frames=slip_from_frames,
        )

    frame_options = dict(getattr(slip_from_frames, "keywords", None) or {})

    def row_fields(obj: Mapping[str, Any]) -> Mapping[str, object]:
        fields: dict[str, object] = dict.fromkeys(_PROFILE_COLUMNS, math.nan)
        fields["slip_criterion"] = RIG_SLIP_CRITERION
        if slip_from_frames is not None:
            fields["slip_criterion"] = FRAMES_SLIP_CRITERION
            fields["slip_tolerance_m"] = float(frame_options.get("tolerance_m", math.nan))
        return fields

    settings: dict[str, Any] = {"rig_command": argv, "rig_timeout_s": float(timeout_s)}
    if slip_from_frames is not None:
        settings["slip_from_frames"] = frame_options

    return RunnerFactory(
        name="rig",
        make=make,
        row_fields=row_fields,
        stop_on_failure=True,
        settings=settings,
    )


def catalog_records(catalog: pd.DataFrame) -> list[dict[str, Any]]:
    """The catalog's rows as plain dicts (Python scalars; NaN and missing values as None)."""
    records: list[dict[str, Any]] = []
    for rec in catalog.to_dict("records"):
        clean: dict[str, Any] = {}
        for key, value in rec.items():
            if isinstance(value, np.generic):
                value = value.item()
            if value is None or (isinstance(value, float) and math.isnan(value)):
                value = None
            clean[str(key)] = value
        records.append(clean)
    return records


def select_objects(catalog: pd.DataFrame, object_ids: Sequence[str] | None) -> pd.DataFrame:
    """The catalog rows of ``object_ids``, in that order (all rows when None).

    Repeated ids are taken once.

    Raises:
        UsageError: an empty list, an empty id, or an id the catalog does not have (exit 2).
    """
    if object_ids is None:
        return catalog.reset_index(drop=True)
    wanted = list(dict.fromkeys(object_ids))
    if not wanted:
        raise UsageError("no object ids given")
    if any(not oid for oid in wanted):
        raise UsageError("an object id is empty")
    known = list(catalog["object_id"])
    unknown = [oid for oid in wanted if oid not in set(known)]
    if unknown:
        shown = ", ".join(known[:10]) + (", ..." if len(known) > 10 else "")
        raise UsageError(f"unknown object id {unknown[0]!r} (the catalog has: {shown})")
    position = {oid: i for i, oid in enumerate(known)}
    return catalog.iloc[[position[oid] for oid in wanted]].reset_index(drop=True)


def check_liftable(catalog: pd.DataFrame, *, path: str | None = None) -> None:
    """Refuse catalog rows a lift cannot use: ``friction_mu`` must be > 0 (F_w = W / (2 mu)).

    The catalog spec allows mu = 0 (a frictionless object can be squeezed), so this is checked
    here, for the objects about to be lifted. Weight and sizes are already > 0 in a valid catalog.

    Raises:
        InputDataError: naming the catalog and the object (exit 65).
    """
    for oid, mu, weight in zip(
        catalog["object_id"], catalog["friction_mu"], catalog["weight_n"], strict=True
    ):
        if not (math.isfinite(mu) and mu > 0):
            raise InputDataError(
                f"object {oid!r}: friction_mu must be > 0 to lift it "
                f"(F_w = W / (2 mu) is undefined), got {float(mu)!r}",
                path=path,
            )
        if not (math.isfinite(weight) and weight > 0):
            raise InputDataError(
                f"object {oid!r}: weight_n must be > 0 to lift it, got {float(weight)!r}",
                path=path,
            )


@dataclass(frozen=True)
class ObjectFailure:
    """An object whose search did not produce a converged L_f.

    Attributes:
        object_id: the object.
        message: one line: why (names the object; for a budget that ran out, the last force
            tried; for a runner failure, the attempt and the force).
        aborted: True when the runner failed (a rig crash, time-out or bad answer), False when
            the search ran out of attempts.
    """

    object_id: str
    message: str
    aborted: bool


@dataclass(frozen=True)
class CatalogLiftResult:
    """What :func:`lift_catalog` found for a set of catalog objects.

    Attributes:
        table: the lift_results table, one row per object in the order run (validated against
            ``schemas/lift_results.columns.json``); objects not run after a runner failure have
            ``attempts = 0`` and an ``error`` starting with ``not run``.
        attempts: every attempt that completed, in the order run (for the lift log); an aborted
            search contributes the attempts before the failure.
        results: the search result of every object that was run (the partial result for an
            aborted search).
        objects: the catalog rows of the objects (see :func:`catalog_records`), for the log.
        failures: the objects that did not converge, in the order run.
        not_run: ids of the objects skipped after a runner failure.
    """

    table: pd.DataFrame
    attempts: tuple[LiftAttempt, ...]
    results: tuple[LiftSearchResult, ...]
    objects: tuple[dict[str, Any], ...]
    failures: tuple[ObjectFailure, ...]
    not_run: tuple[str, ...]

    @property
    def ok(self) -> bool:
        """True when every object's search converged."""
        return not self.failures and not self.not_run

    def error_message(self) -> str | None:
        """One line for the exit: the runner failure if any, else the first non-converged object.

        None when :attr:`ok`.
        """
        if self.ok:
            return None
        aborted = [f for f in self.failures if f.aborted]
        first = aborted[0] if aborted else self.failures[0]
        notes = []
        others = len(self.failures) - 1
        if others:
            notes.append(f"{others} more object{'s' if others > 1 else ''} did not converge")
        if self.not_run:
            n = len(self.not_run)
            notes.append(f"{n} later object{'s' if n > 1 else ''} not run")
        return first.message + (f" ({'; '.join(notes)})" if notes else "")


def lift_catalog(
    catalog: pd.DataFrame,
    factory: RunnerFactory,
    *,
    protocol: SearchProtocol = "refine",
    growth: float = DEFAULT_GROWTH,
    tolerance_rel: float = DEFAULT_TOLERANCE_REL,
    max_attempts: int = DEFAULT_MAX_ATTEMPTS,
    progress: LiftProgress | None = None,
    path: str | None = None,
) -> CatalogLiftResult:
    """Search the minimum lifting force of every object of a catalog, one after another.

    Each object gets its own runner from ``factory`` and one :func:`find_min_lift_force`
    search. Failures do not raise; they are recorded so the caller can still write every
    attempt and a row per object, then decide the exit:

    * a search that runs out of attempts gives a row with ``converged = False`` and the search's
      message in ``error``; the next object is run.
    * a runner failure (:class:`SearchAbortedError`) gives a row from the partial result with
      the failure in ``error``; the attempts before it are kept. When
      ``factory.stop_on_failure`` (the rig), the remaining objects are not run and get a
      ``not run`` row.

    Args:
        catalog: a validated catalog (see :func:`deformctl.artifacts.read_catalog`), already cut
            to the objects to lift (:func:`select_objects`).
        factory: builds the runner of each object.
        protocol: ``"refine"`` or ``"paper"``.
        growth: ramp factor (> 1).
        tolerance_rel: ``refine``'s relative bracket width, in (0, 1).
        max_attempts: attempt budget per object (>= 1).
        progress: called after each object as ``progress(object_id, done, total)``.
        path: the catalog's file name, for error messages.

    Returns:
        A :class:`CatalogLiftResult`.

    Raises:
        UsageError: a search option out of range (before anything runs; exit 2).
        InputDataError: an object the lift cannot use, e.g. ``friction_mu = 0``, or one the
            runner refuses (``factory.check``) (before anything runs; exit 65).
    """
    validate_search_options(
        protocol=protocol, growth=growth, tolerance_rel=tolerance_rel, max_attempts=max_attempts
    )
    check_liftable(catalog, path=path)
    if factory.check is not None:
        factory.check(catalog, path)
    records = catalog_records(catalog)
    rows: list[dict[str, object]] = []
    attempts: list[LiftAttempt] = []
    results: list[LiftSearchResult] = []
    failures: list[ObjectFailure] = []
    not_run: list[str] = []
    stopped_at: str | None = None
    for done, obj in enumerate(records, start=1):
        oid = str(obj["object_id"])
        if stopped_at is not None:
            rows.append(_not_run_row(obj, factory, protocol, tolerance_rel, stopped_at))
            not_run.append(oid)
        else:
            try:
                result = find_min_lift_force(
                    factory.make(obj),
                    weight_n=float(obj["weight_n"]),
                    friction_mu=float(obj["friction_mu"]),
                    protocol=protocol,
                    growth=growth,
                    tolerance_rel=tolerance_rel,
                    max_attempts=max_attempts,
                    object_id=oid,
                )
                error = None if result.converged else result.message
                if error is not None:
                    failures.append(ObjectFailure(oid, error, aborted=False))
            except SearchAbortedError as err:
                result, error = err.partial, str(err)
                failures.append(ObjectFailure(oid, error, aborted=True))
                if factory.stop_on_failure:
                    stopped_at = oid
            results.append(result)
            attempts.extend(LiftAttempt(oid, i, t) for i, t in enumerate(result.trials))
            row = result.table_row(runner=factory.name, error=error)
            row.update(factory.row_fields(obj))
            rows.append(row)
        if progress is not None:
            progress(oid, done, len(records))
    table = validate_frame(pd.DataFrame(rows), "lift_results")
    return CatalogLiftResult(
        table=table,
        attempts=tuple(attempts),
        results=tuple(results),
        objects=tuple(records),
        failures=tuple(failures),
        not_run=tuple(not_run),
    )


def _not_run_row(
    obj: Mapping[str, Any],
    factory: RunnerFactory,
    protocol: SearchProtocol,
    tolerance_rel: float,
    stopped_at: str,
) -> dict[str, object]:
    weight_n, friction_mu = float(obj["weight_n"]), float(obj["friction_mu"])
    row: dict[str, object] = {
        "object_id": str(obj["object_id"]),
        "weight_n": weight_n,
        "friction_mu": friction_mu,
        "f_w_n": rigid_grip_force_n(weight_n, friction_mu),
        "lift_force_n": math.nan,
        "f_d_n": math.nan,
        "attempts": 0,
        "converged": False,
        "protocol": protocol,
        "bracket_low_n": math.nan,
        "bracket_high_n": math.nan,
        "tolerance_rel": math.nan if protocol == "paper" else float(tolerance_rel),
        "runner": factory.name,
        "error": f"not run: the run stopped at object {stopped_at!r} after a runner failure",
    }
    row.update(factory.row_fields(obj))
    return row
