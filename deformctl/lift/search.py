"""Iterative lifting: search for the minimum lifting force L_f of one object.

The seed paper grips an object of weight ``W`` with the rigid-object force ``F_w = W / (2 mu)``
(two palms, friction coefficient ``mu``), lifts it, checks for slip, and raises the grip force by
20 % until the object comes up. The force that first lifts is the object's lifting force
``L_f = F_w + F_d``, where ``F_d >= 0`` is the surplus the deformation demands.

The search here does not care where a trial runs. A *trial runner* (:class:`TrialRunner`) takes a
grip force and an attempt index and returns a :class:`deformctl.series.TrialOutcome`; the built-in
simulator (:mod:`deformctl.lift.runners.sim`) and an external rig
(:class:`deformctl.lift.runners.rig.RigRunner`) are both runners, so the same code drives a
simulation and a real robot. This module knows neither: it holds the protocols, the result types
(:class:`LiftSearchResult`; :class:`LiftAttempt`, the unit a lift log stores, is
:class:`deformctl.series.LiftAttempt`, re-exported) and the search.

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

Every protocol takes a force ceiling ``max_force_n`` (:mod:`deformctl.lift.ceiling`; infinite
by default here, ``lift`` always gives one): no attempt is ever requested above it. A ramp step
or a seeded step up that would pass it tries the ceiling itself once; if that slips (or F_w is
already above it), the search stops with ``converged = False`` and a message "no safe grip". A
seeded start above it is clamped to it.
If ``F_w`` itself lifts, ``L_f = F_w`` with bracket ``(F_w, F_w)`` and ``converged = True``.

A third protocol starts from a *predicted* L_f instead (the paper's closing proposal: use the
trained network's answer and lift only to correct its error):

``seeded`` (:func:`find_min_lift_force_seeded`; ``lift --start-model`` / ``--start-table``)
    First attempt at ``max(F_w, prediction * margin)``; if it lifts, step down (first to
    ``prediction / margin``) until one slips, never below ``F_w``; if it slips, step up until
    one lifts; the steps grow from ``margin**2`` to ``growth`` (then the paper's ramp); then
    bisect exactly as ``refine`` does. Same tolerance, same rule for what is reported, so its
    L_f agrees with ``refine``'s within ``tolerance_rel``; only the number of attempts differs.

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

Many objects (the ``lift`` stage) are :mod:`deformctl.lift.stage`.

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
from dataclasses import dataclass, field
from typing import Any, Protocol

from deformctl.catalog import rigid_grip_force_n
from deformctl.errors import DeformctlError, RigError, SearchError, UsageError
from deformctl.lift.options import (
    DEFAULT_GROWTH,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_START_MARGIN,
    DEFAULT_TOLERANCE_REL,
    PROTOCOLS,
    SearchOptions,
    SearchProtocol,
)
from deformctl.quantities import FRICTION_MU, MAX_FORCE_N, START_MARGIN, WEIGHT_N
from deformctl.reprs import short_repr
from deformctl.series import LiftAttempt, TrialOutcome

__all__ = [
    "DEFAULT_GROWTH",
    "DEFAULT_MAX_ATTEMPTS",
    "DEFAULT_START_MARGIN",
    "DEFAULT_TOLERANCE_REL",
    "PROTOCOLS",
    "AttemptError",
    "LiftAttempt",
    "LiftSearchResult",
    "RigSearchAbortedError",
    "SearchAbortedError",
    "SearchOptions",
    "SearchProtocol",
    "TrialRunner",
    "find_min_lift_force",
    "find_min_lift_force_seeded",
    "rigid_grip_force_n",
    "validate_start_margin",
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


class AttemptError(DeformctlError):
    """A runner failure whose message already names the object, the attempt and the force.

    The search uses such a message as it is; any other :class:`DeformctlError` of a runner is
    prefixed with the object, the attempt and the force.
    """


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
        ramp_attempts: how many of ``trials`` belong to the paper ramp (the rest are bisection);
            for ``seeded``, the attempts before the bisection (the start, then down or up).
        predicted_lift_force_n: the L_f a model or an index table predicted, N, when the search
            was given a start (``seeded``, or a fallback to F_w); NaN otherwise.
        start_force_n: the force of the first attempt, N, when a start was given:
            ``max(F_w, predicted * margin)``, or F_w after a fallback; NaN otherwise.
        start_in_training_range: whether the object's (W, D, λ) lay inside the model's training
            range (or the table's attribute range); False means the search fell back to the
            ``refine`` ramp from F_w. None when no start was given.
        start_source: ``"model"`` or ``"table"`` when a start was given, else None.
        max_force_n: the force ceiling of the search, N (inf: none).
        start_clamped: True when a seeded start above the ceiling was lowered to it.
    """

    __repr__ = short_repr

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
    predicted_lift_force_n: float = math.nan
    start_force_n: float = math.nan
    start_in_training_range: bool | None = None
    start_source: str | None = None
    max_force_n: float = math.inf
    start_clamped: bool = False

    @property
    def seeded(self) -> bool:
        """True when the search was given a start (a model's or a table's L_f), even one that
        fell back to F_w (``start_in_training_range = False``)."""
        return self.start_source is not None

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
        names; ``growth``, ``max_attempts``, ``last_force_n`` and ``message`` follow, then
        ``predicted_lift_force_n``, ``start_force_n``, ``start_in_training_range`` and
        ``start_source`` (NaN / None unless the search was given a start, :attr:`seeded`; every
        row has them, so a table's columns do not depend on how it was run). Values are the
        result's own (an unbounded bracket keeps ``inf``); :meth:`table_row` makes a row.
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
            "predicted_lift_force_n": self.predicted_lift_force_n,
            "start_force_n": self.start_force_n,
            "start_in_training_range": self.start_in_training_range,
            "start_source": self.start_source,
            "max_force_n": self.max_force_n,
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
        if not math.isfinite(self.max_force_n):
            row["max_force_n"] = math.nan
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


def _validate(
    *, weight_n: float, friction_mu: float, object_id: str, max_force_n: float = math.inf
) -> None:
    """The object's W and μ under their rules (:mod:`deformctl.quantities`), and its ceiling."""
    if not (isinstance(max_force_n, float) and max_force_n == math.inf):  # inf: no ceiling
        MAX_FORCE_N.check(max_force_n, label=f"object {object_id!r}: max_force_n")
    WEIGHT_N.check(weight_n, label=f"object {object_id!r}: weight_n")
    FRICTION_MU.check(friction_mu, label=f"object {object_id!r}: friction_mu")


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
    seed: dict[str, Any] = field(default_factory=dict)  # the result's start_* fields
    max_force_n: float = math.inf  # no attempt above it (module doc)

    @property
    def obj(self) -> str:
        return f"object {self.object_id!r}"

    @property
    def out_of_attempts(self) -> bool:
        return len(self.trials) >= self.max_attempts

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
            max_force_n=self.max_force_n,
            **self.seed,
        )

    def no_safe_grip(self, why: str) -> LiftSearchResult:
        """The result of a search that would need a force above its ceiling."""
        return self.result(
            converged=False,
            message=(
                f"{self.obj}: no safe grip below the force ceiling {self.max_force_n:.6g} N: "
                f"{why} (F_w = {self.f_w_n:.6g} N, {len(self.trials)} attempts)"
            ),
        )

    def capped(self, force_n: float) -> float | None:
        """``force_n``, or the ceiling when it is above it and the ceiling was not tried yet
        (None: the ceiling slipped already, or the search is at it)."""
        if force_n <= self.max_force_n:
            return force_n
        if math.isfinite(self.low_n) and self.low_n >= self.max_force_n:
            return None
        return self.max_force_n

    def attempt(self, runner: TrialRunner, force_n: float) -> bool:
        """Run one trial at ``force_n`` and book it; True when it lifted."""
        index = len(self.trials)
        if not force_n <= self.max_force_n:  # the callers cap every force: a bug otherwise
            raise AssertionError(f"{force_n!r} N above the ceiling {self.max_force_n!r} N")
        try:
            outcome = runner(force_n, index)
        except DeformctlError as err:
            kept = f"{index} attempt{'' if index == 1 else 's'} kept"
            if isinstance(err, AttemptError):  # names the object, attempt and force itself
                detail = str(err)
            else:
                detail = f"{self.obj}: attempt {index} at {force_n:.6g} N: {err}"
            why = f"search aborted, {kept}: {detail}"
            partial = self.result(converged=False, message=why)
            cls = RigSearchAbortedError if isinstance(err, RigError) else SearchAbortedError
            raise cls(why, partial=partial) from err
        if not isinstance(outcome, TrialOutcome):
            raise TypeError(f"trial runner returned {type(outcome).__name__}, not TrialOutcome")
        self.trials.append(outcome)
        if outcome.lifted:
            self.high_n = force_n if not math.isfinite(self.high_n) else min(self.high_n, force_n)
        elif not math.isfinite(self.low_n) or force_n > self.low_n:
            self.low_n = force_n
        return bool(outcome.lifted)

    def ramp_up(self, runner: TrialRunner, start_n: float) -> LiftSearchResult | None:
        """The paper's ramp ``start * growth**k``, k = 0, 1, ... until a force lifts.

        Returns None when a force lifted, else the (unconverged) result to return.
        """
        k = 0
        if start_n > self.max_force_n:
            return self.no_safe_grip("F_w is above it")
        while True:
            try:
                force_n = start_n * self.growth**k
            except OverflowError:
                force_n = math.inf
            capped = self.capped(force_n)
            if capped is None:
                return self.no_safe_grip("the object slipped at the ceiling")
            force_n = capped
            if not math.isfinite(force_n):  # only with a huge budget and growth
                return self.result(
                    converged=False,
                    message=(
                        f"{self.obj}: did not lift; the ramp overflowed after "
                        f"{len(self.trials)} attempts"
                    ),
                )
            lifted = self.attempt(runner, force_n)
            self.ramp_attempts = len(self.trials)
            if lifted:
                return None
            if self.out_of_attempts:
                return self.result(
                    converged=False,
                    message=(
                        f"{self.obj}: did not lift within {self.max_attempts} attempts; "
                        f"last force tried {force_n:.6g} N slipped (F_w = {self.f_w_n:.6g} N)"
                    ),
                )
            k += 1

    def bisect(self, runner: TrialRunner) -> LiftSearchResult:
        """Bisect (low slipped, high lifted) until ``(high - low) / high <= tolerance_rel``."""
        if not math.isfinite(self.low_n):  # F_w lifted: nothing below it to try
            return self.result(converged=True, message=_found_message(self))
        while (self.high_n - self.low_n) / self.high_n > self.tolerance_rel:
            if self.out_of_attempts:
                return self.result(
                    converged=False,
                    message=(
                        f"{self.obj}: bracket [{self.low_n:.6g}, {self.high_n:.6g}] N did not "
                        f"reach tolerance {self.tolerance_rel:g} within {self.max_attempts} "
                        f"attempts; smallest force that lifted {self.high_n:.6g} N"
                    ),
                )
            mid_n = 0.5 * (self.low_n + self.high_n)
            if not self.low_n < mid_n < self.high_n:  # the bracket is as narrow as floats allow
                return self.result(
                    converged=False,
                    message=(
                        f"{self.obj}: tolerance {self.tolerance_rel:g} is below floating-point "
                        f"resolution at {self.high_n:.6g} N"
                    ),
                )
            self.attempt(runner, mid_n)
        return self.result(converged=True, message=_found_message(self))


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
    max_force_n: float = math.inf,
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
        max_force_n: the force ceiling, N (> 0; inf: none); see the module docstring.

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
        weight_n=weight_n, friction_mu=friction_mu, object_id=object_id, max_force_n=max_force_n
    )
    search = SearchOptions(
        protocol=protocol, growth=growth, tolerance_rel=tolerance_rel, max_attempts=max_attempts
    )
    return search_lift_force(runner, object_id, weight_n, friction_mu, search, max_force_n)


def search_lift_force(
    runner: TrialRunner,
    object_id: str,
    weight_n: float,
    friction_mu: float,
    search: SearchOptions,
    max_force_n: float,
) -> LiftSearchResult:
    """:func:`find_min_lift_force` with values already checked (the stage's: the object's W and
    μ by the catalog, the search by :class:`SearchOptions`, the ceiling by
    :mod:`deformctl.lift.ceiling`); ``search.protocol`` is ``refine`` or ``paper``."""
    s = _new_search(object_id, weight_n, friction_mu, search.protocol, search)
    s.max_force_n = float(max_force_n)
    # Phase 1: the paper's ramp F_w * growth**k until a force lifts.
    failed = s.ramp_up(runner, s.f_w_n)
    if failed is not None:
        return failed
    if s.protocol == "paper":
        return s.result(converged=True, message=_found_message(s))
    # Phase 2 (refine): bisect the last ramp bracket (low slipped, high lifted).
    return s.bisect(runner)


def validate_start_margin(margin: float) -> None:
    """Check a seeded search's start margin (:data:`deformctl.quantities.START_MARGIN`).

    Raises:
        UsageError: ``margin`` is not a finite number >= 1 (exit 2).
    """
    START_MARGIN.check(margin)


def find_min_lift_force_seeded(
    runner: TrialRunner,
    *,
    weight_n: float,
    friction_mu: float,
    predicted_lift_force_n: float,
    margin: float = DEFAULT_START_MARGIN,
    growth: float = DEFAULT_GROWTH,
    tolerance_rel: float = DEFAULT_TOLERANCE_REL,
    max_attempts: int = DEFAULT_MAX_ATTEMPTS,
    object_id: str = "object",
    source: str = "model",
    max_force_n: float = math.inf,
) -> LiftSearchResult:
    """The minimum lifting force, searched from a predicted L_f instead of from F_w.

    The paper's closing proposal: use the learnt L_f and keep iterative lifting only to correct
    its error. With ``P = predicted_lift_force_n`` and ``m = margin``:

    1. the first attempt is at ``S = max(F_w, P * m)``: a little above the prediction, so a good
       prediction lifts at once;
    2. if ``S`` lifts, the search goes **down** until one slips, never below F_w (if F_w lifts,
       ``L_f = F_w`` as in the other protocols); if ``S`` slips, it goes **up** until one lifts.
       The first step is ``m**2`` (down: to ``P / m``, the other edge of the band the margin
       puts around the prediction), and each further step squares the last one, up to
       ``growth``: ``m**2, m**4, m**8, ...`` then ``÷ growth`` / ``× growth`` as the paper's
       ramp (the first step is at least one tolerance, ``1 / (1 - tolerance_rel)``, a hair less). A
       prediction just outside the band so costs one step more, not a 20 % bracket; one far
       off is found about as fast as by the paper's ramp;
    3. then it bisects the bracket exactly as ``refine`` does, to ``tolerance_rel``, and reports
       the smallest force that was tried and lifted.

    So with the same tolerance the answer agrees with ``refine``'s within ``tolerance_rel`` (both
    brackets hold the threshold), and when the prediction is within the margin the search costs
    2 attempts plus ``ceil(log2((1 - m**-2) / tolerance_rel))`` bisections instead of the ramp
    from F_w plus ``log2((growth - 1) / tolerance_rel)``. The result is a
    :class:`LiftSearchResult` with ``protocol = "seeded"``, ``predicted_lift_force_n``,
    ``start_force_n``, ``start_in_training_range = True`` and ``start_source``; the rule for a
    search that runs out of attempts is the module's. The runner sees only grip forces.

    Args:
        runner, weight_n, friction_mu, growth, tolerance_rel, max_attempts, object_id: as for
            :func:`find_min_lift_force`.
        predicted_lift_force_n: the predicted L_f, N (finite, > 0).
        margin: the first attempt is at the prediction times this (>= 1).
        source: what predicted it (``"model"``, ``"table"``), recorded as ``start_source``.
        max_force_n: the force ceiling, N (module docstring); a start above it is clamped to it
            (``start_clamped``).

    Raises:
        UsageError: a parameter out of range (one-line message).
        SearchAbortedError: as for :func:`find_min_lift_force`.

    Example:
        >>> from deformctl.series import TrialOutcome
        >>> def runner(grip_force_n: float, attempt_index: int) -> TrialOutcome:
        ...     return TrialOutcome(grip_force_n, grip_force_n >= 7.0, 0.0)
        >>> r = find_min_lift_force_seeded(runner, weight_n=5.0, friction_mu=0.5,
        ...                                predicted_lift_force_n=7.05, margin=1.02)
        >>> r.attempts, r.converged, 7.0 <= r.lift_force_n <= 7.0 / (1 - 0.005)
        (5, True, True)
    """
    _validate(
        weight_n=weight_n, friction_mu=friction_mu, object_id=object_id, max_force_n=max_force_n
    )
    search = SearchOptions(growth=growth, tolerance_rel=tolerance_rel, max_attempts=max_attempts)
    validate_start_margin(margin)
    where = f"object {object_id!r}: "
    if isinstance(predicted_lift_force_n, bool) or not (
        isinstance(predicted_lift_force_n, int | float)
        and math.isfinite(predicted_lift_force_n)
        and predicted_lift_force_n > 0
    ):
        raise UsageError(
            f"{where}predicted lifting force must be a finite number > 0 N, "
            f"got {predicted_lift_force_n!r}"
        )
    start = SearchStart(float(predicted_lift_force_n), float(margin), source)
    return search_lift_force_seeded(
        runner, object_id, weight_n, friction_mu, search, max_force_n, start
    )


@dataclass(frozen=True)
class SearchStart:
    """A seeded search's start: the predicted L_f, N, the margin above it and its source."""

    predicted_lift_force_n: float
    margin: float
    source: str


def search_lift_force_seeded(
    runner: TrialRunner,
    object_id: str,
    weight_n: float,
    friction_mu: float,
    search: SearchOptions,
    max_force_n: float,
    start: SearchStart,
) -> LiftSearchResult:
    """:func:`find_min_lift_force_seeded` with values already checked (as
    :func:`search_lift_force`)."""
    predicted_lift_force_n, margin, source = (
        start.predicted_lift_force_n,
        start.margin,
        start.source,
    )
    max_attempts = search.max_attempts
    s = _new_search(object_id, weight_n, friction_mu, "seeded", search)
    s.max_force_n = float(max_force_n)
    wanted_n = max(s.f_w_n, float(predicted_lift_force_n) * float(margin))
    start_n = min(wanted_n, s.max_force_n)
    s.seed = {
        "predicted_lift_force_n": float(predicted_lift_force_n),
        "start_force_n": start_n,
        "start_in_training_range": True,
        "start_source": source,
        "start_clamped": start_n < wanted_n,
    }
    if s.f_w_n > s.max_force_n:
        return s.no_safe_grip("F_w is above it")
    s.attempt(runner, start_n)
    # the smallest step: one that leaves a bracket within the tolerance (with room for rounding)
    step = min(s.growth, max(float(margin) ** 2, 1 / (1 - 0.999 * s.tolerance_rel)))
    # Down while it lifts (never below F_w), or up while it slips, until the outcome flips.
    while not (math.isfinite(s.low_n) and math.isfinite(s.high_n)):
        going_down = math.isfinite(s.high_n)
        if going_down and s.high_n <= s.f_w_n:  # F_w lifted: L_f = F_w
            break
        force_n = max(s.f_w_n, s.high_n / step) if going_down else s.low_n * step
        capped = s.capped(force_n)
        if capped is None:
            return s.no_safe_grip("the object slipped at the ceiling")
        force_n = capped
        if s.out_of_attempts or not math.isfinite(force_n):
            last = s.trials[-1].grip_force_n
            why = (
                f"every force down to {s.high_n:.6g} N lifted; no bracket yet"
                if going_down
                else f"did not lift; last force tried {last:.6g} N slipped"
            )
            return s.result(
                converged=False,
                message=(
                    f"{s.obj}: {why} after {len(s.trials)} attempts (of {max_attempts}; "
                    f"F_w = {s.f_w_n:.6g} N)"
                ),
            )
        s.attempt(runner, force_n)
        s.ramp_attempts = len(s.trials)
        step = min(s.growth, step * step)
    s.ramp_attempts = len(s.trials)
    return s.bisect(runner)


def _new_search(
    object_id: str,
    weight_n: float,
    friction_mu: float,
    protocol: SearchProtocol,
    search: SearchOptions,
) -> _Search:
    return _Search(
        object_id=object_id,
        weight_n=float(weight_n),
        friction_mu=float(friction_mu),
        f_w_n=rigid_grip_force_n(float(weight_n), float(friction_mu)),
        protocol=protocol,
        growth=float(search.growth),
        tolerance_rel=float(search.tolerance_rel),
        max_attempts=search.max_attempts,
        trials=[],
    )


def _found_message(s: _Search) -> str:
    low = s.low_n if math.isfinite(s.low_n) else s.high_n
    seeded = ""
    if s.protocol == "seeded":
        seeded = (
            f" from the {s.seed['start_source']}'s {s.seed['predicted_lift_force_n']:.6g} N, "
            f"first attempt {s.seed['start_force_n']:.6g} N"
            + (" (clamped to the force ceiling)" if s.seed.get("start_clamped") else "")
        )
    return (
        f"{s.obj}: lifted at L_f = {s.high_n:.6g} N (F_w = {s.f_w_n:.6g} N, "
        f"bracket [{low:.6g}, {s.high_n:.6g}] N) after {len(s.trials)} attempts "
        f"({s.protocol}{seeded})"
    )
