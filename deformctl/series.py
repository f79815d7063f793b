"""In-memory time series shared by the stages: one squeeze, one lift attempt, and their records.

These are the contract between the simulator (:mod:`deformctl.sim`), the ingestion of real logs
(:mod:`deformctl.measure`), the estimators (:mod:`deformctl.characterize`), the lifting-force
search (:mod:`deformctl.lift`) and the artifact layer (:mod:`deformctl.artifacts`), which maps them
to MCAP messages one sample per message. Arrays are 1-D float64 of shape ``[n]`` on one time base,
in SI units named in the field.

Compression ``d`` is defined once, here: the *total* compression between the two palms,
``d(t) = gap(t0) - gap(t)`` where ``gap = palm_right_x_m - palm_left_x_m`` and ``t0`` is the first
sample of the squeeze (palms touching the unloaded object). It is positive when squeezed.

Beside the series: :class:`Rupture` (where a squeeze ruptured, as a squeeze log stores it; found
by :mod:`deformctl.squeeze.rupture`) and :class:`LiftAttempt` (one attempt's
:class:`TrialOutcome` as a lift log stores it).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from deformctl.arraytypes import FloatArray
from deformctl.reprs import short_repr

if TYPE_CHECKING:  # pragma: no cover - typing only
    from deformctl.scene import SceneFrames


def _as_1d(name: str, value: object, n: int | None) -> FloatArray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} has {arr.shape[0]} samples, time_s has {n}")
    return arr


@dataclass(frozen=True)
class SqueezeSeries:
    """One squeeze operation of one object.

    Attributes:
        object_id: catalog id of the squeezed object.
        squeeze_index: 0-based index of this squeeze among the object's squeezes.
        time_s: sample times since the start of the squeeze, s, shape ``[n]``, increasing.
        force_n: force felt by the manipulator (mean of the two palms' normal forces), N, ``[n]``.
        compression_m: total compression between the palms (see module docstring), m, ``[n]``.
        commanded_force_n: the commanded palm force, N, ``[n]``, when known.
        palm_left_x_m, palm_right_x_m: palm positions along the squeeze axis, m, when known.
        start_time_ns: the source's clock at the first sample, ns since the Unix epoch, when
            the recording has one (a ROS 2 bag's header stamps, a CSV export's absolute times);
            a squeeze log places the squeeze there. None for a simulated squeeze.
        scene: the squeeze's scene (:class:`deformctl.scene.SceneFrames`, on the time base of
            ``time_s``), when the simulator recorded one; a squeeze log writes it on ``/scene``
            and ``/palms``.
    """

    __repr__ = short_repr

    object_id: str
    squeeze_index: int
    time_s: FloatArray
    force_n: FloatArray
    compression_m: FloatArray
    commanded_force_n: FloatArray | None = None
    palm_left_x_m: FloatArray | None = None
    palm_right_x_m: FloatArray | None = None
    start_time_ns: int | None = None
    scene: SceneFrames | None = None

    def __post_init__(self) -> None:
        t = _as_1d("time_s", self.time_s, None)
        object.__setattr__(self, "time_s", t)
        n = t.shape[0]
        for name in ("force_n", "compression_m"):
            object.__setattr__(self, name, _as_1d(name, getattr(self, name), n))
        for name in ("commanded_force_n", "palm_left_x_m", "palm_right_x_m"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _as_1d(name, value, n))

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


@dataclass(frozen=True)
class LiftAttemptSeries:
    """The time series of one lift attempt at one grip force.

    Attributes:
        time_s: sample times since the start of the attempt, s, ``[n]``.
        palm_z_m: palm height above its start, m, ``[n]``.
        object_com_z_m: object centre-of-mass height above its start, m, ``[n]``.
        slip_m: accumulated sliding of the object against the palms, m, ``[n]``.
        friction_force_n: total tangential (vertical) force the two palms carry, N, ``[n]``.
        normal_force_n: normal force of each palm (force felt), N, ``[n]``.
    """

    __repr__ = short_repr

    time_s: FloatArray
    palm_z_m: FloatArray
    object_com_z_m: FloatArray
    slip_m: FloatArray
    friction_force_n: FloatArray
    normal_force_n: FloatArray

    def __post_init__(self) -> None:
        t = _as_1d("time_s", self.time_s, None)
        object.__setattr__(self, "time_s", t)
        n = t.shape[0]
        for name in ("palm_z_m", "object_com_z_m", "slip_m", "friction_force_n", "normal_force_n"):
            object.__setattr__(self, name, _as_1d(name, getattr(self, name), n))

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


@dataclass(frozen=True)
class TrialOutcome:
    """What one lift attempt at ``grip_force_n`` found; returned by every trial runner.

    Attributes:
        grip_force_n: the grip (normal) force of each palm, N.
        lifted: True when the object came up without slipping beyond the tolerance.
        slip_m: the slip distance the runner measured, m (NaN when the runner cannot tell).
        series: the attempt's time series, when the runner records one.
        details: runner-specific extras (e.g. camera frame paths from a rig), JSON-serialisable.
        start_time_ns: the wall clock when the attempt started, ns since the Unix epoch, for a
            runner that acts in real time (a rig); a lift log places the attempt there. None
            for a simulated attempt.
        scene: the attempt's scene (:class:`deformctl.scene.SceneFrames`, on the time base of
            ``series``), when the simulator recorded one; a lift log writes it on ``/scene``
            and ``/palms``.
    """

    __repr__ = short_repr

    grip_force_n: float
    lifted: bool
    slip_m: float
    series: LiftAttemptSeries | None = None
    details: dict[str, object] = field(default_factory=dict)
    start_time_ns: int | None = None
    scene: SceneFrames | None = None


@dataclass(frozen=True)
class LiftAttempt:
    """One lift attempt of one object: what a lift log stores per attempt.

    Attributes:
        object_id: catalog id of the object.
        attempt_index: 0-based index of the attempt among the object's attempts.
        outcome: what the attempt found (``outcome.series`` is the attempt's time series, when
            recorded; ``outcome.details`` must be JSON-serialisable).
    """

    __repr__ = short_repr

    object_id: str
    attempt_index: int
    outcome: TrialOutcome


@dataclass(frozen=True)
class Rupture:
    """Where a squeeze ruptured: the onset of its collapse (the force peak before it, unless the
    force fell from that peak before collapsing: :mod:`deformctl.squeeze.rupture`).

    Attributes:
        squeeze_index: the squeeze.
        time_s: time of the onset since the start of the squeeze, s.
        force_n: the force at the onset, N (the force the object could bear).
        compression_m: the compression at the onset, m.
        recording_time_s: time of the onset in the source recording, s (None when not known).
    """

    squeeze_index: int
    time_s: float
    force_n: float
    compression_m: float
    recording_time_s: float | None = None

    def to_record(self) -> dict[str, Any]:
        """The JSON record stored in a squeeze log's object row (key ``ruptures``)."""
        rec: dict[str, Any] = {
            "squeeze_index": self.squeeze_index,
            "time_s": self.time_s,
            "force_n": self.force_n,
            "compression_m": self.compression_m,
        }
        if self.recording_time_s is not None:
            rec["recording_time_s"] = self.recording_time_s
        return rec

    @classmethod
    def from_record(cls, rec: Any) -> Rupture | None:
        """A rupture from a stored record; None when the record is not one."""
        if not isinstance(rec, dict):
            return None
        try:
            rt = rec.get("recording_time_s")
            return cls(
                squeeze_index=int(rec["squeeze_index"]),
                time_s=float(rec["time_s"]),
                force_n=float(rec["force_n"]),
                compression_m=float(rec["compression_m"]),
                recording_time_s=None if rt is None else float(rt),
            )
        except (KeyError, TypeError, ValueError):
            return None

    def describe(self) -> str:
        """``squeeze #1 at 2.00 s, 10.1 N``."""
        return f"squeeze #{self.squeeze_index} at {self.time_s:.3g} s, {self.force_n:.3g} N"


def ruptures_from_object(obj: Any) -> list[Rupture]:
    """The ruptures a squeeze log's object row records (``ruptures``), in squeeze order."""
    raw = obj.get("ruptures") if isinstance(obj, dict) else None
    if not isinstance(raw, list):
        return []
    out = [r for r in (Rupture.from_record(x) for x in raw) if r is not None]
    return sorted(out, key=lambda r: r.squeeze_index)
