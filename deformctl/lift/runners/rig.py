"""Drive an external rig (a real robot's driver, or a stand-in) as a lift trial runner.

:class:`RigRunner` runs a command once per lift attempt, writes one JSON request to its stdin and
reads one JSON answer from its stdout. It is a :class:`deformctl.lift.search.TrialRunner`, so
:func:`deformctl.lift.search.find_min_lift_force` drives a rig exactly as it drives the
simulator; :func:`rig_runner_factory` makes one per catalog object for the ``lift`` stage.

Rig protocol, version 2
-----------------------
The command is given as a string (split with :func:`shlex.split`, never run through a shell) or
as an argument list. deformctl starts it once per attempt, in ``cwd`` when given.

Handshake (version 2). Before the first attempt of a run, deformctl starts the command once with
``{"handshake": true, "protocol_version": 2}`` on stdin. The rig must not move; it answers
``{"protocol_version": 2, "max_force_n": 120.0}``: the largest grip force it can and may apply,
N. No request of the run asks for more (:mod:`deformctl.lift.ceiling`). A rig that answers
anything else (a version-1 rig fails to read ``grip_force_n`` and exits non-zero, or answers
without ``max_force_n``) has stated no maximum: the absolute default
(:data:`~deformctl.lift.ceiling.DEFAULT_ABSOLUTE_MAX_FORCE_N`) applies. A ``max_force_n`` that is
not a finite number > 0 is a :class:`~deformctl.errors.RigError`.

Request (stdin, one JSON object, UTF-8, followed by a newline; then stdin is closed)::

    {"object_id": "sponge", "attempt_index": 0, "grip_force_n": 3.5,
     "weight_n": 2.1, "friction_mu": 0.3, "size_cm": [8.0, 5.0, 4.0]}

* ``object_id`` (string): the catalog id of the object on the rig.
* ``attempt_index`` (integer >= 0): 0-based index of the attempt within this object's search.
* ``grip_force_n`` (number > 0, N): the normal force each palm must apply during the lift.
* ``weight_n`` (number > 0, N) and ``friction_mu`` (number > 0): the object's catalog values.
* ``size_cm`` ([x, y, z] numbers, cm): the object's size, present only when the catalog knows it.
* ``max_force_n`` (number > 0, N): the object's force ceiling, never above the rig's absolute
  limit (always sent); no request asks for more, and a driver may refuse a ``grip_force_n``
  above it.

The rig grips the object with ``grip_force_n``, lifts it (the paper: by half its height), checks
for slip and answers.

Response (stdout, exactly one JSON object and nothing else; logs belong on stderr)::

    {"lifted": true, "slip_m": 0.0004, "message": "ok"}
    {"before_frame": "frames/a0_before.png", "after_frame": "frames/a0_after.png"}

* ``lifted`` (boolean): true when the object came up with the palms without slipping out.
* ``slip_m`` (number >= 0, m): how far the object slid against the palms. Required with
  ``lifted``; not allowed without it.
* ``before_frame``, ``after_frame`` (strings, optional, together): paths to camera frames taken
  before and after the lift; relative paths are relative to ``cwd``. They must exist when the answer
  is read. Without ``lifted``, deformctl decides ``lifted`` and ``slip_m`` from the frames with the
  ``slip_from_frames`` function it was given (the vision stage provides one); with ``lifted``, the
  frames are only recorded.
* ``message`` (string, optional): a note recorded with the attempt.
* Any other key is ignored (room for later versions).

Failures. A command that cannot be started, exits non-zero, runs longer than ``timeout_s`` (it is
killed with its whole process group), or answers with something that is not one JSON object
matching the contract above raises :class:`deformctl.errors.RigError` with one line naming the
object, the attempt, the force and what went wrong (for a non-zero exit: the last non-empty line of
stderr). The search wraps it so the attempts made so far are kept
(:class:`deformctl.lift.search.RigSearchAbortedError`).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shlex
import signal
import subprocess
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeGuard

from deformctl import jsonsafe
from deformctl.catalog import CatalogObject
from deformctl.errors import DeformctlError, RigError, UsageError
from deformctl.lift.ceiling import DEFAULT_ABSOLUTE_MAX_FORCE_N, ForceCeiling, absolute_limit
from deformctl.lift.options import DEFAULT_RIG_TIMEOUT_S
from deformctl.lift.search import AttemptError, TrialRunner
from deformctl.lift.stage import RunnerFactory
from deformctl.quantities import FRICTION_MU, RIG_TIMEOUT_S, SIZE_CM, WEIGHT_N
from deformctl.series import TrialOutcome

RIG_PROTOCOL_VERSION = 2
#: What deformctl sends to ask the rig for its maximum force (module doc).
HANDSHAKE_REQUEST: dict[str, Any] = {"handshake": True, "protocol_version": RIG_PROTOCOL_VERSION}

SlipFromFrames = Callable[[Path, Path], tuple[bool, float]]
"""``(before_frame, after_frame) -> (lifted, slip_m)``: decide a lift from two camera frames."""

_MAX_SHOWN_CHARS = 120  # how much of a bad answer or stderr line goes into an error message

__all__ = [
    "DEFAULT_RIG_TIMEOUT_S",
    "FRAMES_SLIP_CRITERION",
    "HANDSHAKE_REQUEST",
    "RIG_PROTOCOL_VERSION",
    "RIG_SLIP_CRITERION",
    "RigAttemptError",
    "RigRunner",
    "SlipFromFrames",
    "parse_rig_response",
    "rig_handshake",
    "rig_object",
    "rig_runner_factory",
]


#: After killing a timed-out rig's process group: how long to wait for its pipes to close, s
#: (a descendant that started its own session keeps them open; they are then closed unread).
_DRAIN_S = 2.0
RIG_SLIP_CRITERION = "rig"  #: ``slip_criterion`` of rows whose outcome the rig reported itself
#: ``slip_criterion`` when deformctl judges rig frames (a rig answering ``lifted`` still decides).
FRAMES_SLIP_CRITERION = "frames"
#: The lift-profile columns a rig run leaves empty (the rig's own protocol is unknown).
_PROFILE_COLUMNS = ("lift_accel_m_s2", "lift_speed_m_s", "lift_height_m", "slip_tolerance_m")


class RigAttemptError(RigError, AttemptError):
    """One rig attempt failed; the message names the object, the attempt and the force.

    Attributes:
        object_id: the object on the rig.
        attempt_index: the 0-based attempt index sent to the rig.
        grip_force_n: the grip force of the failed attempt, N.
        reason: what went wrong, without the attempt context.
    """

    def __init__(
        self, object_id: str, attempt_index: int, grip_force_n: float, reason: str
    ) -> None:
        self.object_id = object_id
        self.attempt_index = attempt_index
        self.grip_force_n = grip_force_n
        self.reason = reason
        super().__init__(
            f"rig: object {object_id!r} attempt_index {attempt_index} "
            f"at {grip_force_n:.6g} N: {reason}"
        )


def _is_number(value: object) -> TypeGuard[int | float]:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _is_positive(value: object) -> TypeGuard[int | float]:
    return _is_number(value) and math.isfinite(value) and value > 0


def _shorten(text: str) -> str:
    text = " ".join(text.split())
    return text if len(text) <= _MAX_SHOWN_CHARS else text[: _MAX_SHOWN_CHARS - 3] + "..."


def parse_rig_response(text: str) -> dict[str, Any]:
    """Parse and check one rig answer; return it as a dict.

    Args:
        text: the rig's whole stdout.

    Returns:
        The answer object. When ``lifted`` is present, ``slip_m`` is a finite number >= 0.

    Raises:
        ValueError: the text is not one JSON object matching the response contract; the message
            says what is wrong (the caller adds the attempt context).
    """
    if not text.strip():
        raise ValueError("empty answer on stdout (expected one JSON object)")
    try:
        answer = jsonsafe.loads(text)
    except ValueError as err:
        raise ValueError(f"answer is not valid JSON ({err}): {_shorten(text)!r}") from None
    if not isinstance(answer, dict):
        raise ValueError(f"answer must be a JSON object, got {type(answer).__name__}")
    if "lifted" in answer:
        if not isinstance(answer["lifted"], bool):
            raise ValueError(f"'lifted' must be true or false, got {answer['lifted']!r}")
        if "slip_m" not in answer:
            raise ValueError("'slip_m' is required with 'lifted'")
        slip = answer["slip_m"]
        if not _is_number(slip) or not math.isfinite(slip) or slip < 0:
            raise ValueError(f"'slip_m' must be a number >= 0 (m), got {slip!r}")
    elif "slip_m" in answer:
        raise ValueError("'slip_m' given without 'lifted'")
    has_before, has_after = "before_frame" in answer, "after_frame" in answer
    if has_before != has_after:
        raise ValueError("'before_frame' and 'after_frame' must be given together")
    for key in ("before_frame", "after_frame"):
        if key in answer and not (isinstance(answer[key], str) and answer[key]):
            raise ValueError(f"{key!r} must be a non-empty path string, got {answer[key]!r}")
    if "lifted" not in answer and not has_before:
        raise ValueError("answer has neither 'lifted' nor 'before_frame'/'after_frame'")
    if "message" in answer and not isinstance(answer["message"], str):
        raise ValueError(f"'message' must be a string, got {answer['message']!r}")
    return answer


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return _shorten(lines[-1]) if lines else "(no stderr)"


class RigRunner:
    """A :class:`~deformctl.lift.TrialRunner` that asks an external command for each attempt.

    Args:
        command: the rig command, a string (split with :func:`shlex.split`) or an argument list.
        timeout_s: the longest one attempt may take, s (> 0); the command is killed after it.
        object: the object on the rig: ``object_id`` (str), ``weight_n`` (N, > 0),
            ``friction_mu`` (> 0) and optionally ``size_cm`` ([x, y, z], cm). Other keys are
            ignored.
        cwd: the directory to run the command in (and to resolve relative frame paths against);
            the current directory when None.
        slip_from_frames: decides ``(lifted, slip_m)`` from ``(before_path, after_path)`` for a rig
            that answers with frames only; without it such an answer is a :class:`RigError`.
        absolute_max_force_n: the rig's absolute limit, N (its handshake's ``max_force_n``;
            default :data:`~deformctl.lift.ceiling.DEFAULT_ABSOLUTE_MAX_FORCE_N`): no request
            above it (nor above the object's ``max_force_n``) is ever sent.

    Raises:
        UsageError: an empty command, a bad ``timeout_s``, a bad object description or a bad
            ``absolute_max_force_n``.

    Example:
        >>> import sys
        >>> runner = RigRunner([sys.executable, "rig.py"], timeout_s=30,
        ...                    object={"object_id": "A", "weight_n": 2.0, "friction_mu": 0.5})
    """

    def __init__(
        self,
        command: str | Sequence[str],
        *,
        timeout_s: float,
        object: Mapping[str, Any],
        cwd: str | os.PathLike[str] | None = None,
        slip_from_frames: SlipFromFrames | None = None,
        absolute_max_force_n: float = DEFAULT_ABSOLUTE_MAX_FORCE_N,
    ) -> None:
        argv = shlex.split(command) if isinstance(command, str) else [str(a) for a in command]
        if not argv:
            raise UsageError("rig command is empty")
        RIG_TIMEOUT_S.check(timeout_s)
        self.absolute_max_force_n = absolute_limit(absolute_max_force_n).max_force_n
        self.argv: list[str] = argv
        self.timeout_s = float(timeout_s)
        self.cwd: Path | None = None if cwd is None else Path(cwd)
        self.slip_from_frames = slip_from_frames
        self.object_id, self._object_fields = self._check_object(object)
        own = self._object_fields.get("max_force_n", math.inf)
        self._object_fields["max_force_n"] = min(own, self.absolute_max_force_n)

    @staticmethod
    def _check_object(obj: Mapping[str, Any]) -> tuple[str, dict[str, Any]]:
        object_id = obj.get("object_id")
        if not isinstance(object_id, str) or not object_id:
            raise UsageError(f"rig object needs a non-empty string 'object_id', got {object_id!r}")
        fields: dict[str, Any] = {}
        for key, quantity in (("weight_n", WEIGHT_N), ("friction_mu", FRICTION_MU)):
            fields[key] = quantity.check(obj.get(key), label=f"object {object_id!r}: {key}")
        size = obj.get("size_cm")
        if size is not None:
            if not (isinstance(size, Sequence) and not isinstance(size, str) and len(size) == 3):
                raise UsageError(
                    f"object {object_id!r}: size_cm must be three numbers (x, y, z), got {size!r}"
                )
            label = f"object {object_id!r}: size_cm"
            fields["size_cm"] = [SIZE_CM.check(v, label=label) for v in size]
        ceiling = obj.get("max_force_n")
        if ceiling is not None and not (isinstance(ceiling, float) and math.isnan(ceiling)):
            if not _is_positive(ceiling):
                raise UsageError(
                    f"object {object_id!r}: max_force_n must be a number > 0, got {ceiling!r}"
                )
            fields["max_force_n"] = float(ceiling)
        return object_id, fields

    def request(self, grip_force_n: float, attempt_index: int) -> dict[str, Any]:
        """The JSON request (as a dict) sent for one attempt."""
        req: dict[str, Any] = {
            "object_id": self.object_id,
            "attempt_index": int(attempt_index),
            "grip_force_n": float(grip_force_n),
            "weight_n": self._object_fields["weight_n"],
            "friction_mu": self._object_fields["friction_mu"],
        }
        if "size_cm" in self._object_fields:
            req["size_cm"] = list(self._object_fields["size_cm"])
        req["max_force_n"] = self._object_fields["max_force_n"]
        return req

    def __call__(self, grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        """Run the rig command for one attempt and turn its answer into a TrialOutcome.

        Raises:
            RigAttemptError: the command could not start, failed, timed out or answered badly.
        """
        where = (attempt_index, grip_force_n)
        ceiling = self._object_fields["max_force_n"]
        if not grip_force_n <= ceiling:  # the search never asks: refuse rather than send it
            raise self._error(where, f"grip force above the force ceiling {ceiling:.6g} N")
        payload = json.dumps(self.request(grip_force_n, attempt_index)) + "\n"
        started_ns = time.time_ns()  # the lift log places the attempt on the wall clock
        stdout = self._run(payload, where)
        try:
            answer = parse_rig_response(stdout)
        except ValueError as err:
            raise self._error(where, str(err)) from None
        details: dict[str, object] = {}
        if "message" in answer:
            details["message"] = answer["message"]
        frames: tuple[Path, Path] | None = None
        if "before_frame" in answer:
            frames = (
                self._frame(answer["before_frame"], where),
                self._frame(answer["after_frame"], where),
            )
            details["before_frame"] = str(frames[0])
            details["after_frame"] = str(frames[1])
        if "lifted" in answer:
            lifted, slip_m = bool(answer["lifted"]), float(answer["slip_m"])
            details["slip_source"] = "rig"
        else:
            assert frames is not None  # parse_rig_response guarantees frames here
            lifted, slip_m = self._from_frames(frames, where)
            details["slip_source"] = "frames"
        return TrialOutcome(
            float(grip_force_n), lifted, slip_m, None, details, start_time_ns=started_ns
        )

    def _error(self, where: tuple[int, float], reason: str) -> RigAttemptError:
        return RigAttemptError(self.object_id, where[0], where[1], reason)

    def _run(self, payload: str, where: tuple[int, float]) -> str:
        try:
            proc = subprocess.Popen(
                self.argv,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                cwd=self.cwd,
                start_new_session=True,  # own process group, so a time-out kills its children too
            )
        except OSError as err:
            raise self._error(
                where, f"cannot run {self.argv[0]!r}: {err.strerror or err}"
            ) from None
        try:
            out_b, err_b = proc.communicate(payload.encode("utf-8"), timeout=self.timeout_s)
        except subprocess.TimeoutExpired:
            self._kill(proc)
            raise self._error(where, f"no answer within {self.timeout_s:g} s (killed)") from None
        stdout = out_b.decode("utf-8", errors="replace")
        stderr = err_b.decode("utf-8", errors="replace")
        if proc.returncode != 0:
            status = (
                f"killed by signal {-proc.returncode}"
                if proc.returncode < 0
                else f"exited with status {proc.returncode}"
            )
            raise self._error(where, f"{status}: {_last_line(stderr)}")
        return stdout

    @staticmethod
    def _kill(proc: subprocess.Popen[bytes]) -> None:
        try:
            if hasattr(os, "killpg"):
                os.killpg(proc.pid, signal.SIGKILL)
            else:  # pragma: no cover - non-POSIX
                proc.kill()
        except ProcessLookupError:  # pragma: no cover - it ended on its own meanwhile
            pass
        try:  # a descendant that left the group (setsid) may still hold the pipes open
            proc.communicate(timeout=_DRAIN_S)
        except subprocess.TimeoutExpired:
            for pipe in (proc.stdin, proc.stdout, proc.stderr):
                if pipe is not None:
                    with contextlib.suppress(OSError):
                        pipe.close()
            proc.wait(timeout=_DRAIN_S)

    def _frame(self, raw: str, where: tuple[int, float]) -> Path:
        path = Path(raw)
        if not path.is_absolute():
            path = (self.cwd or Path.cwd()) / path
        if not path.is_file():
            raise self._error(where, f"frame {raw!r} does not exist")
        return path

    def _from_frames(
        self, frames: tuple[Path, Path], where: tuple[int, float]
    ) -> tuple[bool, float]:
        if self.slip_from_frames is None:
            raise self._error(
                where,
                "answer has frames but no 'lifted', and no slip-from-frames function was given",
            )
        try:
            lifted, slip_m = self.slip_from_frames(*frames)
        except DeformctlError as err:
            raise self._error(where, f"slip from frames failed: {err}") from err
        return bool(lifted), float(slip_m)


def rig_handshake(
    command: str | Sequence[str],
    *,
    timeout_s: float,
    cwd: str | os.PathLike[str] | None = None,
) -> ForceCeiling:
    """Ask the rig for its maximum force (the handshake of the module doc); its absolute limit.

    Returns:
        :func:`~deformctl.lift.ceiling.absolute_limit` of the stated maximum, or of None (the
        default) when the rig states none: it cannot be started, exits non-zero, runs past
        ``timeout_s``, or answers without ``max_force_n`` (a version-1 rig).

    Raises:
        RigError: the answer states a ``max_force_n`` that is not a finite number > 0.
    """
    argv = shlex.split(command) if isinstance(command, str) else [str(a) for a in command]
    try:
        proc = subprocess.Popen(
            argv,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            cwd=None if cwd is None else Path(cwd),
            start_new_session=True,
        )
    except OSError:  # the first attempt reports it, as it always did
        return absolute_limit(None)
    payload = json.dumps(HANDSHAKE_REQUEST) + "\n"
    try:
        out_b, _ = proc.communicate(payload.encode("utf-8"), timeout=float(timeout_s))
    except subprocess.TimeoutExpired:
        RigRunner._kill(proc)
        return absolute_limit(None)
    except OSError:  # it closed stdin without reading (a version-1 rig that gave up)
        proc.kill()
        proc.communicate()
        return absolute_limit(None)
    if proc.returncode != 0:
        return absolute_limit(None)
    try:
        answer = jsonsafe.loads(out_b.decode("utf-8", errors="replace"))
    except ValueError:
        return absolute_limit(None)
    if not isinstance(answer, dict) or "max_force_n" not in answer:
        return absolute_limit(None)
    stated = answer["max_force_n"]
    if not _is_positive(stated):
        raise RigError(
            f"rig handshake: max_force_n must be a finite number > 0 (N), got {stated!r}"
        )
    return absolute_limit(float(stated))


def rig_object(obj: CatalogObject, max_force_n: float) -> dict[str, Any]:
    """The object description a :class:`RigRunner` sends: id, W, mu, size (cm) and the force
    ceiling ``max_force_n`` (N) the lift gave the object."""
    return {
        "object_id": obj.object_id,
        "weight_n": obj.weight_n,
        "friction_mu": obj.friction_mu,
        "size_cm": list(obj.size_cm),
        "max_force_n": max_force_n,
    }


def rig_runner_factory(
    command: str | Sequence[str],
    *,
    timeout_s: float,
    cwd: str | os.PathLike[str] | None = None,
    slip_from_frames: SlipFromFrames | None = None,
) -> RunnerFactory:
    """A :class:`~deformctl.lift.stage.RunnerFactory` for an external rig command (module doc).

    Each object gets its own :class:`RigRunner`; the command runs once per attempt.
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
    RIG_TIMEOUT_S.check(timeout_s)

    stated: list[ForceCeiling] = []  # the handshake's answer, asked once per factory

    def limit() -> ForceCeiling:
        if not stated:
            stated.append(rig_handshake(argv, timeout_s=float(timeout_s), cwd=cwd))
        return stated[0]

    def make(obj: CatalogObject, max_force_n: float) -> TrialRunner:
        return RigRunner(
            argv,
            timeout_s=float(timeout_s),
            object=rig_object(obj, max_force_n),
            cwd=cwd,
            slip_from_frames=slip_from_frames,
            absolute_max_force_n=limit().max_force_n,
        )

    frame_options = dict(getattr(slip_from_frames, "keywords", None) or {})

    def row_fields(obj: CatalogObject) -> Mapping[str, object]:
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
        journal=True,  # every attempt costs a grip on a real robot: keep them as they happen
        absolute_limit=limit,
    )
