"""Squeeze logs from real rigs (ROS 2 MCAP bags, CSV exports) and the simulator.

:func:`simulate_squeezes` squeezes catalog objects in :mod:`deformctl.sim` (``measure --sim``;
see its docstring for the default force rule); at scale, :class:`SimulateCatalogTask` is the sweep
task of one object and :func:`simulate_catalog_sweep` runs a catalog into a dataset directory.
For real rigs:

Both readers (:func:`read_ros2_bag`, :func:`read_csv_export`) return a :class:`Recording`:
the squeezes as ``list[SqueezeSeries]`` in SI units with compression ``d`` as defined in
:mod:`deformctl.series` (total compression between the palms, positive when squeezed), plus the
source streams' sample rates, which ``measure`` stores with the object so that ``characterize``
can widen its differentiation window for slow position topics. :func:`squeeze_from_ros2_bag`
and :func:`squeeze_from_csv` return the squeezes alone.

**Where the compression comes from.** A position signal is one of:

* ``gap``: the distance between the palms (e.g. a parallel gripper's opening width):
  ``d = gap(t0) − gap(t)``.
* ``palm``: the travel of one palm along the squeeze axis while its partner moves symmetrically
  (mirror-image arms, as in the paper's rig): ``d = 2 · s · (p(t) − p(t0))``, with the sign
  ``s = ±1`` chosen so that ``d`` is positive at the sample of peak force (so it does not matter
  whether the logged palm is the left or the right one).
* ``compression`` (CSV only): the compression itself, e.g. a testing machine's crosshead travel
  against a fixed anvil: ``d = c(t) − c(t0)``.

The zero of compression is the median position over the recording's lead-in (the samples from
the start of the force/position overlap until the force first reaches half the segmentation
threshold), so the recording must start with the palms touching the unloaded object
(``compression_zero="lead_in"``, the default for bags, whose position noise would otherwise
enter every compression through one sample), or the first sample (``"first"``, the default for
CSV exports of testing machines, which start at the contact point). Every squeeze in a recording
is referenced to that same zero: an object that has not fully recovered between squeezes is
still measured from its unloaded shape.

**Segmentation.** With ``segment=True`` a recording is split into squeezes where the force rises
above ``force_threshold_frac`` of the recording's peak force and falls back: runs above the
threshold that are closer than ``min_gap_s`` are merged, runs shorter than ``min_squeeze_s`` are
dropped, and the recording is cut at the midpoints of the quiet stretches between runs, so each
squeeze includes its unloaded lead-in and relaxation. With ``segment=False`` the recording is
one squeeze. Bags default to segmenting (a rig logs several squeezes per object, the paper
three); CSV exports default to one squeeze per file (one test per export).

**Force.** For bags, ``geometry_msgs/msg/WrenchStamped`` ``wrench.force.<axis>``: the force
felt is its magnitude; with two wrench topics (one per palm) it is the mean of the two palms'
magnitudes, the second palm interpolated onto the first palm's timestamps.

**Alignment.** Streams are aligned by their header stamps; position is linearly interpolated
onto the force timestamps inside the overlap of the two streams. Samples outside the overlap are
dropped.

**Checks and cuts.** A recording whose sample rate, peak force, peak compression, force axis or
compression sign a unit, axis or sign mistake explains is refused with the likely fix
(:mod:`deformctl.plausibility`). Every squeeze is then cut at a rupture and reduced to the
``phase`` asked for (:mod:`deformctl.phases`); the :class:`Recording` carries the ruptures, which
the log stores with the object (:meth:`Recording.log_fields`).
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import io
import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd
import pyarrow as pa

from deformctl.artifacts import check_output_path, read_catalog, write_squeeze_log
from deformctl.artifacts.dataset import LogPartWriter, dataset_fingerprint
from deformctl.artifacts.io import note_input
from deformctl.artifacts.mcaplog import LOG_EPOCH_NS
from deformctl.artifacts.provenance import Provenance, input_digest
from deformctl.catalog import CatalogObject, catalog_objects, select_objects
from deformctl.errors import InputDataError, MissingInputError, UsageError
from deformctl.parallel import (
    SweepOptions,
    SweepSummary,
    TaskOutput,
    map_in_order,
    run_sweep,
    single_file_workers,
)
from deformctl.phases import PHASES, Phase, Rupture, cut_rupture, phase_slice, slice_squeeze
from deformctl.plausibility import (
    MAX_PEAK_FORCE_N,
    check_force_axis,
    check_peak_compression,
    check_peak_force,
    check_sample_rate,
    compression_has_wrong_sign,
    compression_limit_m,
    compression_target_m,
    rate_ok,
    suggest_unit,
)
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.units import NS_PER_S

if TYPE_CHECKING:  # pragma: no cover - typing only; the simulator is imported when used
    from deformctl.sim import ObjectSpec, SimSettings

Axis = Literal["x", "y", "z"]
PositionIs = Literal["gap", "palm"]
CompressionZero = Literal["first", "lead_in"]
IncreasesWhen = Literal["closing", "opening"]
INCREASES_WHEN: tuple[str, ...] = ("closing", "opening")

WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"

#: Segmentation defaults (see the module docstring).
DEFAULT_FORCE_THRESHOLD_FRAC = 0.1
DEFAULT_MIN_GAP_S = 0.1
DEFAULT_MIN_SQUEEZE_S = 0.2

#: Multiply a value in the unit by the factor to get SI; keys are lower-case unit names.
TIME_UNITS_S: dict[str, float] = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9}
FORCE_UNITS_N: dict[str, float] = {"n": 1.0, "kn": 1e3, "mn": 1e-3, "lbf": 4.4482216152605}
LENGTH_UNITS_M: dict[str, float] = {
    "m": 1.0,
    "cm": 1e-2,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
    "in": 0.0254,
}
_UNITS_BY_KEY: dict[str, dict[str, float]] = {
    "time": TIME_UNITS_S,
    "force": FORCE_UNITS_N,
    "position": LENGTH_UNITS_M,
    "gap": LENGTH_UNITS_M,
    "compression": LENGTH_UNITS_M,
}
_POSITION_KEYS = ("position", "gap", "compression")
#: A CSV time column whose first value (in s, after ``--units``) is at least this is Unix time
#: (2000-01-01T00:00:00Z): the squeeze log keeps those times as its ``log_time``.
ABSOLUTE_TIME_MIN_S = 946_684_800.0


@dataclass(frozen=True)
class Recording:
    """The squeezes read from one recording, with the sample rates of its source streams.

    Attributes:
        squeezes: the squeezes, in SI, as returned by :func:`squeeze_from_ros2_bag` /
            :func:`squeeze_from_csv`.
        force_rate_hz: median sample rate of the (first) force stream, Hz.
        position_rate_hz: median sample rate of the position stream, Hz. Position is
            interpolated onto the force timestamps, so a slow position stream carries fewer
            independent samples than the squeezes have; ``characterize`` widens its
            differentiation window for it (see :func:`deformctl.characterize.default_window_s`).
    """

    squeezes: list[SqueezeSeries]
    force_rate_hz: float
    position_rate_hz: float
    source: str = ""
    phase: str = "all"
    ruptures: tuple[Rupture, ...] = ()

    def log_fields(self) -> dict[str, Any]:
        """What a squeeze log stores with the object besides its catalog values.

        ``force_rate_hz`` and ``position_rate_hz``; ``source`` (``ros2_bag`` or ``csv``: the
        log is a rig recording, which ``characterize`` fits with a preload by default),
        ``phase`` and ``ruptures`` (the points where squeezes were cut, see
        :class:`deformctl.phases.Rupture`).
        """
        out: dict[str, Any] = {
            "force_rate_hz": self.force_rate_hz,
            "position_rate_hz": self.position_rate_hz,
        }
        if self.source:
            out["source"] = self.source
        if self.phase != "all":
            out["phase"] = self.phase
        if self.ruptures:
            out["ruptures"] = [r.to_record() for r in self.ruptures]
        return out


def _rate_hz(time_s: FloatArray) -> float:
    """Median sample rate of increasing timestamps ``[n]`` (n ≥ 2), Hz."""
    return float(1.0 / np.median(np.diff(time_s)))


# ---------------------------------------------------------------------------------------------
# shared helpers
# ---------------------------------------------------------------------------------------------


def _check_stream(name: str, time_s: FloatArray, values: FloatArray, path: str) -> None:
    """Refuse NaN samples and timestamps that do not strictly increase."""
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise InputDataError(
            f"{name}: {bad.size} NaN/inf sample(s), first at index {int(bad[0])}", path=path
        )
    steps = np.diff(time_s)
    back = np.flatnonzero(steps <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise InputDataError(
            f"{name}: non-monotonic timestamps, sample {i} at {time_s[i]:.9f} s does not follow "
            f"sample {i - 1} at {time_s[i - 1]:.9f} s",
            path=path,
        )
    if time_s.shape[0] < 2:
        raise InputDataError(f"{name}: only {time_s.shape[0]} sample(s)", path=path)


def _unloaded_reference(position: FloatArray, force_n: FloatArray, threshold_frac: float) -> float:
    """Position of the unloaded object: the median over the lead-in before the first squeeze.

    The lead-in is the run of samples from the start whose force stays below half the
    segmentation threshold; one noisy sample would put its noise into every compression.
    """
    peak = float(np.max(force_n))
    loaded = np.flatnonzero(force_n >= 0.5 * threshold_frac * peak)
    n_lead = int(loaded[0]) if loaded.size else position.shape[0]
    return float(np.median(position[: max(n_lead, 1)]))


def _convention(kind: str, increases_when: str | None) -> str | None:
    """When the position grows for a position kind: ``closing``, ``opening`` or None (auto)."""
    if increases_when is not None:
        if increases_when not in INCREASES_WHEN:
            raise UsageError(
                f"position_increases_when must be closing or opening, got {increases_when!r}"
            )
        return increases_when
    return {"gap": "opening", "compression": "closing"}.get(kind)


def _compression(
    position: FloatArray,
    force_n: FloatArray,
    kind: str,
    path: str,
    threshold_frac: float,
    zero: str,
    increases_when: str | None = None,
    what: str = "the position",
) -> FloatArray:
    """Compression ``[n]`` (m) from a gap, a symmetric palm's travel, or a direct compression.

    ``increases_when`` says whether the position grows as the gripper closes or opens; None
    means the kind's convention (a gap grows when opening, a compression when closing) or, for
    one palm's travel, the sign that makes d positive at the peak force.

    Raises:
        InputDataError: the position never moves, or d is negative where the object is loaded
            (the message names the ``--position-increases-when`` that flips it).
    """
    if zero == "first":
        rel = position - position[0]
    elif zero == "lead_in":
        rel = position - _unloaded_reference(position, force_n, threshold_frac)
    else:
        raise UsageError(f"compression_zero must be 'first' or 'lead_in', got {zero!r}")
    if kind not in ("gap", "palm", "compression"):
        raise UsageError(f"unknown position kind {kind!r}; expected 'gap' or 'palm'")
    convention = _convention(kind, increases_when)
    if convention is None:  # one palm, auto: positive at the peak force
        peak = int(np.argmax(force_n))
        sign = 1.0 if rel[peak] >= 0 else -1.0
    else:
        sign = 1.0 if convention == "closing" else -1.0
    d = (2.0 if kind == "palm" else 1.0) * sign * rel
    if float(np.max(np.abs(d))) <= 0.0:
        raise InputDataError(
            "no compression: the position signal never moves (zero displacement)", path=path
        )
    if convention is not None and compression_has_wrong_sign(d, force_n):
        other = "opening" if convention == "closing" else "closing"
        loaded = float(np.median(d[force_n >= 0.5 * float(np.max(force_n))]))
        raise InputDataError(
            f"compression has the wrong sign: {what} moves the other way as the force rises "
            f"(compression {loaded:.3g} m where loaded); if it grows as the gripper "
            f"{'closes' if other == 'closing' else 'opens'}, pass --position-increases-when "
            f"{other}",
            path=path,
        )
    return np.asarray(d, dtype=np.float64)


def segment_squeezes(
    time_s: FloatArray,
    force_n: FloatArray,
    *,
    force_threshold_frac: float = DEFAULT_FORCE_THRESHOLD_FRAC,
    min_gap_s: float = DEFAULT_MIN_GAP_S,
    min_squeeze_s: float = DEFAULT_MIN_SQUEEZE_S,
) -> list[slice]:
    """Index ranges of the squeezes in a recording (see the module docstring).

    Args:
        time_s: sample times ``[n]``, s, increasing.
        force_n: force felt ``[n]``, N.
        force_threshold_frac: threshold as a fraction of the recording's peak force.
        min_gap_s: runs above the threshold closer than this are one squeeze, s.
        min_squeeze_s: runs shorter than this are ignored, s.

    Returns:
        Slices into the arrays, in time order; empty when no squeeze is found.
    """
    peak = float(np.max(force_n))
    if not peak > 0:
        return []
    above = force_n > force_threshold_frac * peak
    edges = np.diff(above.astype(np.int8))
    starts: list[int] = (np.flatnonzero(edges == 1) + 1).tolist()
    stops: list[int] = (np.flatnonzero(edges == -1) + 1).tolist()
    if above[0]:
        starts.insert(0, 0)
    if above[-1]:
        stops.append(above.shape[0])
    runs: list[list[int]] = []
    for a, b in zip(starts, stops, strict=True):
        if runs and time_s[a] - time_s[runs[-1][1] - 1] < min_gap_s:
            runs[-1][1] = b
        else:
            runs.append([a, b])
    runs = [r for r in runs if time_s[r[1] - 1] - time_s[r[0]] >= min_squeeze_s]
    if not runs:
        return []
    cuts = [0]
    for (_, b0), (a1, _) in itertools.pairwise(runs):
        cuts.append((b0 + a1) // 2)
    cuts.append(time_s.shape[0])
    return [slice(cuts[i], cuts[i + 1]) for i in range(len(runs))]


def _to_squeezes(
    time_s: FloatArray,
    force_n: FloatArray,
    compression_m: FloatArray,
    *,
    object_id: str,
    segment: bool,
    path: str,
    force_threshold_frac: float,
    min_gap_s: float,
    min_squeeze_s: float,
    phase: str = "all",
    window_s: float | None = None,
    clock_origin_ns: int | None = None,
) -> tuple[list[SqueezeSeries], list[Rupture]]:
    """Cut a recording into squeezes, each up to its rupture and reduced to ``phase``.

    ``clock_origin_ns`` is the source's clock at ``time_s = 0`` (ns since the Unix epoch) when
    the recording has one: each squeeze then carries its first sample's ``start_time_ns``.

    Returns:
        The squeezes and the ruptures found (one per ruptured squeeze, recording times set).

    Raises:
        InputDataError: no squeeze found, or ``phase="unloading"`` on a squeeze that ruptured.
        UsageError: an unknown phase.
    """
    from deformctl.characterize import DEFAULT_WINDOW_S

    if phase not in PHASES:
        raise UsageError(f"--phase must be one of {', '.join(PHASES)}, got {phase!r}")
    window = DEFAULT_WINDOW_S if window_s is None else window_s
    if segment:
        slices = segment_squeezes(
            time_s,
            force_n,
            force_threshold_frac=force_threshold_frac,
            min_gap_s=min_gap_s,
            min_squeeze_s=min_squeeze_s,
        )
        if not slices:
            raise InputDataError(
                f"no squeeze found: the force never stays above {force_threshold_frac:g} of its "
                f"peak for {min_squeeze_s:g} s",
                path=path,
            )
    else:
        slices = [slice(0, time_s.shape[0])]
    out = []
    ruptures: list[Rupture] = []
    for i, sl in enumerate(slices):
        t = time_s[sl]
        whole = SqueezeSeries(
            object_id=object_id,
            squeeze_index=i,
            time_s=t - t[0],
            force_n=force_n[sl],
            compression_m=compression_m[sl],
            start_time_ns=None
            if clock_origin_ns is None
            else clock_origin_ns + round(float(t[0]) * NS_PER_S),
        )
        sq, rupture = cut_rupture(whole, window_s=window, recording_offset_s=float(t[0]))
        if rupture is not None:
            ruptures.append(rupture)
            if phase == "unloading":
                raise InputDataError(
                    f"squeeze #{i} ruptured ({rupture.describe()}): it has no unloading phase; "
                    "use --phase loading or all",
                    path=path,
                )
        out.append(slice_squeeze(sq, phase_slice(sq.time_s, sq.force_n, phase, window_s=window)))
    return out, ruptures


def _check_recording_options(phase: str, increases_when: str | None) -> None:
    if phase not in PHASES:
        raise UsageError(f"--phase must be one of {', '.join(PHASES)}, got {phase!r}")
    if increases_when is not None and increases_when not in INCREASES_WHEN:
        raise UsageError(
            f"--position-increases-when must be closing or opening, got {increases_when!r}"
        )


#: How the units are spelled in messages (the tables above key them in lower case).
_UNIT_SPELLING = {"n": "N", "kn": "kN", "mn": "mN"}


def _unit_hint(key: str, unit: str | None, what: str, stated: str | None = None) -> str:
    """``did you mean --units key=unit?``; ``stated``: the unit the file's units row gives."""
    if unit is None:
        return f"check the unit of {what}"
    spelled = _UNIT_SPELLING.get(unit, unit)
    if stated is not None:
        return f"the file's units row says {stated!r}; is {what} in {spelled}?"
    return f"did you mean --units {key}={spelled}?"


# ---------------------------------------------------------------------------------------------
# ROS 2 bags
# ---------------------------------------------------------------------------------------------


#: The fields each message type must have for the reader (dotted paths).
_REQUIRED_FIELDS: dict[str, tuple[str, ...]] = {
    WRENCH_TYPE: ("header.stamp.sec", "header.stamp.nanosec", "wrench.force"),
    POSE_TYPE: ("header.stamp.sec", "header.stamp.nanosec", "pose.position"),
    JOINT_STATE_TYPE: ("header.stamp.sec", "header.stamp.nanosec", "name", "position"),
}

#: The first two bytes of a ROS 2 CDR payload (the encapsulation kind): plain CDR, big or little
#: endian.
_CDR_KINDS = (b"\x00\x00", b"\x00\x01")

_MISSING = object()


def _field(msg: Any, dotted: str, where: str, path: Path) -> Any:
    """``msg.<dotted>``, or a one-line error naming the field the message definition lacks."""
    value = msg
    for part in dotted.split("."):
        value = getattr(value, part, _MISSING)
        if value is _MISSING:
            raise InputDataError(
                f"{where}: the message has no field {dotted!r} (its message definition does not "
                "match its type name)",
                path=path,
            )
    return value


def _number(value: Any, dotted: str, where: str, path: Path) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputDataError(
            f"{where}: field {dotted!r} is a {type(value).__name__}, not a number", path=path
        )
    return float(value)


def _stamp_ns(msg: Any, where: str, path: Path) -> int:
    sec = _field(msg, "header.stamp.sec", where, path)
    nanosec = _field(msg, "header.stamp.nanosec", where, path)
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in (sec, nanosec)):
        raise InputDataError(f"{where}: header.stamp is not (sec, nanosec) integers", path=path)
    return int(sec) * NS_PER_S + int(nanosec)


def _decoder(factory: Any, schema: Any, channel: Any, where: str, path: Path) -> Any:
    """The CDR decoder of ``channel``'s message definition, or a one-line error (exit 65)."""
    if channel.message_encoding != "cdr" or schema is None or schema.encoding != "ros2msg":
        got = f"{channel.message_encoding}/{getattr(schema, 'encoding', None)}"
        raise InputDataError(f"{where}: encoding {got}, expected cdr/ros2msg", path=path)
    try:  # the msgdef parser also prints its complaint to stderr: keep that to the one line
        with contextlib.redirect_stderr(io.StringIO()):
            return factory.decoder_for(channel.message_encoding, schema)
    except Exception as err:  # the msgdef parser raises many kinds of error on bad text
        raise InputDataError(
            f"{where}: unparseable message definition ({type(err).__name__}: "
            f"{' '.join(str(err).split())[:200]})",
            path=path,
        ) from None


def _decode(decode: Any, data: bytes, index: int, where: str, path: Path) -> Any:
    """One CDR payload decoded, or a one-line error naming the message (exit 65)."""
    if len(data) < 4 or bytes(data[:2]) not in _CDR_KINDS:
        raise InputDataError(
            f"{where}: message {index} has no CDR encapsulation header "
            f"(first bytes {bytes(data[:4]).hex() or 'none'})",
            path=path,
        )
    try:
        return decode(data)
    except Exception as err:  # a truncated payload raises struct, index, unicode... errors
        raise InputDataError(
            f"{where}: message {index} does not decode with its message definition "
            f"({type(err).__name__}: {' '.join(str(err).split())[:200]})",
            path=path,
        ) from None


def _read_topics(
    path: Path, roles: Mapping[str, tuple[str, ...]], joint: str | None, axis: Axis
) -> dict[str, tuple[list[int], list[Any]]]:
    """Read ``(stamp_ns list, value list)`` per topic: the force vector, position.axis or joint.

    Each channel's encoding, message definition and every decoded message are checked against
    the fields the reader needs (:data:`_REQUIRED_FIELDS`) before use; a mismatch names the
    topic, the type and the field (exit 65).

    Args:
        path: the bag.
        roles: topic → the message types accepted on it.
        joint: JointState joint name.
        axis: squeeze axis.
    """
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    topics = list(roles)
    out: dict[str, tuple[list[int], list[Any]]] = {t: ([], []) for t in topics}
    with path.open("rb") as fh:
        try:
            reader = make_reader(fh)
            summary = reader.get_summary()
        except (McapError, ValueError, OSError) as err:
            raise InputDataError(f"not a readable MCAP file ({err})", path=path) from err
        if summary is None:
            raise InputDataError("MCAP file has no summary (unindexed bag)", path=path)
        types: dict[str, str] = {}
        for ch in summary.channels.values():
            schema = summary.schemas.get(ch.schema_id)
            types[ch.topic] = schema.name if schema is not None else ""
        available = ", ".join(sorted(types)) or "none"
        for topic in topics:
            if topic not in types:
                raise InputDataError(
                    f"topic {topic!r} is not in the bag; topics: {available}", path=path
                )
        for topic in topics:
            want = types[topic]
            if want not in roles[topic]:
                raise InputDataError(
                    f"topic {topic!r} has type {want or 'unknown'}, expected "
                    f"{' or '.join(roles[topic])}",
                    path=path,
                )
            if want == JOINT_STATE_TYPE and joint is None:
                raise UsageError(f"topic {topic!r} is {JOINT_STATE_TYPE}: pass a joint name")
        factory = DecoderFactory()
        decoders: dict[int, Any] = {}
        counts = dict.fromkeys(topics, 0)
        try:
            for schema, channel, message in reader.iter_messages(topics=topics):
                where = f"topic {channel.topic!r} ({types[channel.topic]})"
                if channel.id not in decoders:
                    decoders[channel.id] = _decoder(factory, schema, channel, where, path)
                index = counts[channel.topic]
                counts[channel.topic] += 1
                msg = _decode(decoders[channel.id], message.data, index, where, path)
                stamps, values = out[channel.topic]
                stamps.append(_stamp_ns(msg, where, path))
                values.append(_extract(msg, types[channel.topic], axis, joint, where, path))
        except McapError as err:
            raise InputDataError(f"cannot decode bag ({err})", path=path) from err
    return out


def _extract(
    msg: Any, type_name: str, axis: Axis, joint: str | None, where: str, path: Path
) -> Any:
    for dotted in _REQUIRED_FIELDS[type_name]:
        _field(msg, dotted, where, path)
    if type_name == WRENCH_TYPE:
        force = msg.wrench.force
        return tuple(
            _number(_field(force, a, where, path), f"wrench.force.{a}", where, path) for a in "xyz"
        )
    if type_name == POSE_TYPE:
        position = msg.pose.position
        return _number(_field(position, axis, where, path), f"pose.position.{axis}", where, path)
    try:
        names = [str(n) for n in msg.name]
        positions = list(msg.position)
    except TypeError:
        raise InputDataError(f"{where}: name and position must be arrays", path=path) from None
    if joint not in names:
        raise InputDataError(
            f"{where}: joint {joint!r} not in the JointState names {names}", path=path
        )
    i = names.index(joint)
    if i >= len(positions):
        raise InputDataError(
            f"{where}: joint {joint!r} has no position ({len(positions)} positions for "
            f"{len(names)} names)",
            path=path,
        )
    return _number(positions[i], "position", where, path)


def read_ros2_bag(
    path: str | PathLike[str],
    *,
    wrench_topics: Sequence[str],
    position_topic: str,
    object_id: str,
    axis: Axis = "x",
    joint: str | None = None,
    position_is: PositionIs = "palm",
    compression_zero: CompressionZero = "lead_in",
    segment: bool = True,
    force_threshold_frac: float = DEFAULT_FORCE_THRESHOLD_FRAC,
    min_gap_s: float = DEFAULT_MIN_GAP_S,
    min_squeeze_s: float = DEFAULT_MIN_SQUEEZE_S,
    phase: Phase = "all",
    position_increases_when: IncreasesWhen | None = None,
    size_x_cm: float | None = None,
) -> Recording:
    """Read the squeezes of one object from a ROS 2 MCAP bag (``ros2msg`` schemas, ``cdr``).

    The recording is checked for plausibility (:mod:`deformctl.plausibility`: sample rates,
    peak force, the force's axis, the compression's sign and size); every squeeze is cut at a
    rupture (recorded in the result) and reduced to ``phase`` (:mod:`deformctl.phases`).

    Args:
        path: the bag, one ``.mcap`` file.
        wrench_topics: one or two ``geometry_msgs/msg/WrenchStamped`` topics (one per palm).
        position_topic: a ``geometry_msgs/msg/PoseStamped`` topic (palm pose) or a
            ``sensor_msgs/msg/JointState`` topic (with ``joint``).
        object_id: catalog id written into every squeeze.
        axis: the squeeze axis in the wrench and pose frames.
        joint: joint name in a JointState topic (its ``position`` in m).
        position_is: ``"palm"`` (one palm's travel, symmetric partner: d = 2·travel) or
            ``"gap"`` (the distance between the palms: d = gap(t0) − gap).
        compression_zero: ``"lead_in"`` (median over the unloaded lead-in) or ``"first"``.
        segment: split the recording into squeezes (else one squeeze).
        force_threshold_frac, min_gap_s, min_squeeze_s: segmentation (module docstring).
        phase: ``"all"``, ``"loading"`` (each squeeze up to its peak force) or ``"unloading"``.
        position_increases_when: ``"closing"`` or ``"opening"``: the direction in which the
            position grows; None: a gap grows when opening, one palm's sign is automatic.
        size_x_cm: the object's size along the squeeze axis, when known (a compression larger
            than it is refused).

    Returns:
        The squeezes (time in s from each squeeze's first sample, on the (first) wrench
        topic's timestamps inside the overlap with the position stream), the median sample
        rates of the first wrench topic and of the position topic, and the ruptures.

    Raises:
        MissingInputError: the bag does not exist.
        InputDataError: not an MCAP file, a topic not in the bag (the message lists those that
            are), a topic of the wrong type, a joint not in the JointState, NaN samples,
            non-monotonic header stamps, streams that do not overlap, no compression, no squeeze,
            or an implausible recording (the message names the likely cause).
        UsageError: no or more than two wrench topics, an unknown axis or position kind, a
            JointState topic without ``joint``.
    """
    p = Path(path)
    _check_recording_options(phase, position_increases_when)
    if not p.is_file():
        raise MissingInputError("no such bag file", path=p)
    note_input(p)
    if not 1 <= len(wrench_topics) <= 2:
        raise UsageError(f"give one or two wrench topics, got {len(wrench_topics)}")
    if axis not in ("x", "y", "z"):
        raise UsageError(f"axis must be x, y or z, got {axis!r}")
    if position_is not in ("gap", "palm"):
        raise UsageError(f"position_is must be 'gap' or 'palm', got {position_is!r}")
    if position_topic in wrench_topics:
        raise UsageError(f"topic {position_topic!r} given as both wrench and position topic")
    roles: dict[str, tuple[str, ...]] = dict.fromkeys(wrench_topics, (WRENCH_TYPE,))
    roles[position_topic] = (POSE_TYPE, JOINT_STATE_TYPE)
    data = _read_topics(p, roles, joint, axis)
    where = str(p)

    streams: list[tuple[FloatArray, FloatArray]] = []
    t_ref_ns = min((data[t][0][0] for t in data if data[t][0]), default=0)
    for topic in [*wrench_topics, position_topic]:
        stamps, values = data[topic]
        if not stamps:
            raise InputDataError(f"topic {topic!r} has no messages", path=p)
        t_s = (np.asarray(stamps, dtype=np.int64) - t_ref_ns).astype(np.float64) / NS_PER_S
        what = f"topic {topic!r}"
        if topic == position_topic:
            v = np.asarray(values, dtype=np.float64)
            _check_stream(what, t_s, v, where)
        else:
            vectors = np.asarray(values, dtype=np.float64).reshape(-1, 3)
            v = np.abs(vectors[:, "xyz".index(axis)])
            _check_stream(what, t_s, v, where)
            check_force_axis(vectors, axis, what=what, path=where)
            check_peak_force(
                float(np.max(v)), what=what, path=where, hint="is the wrench in newtons?"
            )
        if t_s.shape[0] >= 2:
            check_sample_rate(
                _rate_hz(t_s), what=what, path=where, hint="are its header stamps right?"
            )
        streams.append((t_s, v))

    pos_t, pos_v = streams[-1]
    force_streams = streams[:-1]
    lo = max(max(s[0][0] for s in force_streams), pos_t[0])
    hi = min(min(s[0][-1] for s in force_streams), pos_t[-1])
    if not hi > lo:
        spans = "; ".join(
            f"{name} {t[0]:.3f}..{t[-1]:.3f} s"
            for name, (t, _) in zip([*wrench_topics, position_topic], streams, strict=True)
        )
        raise InputDataError(f"force and position streams do not overlap in time: {spans}", path=p)
    t0, f0 = force_streams[0]
    keep = (t0 >= lo) & (t0 <= hi)
    time_s = t0[keep]
    force_n = f0[keep]
    if len(force_streams) == 2:
        t1, f1 = force_streams[1]
        force_n = 0.5 * (force_n + np.interp(time_s, t1, f1))
    position = np.interp(time_s, pos_t, pos_v)
    if time_s.shape[0] < 2:
        raise InputDataError("fewer than two force samples inside the overlap", path=p)
    compression_m = _compression(
        position,
        force_n,
        position_is,
        where,
        force_threshold_frac,
        compression_zero,
        position_increases_when,
        f"topic {position_topic!r}",
    )
    check_peak_compression(
        float(np.max(compression_m)),
        size_x_cm=size_x_cm,
        what=f"topic {position_topic!r}",
        path=where,
        hint="is the position in metres? (ROS uses metres; convert a joint in mm or rad)",
    )
    position_rate_hz = _rate_hz(pos_t)
    squeezes, ruptures = _to_squeezes(
        time_s,
        force_n,
        compression_m,
        object_id=object_id,
        segment=segment,
        path=where,
        force_threshold_frac=force_threshold_frac,
        min_gap_s=min_gap_s,
        min_squeeze_s=min_squeeze_s,
        phase=phase,
        window_s=_detection_window_s(position_rate_hz),
        clock_origin_ns=t_ref_ns,
    )
    return Recording(
        squeezes,
        _rate_hz(force_streams[0][0]),
        position_rate_hz,
        source="ros2_bag",
        phase=phase,
        ruptures=tuple(ruptures),
    )


def _detection_window_s(position_rate_hz: float) -> float:
    """The SG window rupture and phase detection use: the one ``characterize`` will use."""
    from deformctl.characterize import default_window_s

    return default_window_s(position_rate_hz)


# ---------------------------------------------------------------------------------------------
# CSV exports
# ---------------------------------------------------------------------------------------------


def _norm_unit(text: str) -> str:
    return text.strip().strip("[]()").strip().lower()


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_csv_export(
    path: str | PathLike[str],
    *,
    columns: Mapping[str, str],
    object_id: str,
    units: Mapping[str, str] | None = None,
    position_is: PositionIs = "palm",
    compression_zero: CompressionZero = "first",
    segment: bool = False,
    force_threshold_frac: float = DEFAULT_FORCE_THRESHOLD_FRAC,
    min_gap_s: float = DEFAULT_MIN_GAP_S,
    min_squeeze_s: float = DEFAULT_MIN_SQUEEZE_S,
    phase: Phase = "all",
    position_increases_when: IncreasesWhen | None = None,
    size_x_cm: float | None = None,
) -> Recording:
    """Read squeezes from a CSV export: plain, or names in row one and units in row two.

    The file is a two-header-row export when every mapped column's second row is not a number;
    that row is then read as the columns' units (``N``, ``[mm]``, ``(s)`` are all accepted).
    Units given in ``units`` apply to columns whose unit the file does not state; a unit stated
    in both places must agree. Columns with no unit anywhere are taken as SI (s, N, m).

    Args:
        path: the CSV file (comma-separated; UTF-8, a BOM is accepted).
        columns: mapping of ``time``, ``force`` and exactly one of ``position`` (one palm's
            travel, see ``position_is``), ``gap`` (between the palms) or ``compression`` (the
            compression itself, e.g. a testing machine's crosshead travel) to CSV column names.
        object_id: catalog id written into the squeezes.
        units: mapping of the same keys to units: time s/ms/us/ns, force N/kN/mN/lbf,
            lengths m/cm/mm/um/in.
        position_is: meaning of a ``position`` column: ``"palm"`` or ``"gap"``.
        compression_zero: ``"first"`` (the first row) or ``"lead_in"`` (module docstring).
        segment: split the file into squeezes (default: one squeeze per file).
        force_threshold_frac, min_gap_s, min_squeeze_s: segmentation (module docstring).
        phase, position_increases_when, size_x_cm: as :func:`read_ros2_bag` (a compression
            column grows when closing unless ``position_increases_when="opening"``).

    Returns:
        The squeezes in SI, the file's median sample rate (for force and position alike) and
        the ruptures.

    Raises:
        MissingInputError: the file does not exist.
        InputDataError: a mapped column missing from the file, an unknown unit in the file,
            file and option units that disagree, non-numeric or NaN cells, non-monotonic time,
            no compression, or an implausible recording: a sample rate, peak force or peak
            compression that a unit mistake explains (the message suggests the ``--units``), a
            compression of the wrong sign (it names ``--position-increases-when``).
        UsageError: a bad ``columns`` mapping, a ``units`` key that names no mapped column or an
            unknown unit in ``units``.
    """
    p = Path(path)
    _check_recording_options(phase, position_increases_when)
    if not p.is_file():
        raise MissingInputError("no such CSV file", path=p)
    note_input(p)
    pos_keys = [k for k in _POSITION_KEYS if k in columns]
    unknown = sorted(set(columns) - {"time", "force", *_POSITION_KEYS})
    if unknown or "time" not in columns or "force" not in columns or len(pos_keys) != 1:
        raise UsageError(
            "columns must map time, force and exactly one of position, gap, compression; got "
            + ",".join(f"{k}={v}" for k, v in columns.items())
        )
    pos_key = pos_keys[0]
    keys = ("time", "force", pos_key)
    opt_units = {k: _norm_unit(v) for k, v in (units or {}).items()}
    for k, u in opt_units.items():
        if k not in keys:
            given = ",".join(f"{key}={columns[key]}" for key in keys)
            raise UsageError(
                f"--units: {k!r} names no column of --columns ({given}); valid keys: "
                f"{', '.join(keys)}"
            )
        if u not in _UNITS_BY_KEY[k]:
            raise UsageError(
                f"units: unknown {k} unit {u!r}; supported: {', '.join(_UNITS_BY_KEY[k])}"
            )

    try:
        with p.open(newline="", encoding="utf-8-sig") as fh:
            rows = [r for r in csv.reader(fh) if any(cell.strip() for cell in r)]
    except UnicodeDecodeError as err:
        raise InputDataError(f"not UTF-8 text (byte {err.start})", path=p) from None
    except csv.Error as err:
        raise InputDataError(f"not a readable CSV file: {err}", path=p) from None
    if not rows:
        raise InputDataError("empty CSV file", path=p)
    header = [h.strip() for h in rows[0]]
    idx: dict[str, int] = {}
    for k in keys:
        name = columns[k]
        if name not in header:
            raise InputDataError(
                f"mapped column {k}={name!r} not in the file; columns: {', '.join(header)}",
                path=p,
            )
        idx[k] = header.index(name)
    body = rows[1:]
    file_units: dict[str, str] = {}
    if body and all(not _is_number(_cell(body[0], idx[k])) for k in keys):
        for k in keys:
            u = _norm_unit(_cell(body[0], idx[k]))
            if not u:
                continue
            if u not in _UNITS_BY_KEY[k]:
                raise InputDataError(
                    f"column {columns[k]!r}: unknown {k} unit {u!r} in the units row; "
                    f"supported: {', '.join(_UNITS_BY_KEY[k])}",
                    path=p,
                )
            file_units[k] = u
        body = body[1:]
    for k, u in file_units.items():
        if k in opt_units and _UNITS_BY_KEY[k][opt_units[k]] != _UNITS_BY_KEY[k][u]:
            raise InputDataError(
                f"column {columns[k]!r}: the file says unit {u!r}, the option says "
                f"{opt_units[k]!r}",
                path=p,
            )
    arrays: dict[str, FloatArray] = {}
    used: dict[str, str] = {}
    for k in keys:
        u = (
            file_units.get(k)
            or opt_units.get(k)
            or ("s" if k == "time" else "n" if k == "force" else "m")
        )
        used[k] = u
        vals = np.empty(len(body))
        for i, row in enumerate(body):
            cell = _cell(row, idx[k]).strip()
            try:
                vals[i] = float(cell) if cell else math.nan
            except ValueError as err:
                raise InputDataError(
                    f"column {columns[k]!r}: non-numeric value {cell!r} in data row {i + 1}",
                    path=p,
                ) from err
        arrays[k] = vals * _UNITS_BY_KEY[k][u]
    where = str(p)
    time_s = arrays["time"]
    for k in keys:
        _check_stream(f"column {columns[k]!r}", time_s, arrays[k], where)
    rate_hz = _rate_hz(time_s)
    _check_time_and_force(arrays, used, columns, where, file_units)
    kind = position_is if pos_key == "position" else pos_key
    compression_m = _compression(
        arrays[pos_key],
        arrays["force"],
        kind,
        where,
        force_threshold_frac,
        compression_zero,
        position_increases_when,
        f"column {columns[pos_key]!r}",
    )
    peak_m = float(np.max(compression_m))
    factor = _UNITS_BY_KEY[pos_key][used[pos_key]]
    unit = suggest_unit(
        peak_m / factor,
        LENGTH_UNITS_M,
        to_value=lambda m: m,
        ok=lambda m: m <= compression_limit_m(size_x_cm),
        target=compression_target_m(size_x_cm),
    )
    check_peak_compression(
        peak_m,
        size_x_cm=size_x_cm,
        what=f"column {columns[pos_key]!r}",
        path=where,
        hint=_unit_hint(pos_key, unit, f"column {columns[pos_key]!r}", file_units.get(pos_key)),
    )
    absolute = float(time_s[0]) >= ABSOLUTE_TIME_MIN_S
    squeezes, ruptures = _to_squeezes(
        time_s - time_s[0],
        arrays["force"],
        compression_m,
        object_id=object_id,
        segment=segment,
        path=where,
        force_threshold_frac=force_threshold_frac,
        min_gap_s=min_gap_s,
        min_squeeze_s=min_squeeze_s,
        phase=phase,
        window_s=_detection_window_s(rate_hz),
        clock_origin_ns=round(float(time_s[0]) * NS_PER_S) if absolute else None,
    )
    return Recording(
        squeezes, rate_hz, rate_hz, source="csv", phase=phase, ruptures=tuple(ruptures)
    )


def _check_time_and_force(
    arrays: Mapping[str, FloatArray],
    used: Mapping[str, str],
    columns: Mapping[str, str],
    where: str,
    stated: Mapping[str, str],
) -> None:
    """Refuse a CSV whose sample rate or peak force a unit mistake explains (names the unit).

    ``stated``: the units the file's units row gives (the hint then questions the file).
    """
    time_s, force_n = arrays["time"], arrays["force"]
    dt_s = float(np.median(np.diff(time_s)))
    rate_hz = 1.0 / dt_s
    if not rate_ok(rate_hz):
        unit = suggest_unit(
            dt_s / TIME_UNITS_S[used["time"]],
            TIME_UNITS_S,
            to_value=lambda dt: 1.0 / dt,
            ok=rate_ok,
            target=1000.0,
        )
        what = f"column {columns['time']!r}"
        hint = _unit_hint("time", unit, what, stated.get("time"))
        check_sample_rate(rate_hz, what=what, path=where, hint=hint)
    peak_n = float(np.max(np.abs(force_n)))
    factor = FORCE_UNITS_N[used["force"]]
    unit = suggest_unit(
        peak_n / factor,
        FORCE_UNITS_N,
        to_value=lambda f: f,
        ok=lambda f: f <= MAX_PEAK_FORCE_N,
        target=10.0,
    )
    what = f"column {columns['force']!r}"
    hint = _unit_hint("force", unit, what, stated.get("force"))
    check_peak_force(peak_n, what=what, path=where, hint=hint)


def _cell(row: Sequence[str], i: int) -> str:
    return row[i] if i < len(row) else ""


def squeeze_from_ros2_bag(path: str | PathLike[str], **options: Any) -> list[SqueezeSeries]:
    """The squeezes of :func:`read_ros2_bag` (same keyword arguments and errors), no rates."""
    return read_ros2_bag(path, **options).squeezes


def squeeze_from_csv(path: str | PathLike[str], **options: Any) -> list[SqueezeSeries]:
    """The squeezes of :func:`read_csv_export` (same keyword arguments and errors), no rates."""
    return read_csv_export(path, **options).squeezes


# ---------------------------------------------------------------------------------------------
# the simulator (measure --sim)
# ---------------------------------------------------------------------------------------------

#: Default peak squeeze strain: the peak force of the last (largest) squeeze is the force that
#: holds the object at this compression, F = D · strain · size_x (catalog D). At 1 % the lattice
#: is in its small-strain range, where its stiffness is the catalog D; the simulator's own
#: helper measured it exact at 1 % and 16 % softer at 17 % strain, and at 5 % the backbone
#: softening already leaks into the λ fit (see README, measure --sim).
DEFAULT_SQUEEZE_STRAIN = 0.01
DEFAULT_SIM_SQUEEZES = 3  #: squeezes per object (the paper's X = 3)
DEFAULT_SIM_RAMP_S = 0.25  #: force ramp of each squeeze, s
DEFAULT_SIM_HOLD_S = 1.0  #: hold at the peak force, s

SqueezeProgress = Callable[[str, int, int], None]
"""``progress(object_id, squeezes_done, squeezes_total)``, called after each simulated squeeze."""


def default_peak_force_n(spec: ObjectSpec, strain: float = DEFAULT_SQUEEZE_STRAIN) -> float:
    """The default peak squeeze force: ``D · strain · size_x``, N (the static force for ``strain``).

    Args:
        spec: the object (catalog D in N/cm, size in cm).
        strain: compression as a fraction of the object's width between the palms.
    """
    return spec.stiffness_n_per_m * strain * spec.size_m[0]


def _object_seed(seed: int, index: int) -> int:
    """A per-object noise seed derived from the run seed (independent streams per object)."""
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


def simulate_squeezes(
    catalog: pd.DataFrame,
    *,
    squeezes: int = DEFAULT_SIM_SQUEEZES,
    settings: SimSettings | None = None,
    peak_force_n: float | None = None,
    strain: float = DEFAULT_SQUEEZE_STRAIN,
    ramp_s: float = DEFAULT_SIM_RAMP_S,
    hold_s: float = DEFAULT_SIM_HOLD_S,
    gravity: bool = True,
    noise_force_n: float = 0.0,
    noise_position_m: float = 0.0,
    seed: int = 0,
    progress: SqueezeProgress | None = None,
    path: str | None = None,
    first_index: int = 0,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """Simulate ``squeezes`` force-controlled squeezes of every catalog object.

    Each object is squeezed ``squeezes`` times from rest by :func:`deformctl.sim.squeeze` (as
    :func:`deformctl.sim.squeeze_many` does): a linear force ramp over ``ramp_s`` then a hold of
    ``hold_s``, at peak forces ``linspace(0.5, 1, squeezes) · F_peak`` (so the squeezes probe
    different force levels). The
    palms are massless, so the force felt is the commanded force; the positions are the palms'.

    Args:
        catalog: catalog rows to squeeze (already selected), with material values.
        squeezes: squeezes per object (>= 1).
        settings: simulator settings (default :class:`~deformctl.sim.SimSettings`).
        peak_force_n: peak force of the largest squeeze, N, for every object; None (default)
            uses :func:`default_peak_force_n` with ``strain`` per object.
        strain: the default rule's strain (0 < strain < ``settings.max_squeeze_strain``).
        ramp_s: force ramp, s (>= 0). hold_s: hold at the peak, s (>= 0, ramp + hold > 0).
        gravity: object on the table under gravity (default); False floats it without a table
            (a pure material test: no pre-stress from the object's own weight).
        noise_force_n: std of Gaussian noise on the force felt, N (>= 0).
        noise_position_m: std of Gaussian noise on each palm position, m (>= 0).
        seed: noise seed; object ``i`` gets its own stream derived from (seed, i) and squeeze
            ``j`` of it that stream's seed + j. Same inputs and seed give the same bytes.
        progress: called after each squeeze.
        path: the catalog's name, for messages.
        first_index: the position of ``catalog``'s first row in the whole run's catalog: row
            ``i`` gets the noise stream of object ``first_index + i``, so squeezing a slice of
            a catalog (a sweep's one object) gives the bytes of the whole run.

    Returns:
        ``(objects, squeezes)``: the objects' catalog rows (NaN as None) plus
        ``force_rate_hz``/``position_rate_hz`` (1/dt) and ``sim_peak_force_n`` (the largest
        squeeze's peak force), and every squeeze in object order.

    Raises:
        InputDataError: a row without material values or with values the simulator refuses
            (names the object; raised before any simulation).
        UsageError: an option out of range.
        SimulationError: the simulation produced a non-finite state.
    """
    from deformctl.sim import SimSettings, squeeze

    s = settings or SimSettings()
    if isinstance(squeezes, bool) or not isinstance(squeezes, int) or squeezes < 1:
        raise UsageError(f"squeezes must be an integer >= 1, got {squeezes!r}")
    if peak_force_n is not None and not (math.isfinite(peak_force_n) and peak_force_n > 0):
        raise UsageError(f"peak force must be a finite number > 0 N, got {peak_force_n}")
    if not (math.isfinite(strain) and 0 < strain < s.max_squeeze_strain):
        raise UsageError(
            f"strain must be in (0, {s.max_squeeze_strain:g}) (the densification limit), "
            f"got {strain}"
        )
    if not (math.isfinite(ramp_s) and ramp_s >= 0 and math.isfinite(hold_s) and hold_s >= 0):
        raise UsageError(f"ramp and hold must be >= 0 s, got {ramp_s} and {hold_s}")
    if ramp_s + hold_s <= 0:
        raise UsageError("ramp + hold must be > 0 s")
    for name, value in (("force", noise_force_n), ("position", noise_position_m)):
        if not (math.isfinite(value) and value >= 0):
            raise UsageError(f"{name} noise must be a finite number >= 0, got {value}")
    objects_in = catalog_objects(catalog, path=path)
    specs = [obj.to_sim_spec(path=path) for obj in objects_in]
    records = [obj.record() for obj in objects_in]
    rate_hz = 1.0 / s.dt_s
    objects: list[dict[str, Any]] = []
    out: list[SqueezeSeries] = []
    total = squeezes * len(specs)
    for i, (spec, rec) in enumerate(zip(specs, records, strict=True)):
        peak = peak_force_n if peak_force_n is not None else default_peak_force_n(spec, strain)
        base_seed = _object_seed(seed, first_index + i)
        for j in range(squeezes):
            out.append(
                squeeze(
                    spec,
                    peak_force_n=peak * _force_scale(j, squeezes),
                    ramp_s=ramp_s,
                    hold_s=hold_s,
                    settings=s,
                    squeeze_index=j,
                    gravity=gravity,
                    noise_force_n=noise_force_n,
                    noise_position_m=noise_position_m,
                    seed=base_seed + j,
                )
            )
            if progress is not None:
                progress(spec.object_id, i * squeezes + j + 1, total)
        objects.append(
            {**rec, "force_rate_hz": rate_hz, "position_rate_hz": rate_hz, "sim_peak_force_n": peak}
        )
    return objects, out


def _force_scale(j: int, n: int) -> float:
    """Squeeze ``j`` of ``n``: the factor on the peak force, ``linspace(0.5, 1, n)[j]``."""
    return 1.0 if n == 1 else float(np.linspace(0.5, 1.0, n)[j])


#: Rows of a ``measure --sim`` dataset: one per object squeezed (the series are in the logs).
MEASURE_SCHEMA = pa.schema(
    [
        pa.field("object_id", pa.string(), nullable=False),
        pa.field("squeezes", pa.int64(), nullable=False),
        pa.field("samples", pa.int64(), nullable=False),
        pa.field("duration_s", pa.float64(), nullable=False, metadata={"unit": "s"}),
        pa.field("peak_force_n", pa.float64(), nullable=False, metadata={"unit": "N"}),
    ]
)


@dataclass(frozen=True)
class SimulateCatalogTask:
    """``measure --sim`` for one catalog object (a picklable sweep task).

    The item carries the object's catalog row and its catalog position under
    ``"_position"``; the noise stream is derived from (seed, position) as in the serial run.

    Attributes:
        simulate: the keyword arguments of :func:`simulate_squeezes` (squeezes, peak force or
            strain, ramp, hold, gravity, noise).
        settings: the :class:`~deformctl.sim.SimSettings` (a preset's object model).
        seed: the run's noise seed.
        sim_preset: the name of the preset ``settings`` came from (recorded in the log).
        log_epoch_ns: where the log's squeezes begin, ns since the Unix epoch (they are laid
            end to end from there).
    """

    simulate: Mapping[str, Any]
    settings: SimSettings
    seed: int = 0
    sim_preset: str | None = None
    log_epoch_ns: int = LOG_EPOCH_NS

    def __call__(self, item: dict[str, Any]) -> TaskOutput:
        """Squeeze one object: its summary row, its (object row, squeezes) as the payload."""
        row = {k: v for k, v in item.items() if k != "_position"}
        objects, series = simulate_squeezes(
            pd.DataFrame([row]),
            settings=self.settings,
            seed=self.seed,
            first_index=int(item["_position"]),
            **self.simulate,
        )
        summary = {
            "object_id": str(objects[0]["object_id"]),
            "squeezes": len(series),
            "samples": int(sum(len(s.time_s) for s in series)),
            "duration_s": float(sum(float(s.time_s[-1]) for s in series)),
            "peak_force_n": float(objects[0]["sim_peak_force_n"]),
        }
        return TaskOutput(rows=[summary], payload=(objects[0], series))


def sim_provenance(
    catalog_path: str, task: SimulateCatalogTask, object_ids: list[str]
) -> Provenance:
    """The provenance of a ``measure --sim`` log: the catalog, the seed and every setting."""
    return Provenance.from_invocation(
        [catalog_path],
        seed=task.seed,
        settings={
            "source": "sim",
            **task.simulate,
            "peak_force_rule": (
                "peak_force_n" if task.simulate.get("peak_force_n") is not None else "strain"
            ),
            "objects": object_ids,
            "sim_preset": task.sim_preset,
            "sim_settings": dataclasses.asdict(task.settings),
            "log_epoch_ns": task.log_epoch_ns,
        },
    )


#: Bytes one sample of a squeeze log held in memory costs: the series arrays and the JSON message
#: built from them before the log is written.
LOG_SAMPLE_BYTES = 400


def _check_budgets(
    catalog: pd.DataFrame, task: SimulateCatalogTask, path: str, *, single_log: bool
) -> None:
    """Refuse, before simulating, a run above the memory budget (``--memory-budget-gib``).

    Each object's squeeze (its model plus the recorded steps, see
    :func:`deformctl.sim.engine.check_run_steps`) must fit; a single-file squeeze log, built in
    memory (MCAP's summary comes at the end), must fit as a whole. A dataset directory is written
    part by part and has no whole-log limit. With ``single_log`` a bad row is refused first
    (exit 65); in a dataset it is skipped here and fails alone in its worker.

    Raises:
        InputDataError: ``single_log`` and a row the simulator refuses (exit 65).
        UsageError: one line naming the estimate, the budget and the option (exit 2).
    """
    from deformctl.sim.engine import GIB, check_run_steps

    settings = task.settings
    squeezes = int(task.simulate.get("squeezes", DEFAULT_SIM_SQUEEZES))
    ramp = task.simulate.get("ramp_s")
    hold = task.simulate.get("hold_s")
    duration_s = float(DEFAULT_SIM_RAMP_S if ramp is None else ramp) + float(
        DEFAULT_SIM_HOLD_S if hold is None else hold
    )
    steps = duration_s / settings.dt_s + 1.0
    for record in catalog.to_dict("records"):
        try:
            spec = CatalogObject.from_row(record).to_sim_spec(path=path)
        except InputDataError:
            if single_log:
                raise
            continue  # a dataset's bad row fails alone, in its worker
        check_run_steps(spec, settings, steps, "squeeze")
    samples = len(catalog) * squeezes * steps
    estimate = samples * LOG_SAMPLE_BYTES
    if single_log and estimate > settings.memory_budget_gib * GIB:
        raise UsageError(
            f"one squeeze log of {len(catalog):,} objects x {squeezes} squeezes is {samples:.3g} "
            f"samples, an estimated {estimate / GIB:.3g} GiB in memory, above the memory budget "
            f"of {settings.memory_budget_gib:g} GiB; write a dataset directory (-o DIR/) or "
            "raise --memory-budget-gib"
        )


def simulate_catalog_file(
    catalog_path: str,
    task: SimulateCatalogTask,
    *,
    output: str,
    object_ids: Sequence[str] | None = None,
    progress: SqueezeProgress | None = None,
    force: bool = False,
    workers: int | None = None,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """``measure CATALOG --sim -o LOG``: squeeze every (selected) object into one squeeze log.

    Every row is checked before anything is simulated (a row without material values is
    refused, naming the object). With ``workers`` > 1 the objects are squeezed on that many
    local processes (:func:`deformctl.parallel.map_in_order`, one :class:`SimulateCatalogTask`
    per object); each object's noise stream depends only on the seed and its position, so the
    log is byte for byte the one-process log. ``workers=None``: every core from
    :data:`~deformctl.parallel.MIN_PARALLEL_OBJECTS` objects on
    (:func:`~deformctl.parallel.single_file_workers`).

    Returns:
        The objects' rows and the squeezes written (see :func:`simulate_squeezes`).

    Raises:
        OutputExistsError: ``output`` exists and ``force`` is false (exit 1).
        UsageError: an unknown object id, or a squeeze option out of range (exit 2).
        InputDataError: a row the simulator refuses (exit 65).
    """
    check_output_path(output, force)
    catalog = select_objects(read_catalog(catalog_path), object_ids)
    _check_budgets(catalog, task, catalog_path, single_log=True)  # bad rows first
    provenance = sim_provenance(catalog_path, task, list(catalog["object_id"]))
    n_workers = single_file_workers(workers, len(catalog))
    if n_workers > 1:
        objects, series = _squeeze_in_workers(catalog, task, n_workers, progress)
    else:
        objects, series = simulate_squeezes(
            catalog,
            settings=task.settings,
            seed=task.seed,
            progress=progress,
            path=catalog_path,
            **task.simulate,
        )
    write_squeeze_log(
        output, objects, series, provenance=provenance, force=force, epoch_ns=task.log_epoch_ns
    )
    return objects, series


def _positioned_items(catalog: pd.DataFrame) -> list[dict[str, Any]]:
    """The :class:`SimulateCatalogTask` items of ``catalog``: each row with its ``_position``."""
    return [{**rec, "_position": i} for i, rec in enumerate(catalog.to_dict("records"))]


def _squeeze_in_workers(
    catalog: pd.DataFrame,
    task: SimulateCatalogTask,
    workers: int,
    progress: SqueezeProgress | None,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """:func:`simulate_squeezes` of ``catalog`` with one task per object on local processes."""
    items = _positioned_items(catalog)
    per_object = int(task.simulate.get("squeezes", DEFAULT_SIM_SQUEEZES))

    def done(i: int, _: object) -> None:
        if progress is not None:
            progress(str(items[i]["object_id"]), (i + 1) * per_object, len(items) * per_object)

    outputs = map_in_order(task, items, workers=workers, on_result=done)
    objects = [out.payload[0] for out in outputs]
    series = [s for out in outputs for s in out.payload[1]]
    return objects, series


def simulate_catalog_sweep(
    catalog_path: str,
    task: SimulateCatalogTask,
    *,
    output: str,
    sweep: SweepOptions,
    object_ids: Sequence[str] | None = None,
    force: bool = False,
) -> SweepSummary:
    """``measure --sim -o DIR/``: one object per task; part ``k``'s squeezes in ``DIR/_logs/``.

    The rows of a part are :data:`MEASURE_SCHEMA` summaries; the squeezes are byte for byte
    those of the serial run (each object's noise stream depends on the seed and its position).
    A row the simulator refuses fails alone (``DIR/_failures/``).

    Args:
        catalog_path: the catalog (``-`` for stdin), hashed into the fingerprint.
        task: the squeeze and simulator settings and the seed.
        output: the dataset directory.
        sweep: where to run (workers, scheduler), partition size, resume.
        object_ids: these objects, in this order (None: all).
        force: overwrite the sweep files of an existing directory.
    """
    catalog = select_objects(read_catalog(catalog_path), object_ids)
    _check_budgets(catalog, task, catalog_path, single_log=False)
    provenance = sim_provenance(catalog_path, task, list(catalog["object_id"]))
    items = _positioned_items(catalog)
    settings = {**task.simulate, "sim_settings": dataclasses.asdict(task.settings)}
    if task.log_epoch_ns != LOG_EPOCH_NS:  # (the default keeps older directories resumable)
        settings["log_epoch_ns"] = task.log_epoch_ns
    fingerprint = dataset_fingerprint(
        "measure", "squeeze_log", settings, {"catalog": input_digest(catalog_path)}, task.seed
    )
    return run_sweep(
        task,
        items,
        out_dir=output,
        schema=MEASURE_SCHEMA,
        fingerprint=fingerprint,
        part_writer=LogPartWriter("squeeze_log", provenance, task.log_epoch_ns),
        force=force,
        **sweep.run_kwargs(),
    )


def recording_log(
    source: str,
    recording: Recording,
    obj: Mapping[str, object],
    settings: Mapping[str, Any],
    *,
    output: str,
    force: bool = False,
) -> None:
    """Write a rig recording's squeezes as a squeeze log (``measure --bag`` / ``--csv``).

    Args:
        source: the recording file (hashed into the provenance).
        recording: what :func:`read_ros2_bag` or :func:`read_csv_export` read.
        obj: the object's row (:func:`deformctl.catalog.object_record`); the source sample
            rates are added, as they are to the provenance's ``settings``, with the source,
            phase and ruptures (:meth:`Recording.log_fields`).
        settings: the reader's options.
        output: the squeeze log (``-`` for stdout).
        force: overwrite an existing output.
    """
    rates = {
        "force_rate_hz": recording.force_rate_hz,
        "position_rate_hz": recording.position_rate_hz,
    }
    provenance = Provenance.from_invocation([source], settings={**settings, **rates})
    write_squeeze_log(
        output,
        [{**obj, **recording.log_fields()}],
        recording.squeezes,
        provenance=provenance,
        force=force,
    )
