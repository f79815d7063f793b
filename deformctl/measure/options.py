"""The options of ``measure``, checked once: what a recording is and how to cut it, and the
simulated squeeze protocol.

The command builds them from its flags and the library takes them (each number's rule is its
:mod:`deformctl.quantities` entry); :meth:`as_dict` is what the squeeze log's provenance records:

* :class:`BagSource`: where force and position are in a ROS 2 bag, and what the position is
  (a CSV export's are :class:`deformctl.measure.csv.options.CsvOptions`);
* :class:`Segmentation`: how a recording is cut into squeezes and which phase is kept;
* :class:`SqueezeProtocol`: the force-controlled squeezes ``measure --sim`` simulates;
* :class:`ScaleReference` and :class:`ObjectMask`: the scale reference in the photos of
  ``measure --images`` and how the object is told from the scene (their ``kwargs()`` are those of
  :func:`deformctl.vision.measure_object_size`; OpenCV is imported only where the images are read).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

from deformctl.errors import UsageError
from deformctl.quantities import (
    FORCE_THRESHOLD_FRAC,
    HOLD_S,
    MARKER_ID,
    MARKER_SIZE_CM,
    MIN_GAP_S,
    MIN_SQUEEZE_S,
    NOISE_FORCE_N,
    NOISE_POSITION_M,
    PEAK_FORCE_N,
    RAMP_S,
    SQUARE_SIZE_CM,
    SQUEEZES,
    STRAIN,
)
from deformctl.squeeze.phase import Phase, check_phase

Axis = Literal["x", "y", "z"]
PositionIs = Literal["travel", "gap", "palm"]
CompressionZero = Literal["first", "lead_in"]
IncreasesWhen = Literal["closing", "opening"]
INCREASES_WHEN: tuple[str, ...] = ("closing", "opening")
#: The readings of a position column: ``travel`` (the compression itself: a testing machine's
#: crosshead travel, a gripper's jaw travel; the CSV default), ``palm`` (one palm's travel, its
#: partner mirroring it: twice the compression's share) and ``gap`` (the distance between the
#: palms).
POSITION_READINGS: tuple[str, ...] = ("travel", "palm", "gap")
#: Segmentation defaults (see :mod:`deformctl.measure.segment`).
DEFAULT_FORCE_THRESHOLD_FRAC = 0.1
DEFAULT_MIN_GAP_S = 0.1
DEFAULT_MIN_SQUEEZE_S = 0.2

#: Default peak squeeze strain: the peak force of the last (largest) squeeze is the force that
#: holds the object at this compression, F = D · strain · size_x (catalog D). At 1 % the lattice
#: is in its small-strain range, where its stiffness is the catalog D; the simulator's own
#: helper measured it exact at 1 % and 16 % softer at 17 % strain, and at 5 % the backbone
#: softening already leaks into the λ fit (see docs, measure --sim).
DEFAULT_SQUEEZE_STRAIN = 0.01
DEFAULT_SIM_SQUEEZES = 3  #: squeezes per object (the paper's X = 3)
DEFAULT_SIM_RAMP_S = 0.25  #: force ramp of each squeeze, s
DEFAULT_SIM_HOLD_S = 1.0  #: hold at the peak force, s


def _choice(value: object, choices: Sequence[str], flag: str, *, optional: bool = False) -> None:
    if optional and value is None:
        return
    if value not in choices:
        raise UsageError(f"{flag} must be one of {', '.join(choices)}, got {value!r}")


def _increases_when(value: object) -> None:
    if value is not None and value not in INCREASES_WHEN:
        raise UsageError(f"--position-increases-when must be closing or opening, got {value!r}")


def check_position_options(
    position_is: object, compression_zero: object, position_increases_when: object
) -> None:
    """What a recording's position signal is (a bag's and a CSV export's alike).

    Raises:
        UsageError: an unknown position kind, compression zero or direction (exit 2).
    """
    _choice(position_is, POSITION_READINGS, "--position-is")
    _choice(compression_zero, ("first", "lead_in"), "compression_zero")
    _increases_when(position_increases_when)


@dataclass(frozen=True)
class Segmentation:
    """How a recording is cut into squeezes, and which part of each is kept.

    Attributes:
        segment: split the recording into squeezes by force; None: the source's default (yes
            for a bag, which logs several squeezes per object; no for a CSV export, one test
            per file).
        force_threshold_frac: a squeeze is where the force is above this fraction of the
            recording's peak, in (0, 1).
        min_gap_s: runs above the threshold closer than this are one squeeze, s (>= 0).
        min_squeeze_s: runs shorter than this are ignored, s (>= 0).
        phase: ``"all"``, ``"loading"`` (each squeeze up to its peak force) or ``"unloading"``.

    Raises:
        UsageError: a value outside its rule, or an unknown phase (exit 2).
    """

    segment: bool | None = None
    force_threshold_frac: float = DEFAULT_FORCE_THRESHOLD_FRAC
    min_gap_s: float = DEFAULT_MIN_GAP_S
    min_squeeze_s: float = DEFAULT_MIN_SQUEEZE_S
    phase: Phase = "all"

    def __post_init__(self) -> None:
        FORCE_THRESHOLD_FRAC.check(self.force_threshold_frac)
        MIN_GAP_S.check(self.min_gap_s)
        MIN_SQUEEZE_S.check(self.min_squeeze_s)
        check_phase(self.phase)

    def segments(self, default: bool) -> bool:
        """Whether to split, with ``default`` the source's when :attr:`segment` is None."""
        return default if self.segment is None else self.segment

    def as_dict(self, default: bool | None = None) -> dict[str, Any]:
        """The options by name, for provenance; with the source's ``default``, ``segment`` is
        resolved (:meth:`segments`)."""
        out = dataclasses.asdict(self)
        if default is not None:
            out["segment"] = self.segments(default)
        return out


@dataclass(frozen=True)
class BagSource:
    """Where a ROS 2 bag holds the squeeze (``measure --bag``).

    Attributes:
        wrench_topics: one or two ``geometry_msgs/msg/WrenchStamped`` topics (one per palm).
        position_topic: a ``geometry_msgs/msg/PoseStamped`` topic (a palm's pose) or a
            ``sensor_msgs/msg/JointState`` topic (with ``joint``).
        joint: the JointState joint whose position is the position signal, m.
        axis: the squeeze axis in the wrench and pose frames.
        position_is: ``"palm"`` (one palm's travel, its partner mirrors it: d = 2·travel),
            ``"gap"`` (the distance between the palms) or ``"travel"`` (d = travel).
        compression_zero: ``"lead_in"`` (the median over the unloaded lead-in) or ``"first"``.
        position_increases_when: ``"closing"`` or ``"opening"``; None: a gap grows when
            opening, one palm's sign is found.
        crc_check: check every chunk's CRC (a damaged chunk is an error naming its offset);
            False reads a damaged bag with a warning (``--no-crc-check``).

    Raises:
        UsageError: no or more than two wrench topics, a position topic that is also a wrench
            topic, or an unknown axis, position kind or direction (exit 2).
    """

    wrench_topics: tuple[str, ...]
    position_topic: str
    joint: str | None = None
    axis: Axis = "x"
    position_is: PositionIs = "palm"
    compression_zero: CompressionZero = "lead_in"
    position_increases_when: IncreasesWhen | None = None
    crc_check: bool = True

    kind = "ros2_bag"  #: the ``source`` a squeeze log's object row records

    def __post_init__(self) -> None:
        object.__setattr__(self, "wrench_topics", tuple(self.wrench_topics))
        if not 1 <= len(self.wrench_topics) <= 2:
            raise UsageError(f"give one or two wrench topics, got {len(self.wrench_topics)}")
        if self.axis not in ("x", "y", "z"):
            raise UsageError(f"--axis must be x, y or z, got {self.axis!r}")
        check_position_options(
            self.position_is, self.compression_zero, self.position_increases_when
        )
        if self.position_topic in self.wrench_topics:
            raise UsageError(
                f"topic {self.position_topic!r} given as both wrench and position topic"
            )

    def as_dict(self) -> dict[str, Any]:
        """The options by name, for provenance."""
        out = dataclasses.asdict(self)
        out["wrench_topics"] = list(self.wrench_topics)
        if self.crc_check:  # recorded only when off: the logs of checked bags are unchanged
            del out["crc_check"]
        return out


@dataclass(frozen=True)
class SqueezeProtocol:
    """The force-controlled squeezes ``measure --sim`` gives every object.

    Each object is squeezed ``squeezes`` times from rest: a linear force ramp over ``ramp_s``,
    then a hold of ``hold_s``, at peak forces ``linspace(0.5, 1, squeezes) · F_peak``.

    Attributes:
        squeezes: squeezes per object (>= 1; the paper's 3).
        peak_force_n: the largest squeeze's peak force, N, for every object; None: the strain
            rule, ``D · strain · size_x`` per object.
        strain: the strain rule's static strain, in (0, 1) (and below the simulator's
            densification limit).
        ramp_s: the force ramp, s (> 0: a force step does not excite the damping).
        hold_s: the hold at the peak force, s (>= 0).
        gravity: the object lies on the table under gravity; False floats it (a material test).
        noise_force_n: std of Gaussian noise on the force felt, N (>= 0).
        noise_position_m: std of Gaussian noise on each palm position, m (>= 0).

    Raises:
        UsageError: a value outside its rule (exit 2).
    """

    squeezes: int = DEFAULT_SIM_SQUEEZES
    peak_force_n: float | None = None
    strain: float = DEFAULT_SQUEEZE_STRAIN
    ramp_s: float = DEFAULT_SIM_RAMP_S
    hold_s: float = DEFAULT_SIM_HOLD_S
    gravity: bool = True
    noise_force_n: float = 0.0
    noise_position_m: float = 0.0

    def __post_init__(self) -> None:
        SQUEEZES.check(self.squeezes)
        PEAK_FORCE_N.check_optional(self.peak_force_n)
        STRAIN.check(self.strain)
        RAMP_S.check(self.ramp_s)
        HOLD_S.check(self.hold_s)
        NOISE_FORCE_N.check(self.noise_force_n)
        NOISE_POSITION_M.check(self.noise_position_m)

    @property
    def duration_s(self) -> float:
        """One squeeze's length, s."""
        return self.ramp_s + self.hold_s

    def as_dict(self) -> dict[str, Any]:
        """The options by name, for provenance (with the rule that sets the peak force)."""
        return dataclasses.asdict(self)


#: OpenCV's ArUco dictionary the markers come from by default.
DEFAULT_MARKER_DICT = "DICT_4X4_50"

HSV = tuple[int, int, int]


@dataclass(frozen=True)
class ScaleReference:
    """The object of known size in both images: an ArUco marker, or a checkerboard.

    Attributes:
        marker_size_cm: side of the marker's black square, cm (a marker reference).
        marker_dict: the marker's OpenCV dictionary (None: :data:`DEFAULT_MARKER_DICT`).
        marker_id: use only the marker with this id (others ignored); None: any.
        checkerboard: ``(cols, rows)`` inner corners, each >= 2 (a checkerboard reference).
        square_size_cm: the checkerboard's square side, cm.

    Raises:
        UsageError: neither or both references, a marker option with a checkerboard, a
            checkerboard without its square size (or the reverse), or a value outside its rule
            (exit 2).
    """

    marker_size_cm: float | None = None
    marker_dict: str | None = None
    marker_id: int | None = None
    checkerboard: tuple[int, int] | None = None
    square_size_cm: float | None = None

    def __post_init__(self) -> None:
        if self.checkerboard is not None:
            extra = [
                ("--marker-size-cm", self.marker_size_cm),
                ("--marker-dict", self.marker_dict),
                ("--marker-id", self.marker_id),
            ]
            used = [flag for flag, value in extra if value is not None]
            if used:
                raise UsageError(f"{', '.join(used)} cannot be used with --checkerboard")
            if self.square_size_cm is None:
                raise UsageError("--checkerboard needs --square-size-cm")
            cols, rows = self.checkerboard
            if cols < 2 or rows < 2:
                raise UsageError(
                    f"--checkerboard: expected COLSxROWS inner corners, each >= 2, got "
                    f"{cols}x{rows}"
                )
            SQUARE_SIZE_CM.check(self.square_size_cm)
            return
        if self.square_size_cm is not None:
            raise UsageError("--square-size-cm needs --checkerboard")
        if self.marker_size_cm is None:
            raise UsageError(
                "--images needs --marker-size-cm (the side of the marker's black square) "
                "or --checkerboard COLSxROWS with --square-size-cm"
            )
        MARKER_SIZE_CM.check(self.marker_size_cm)
        MARKER_ID.check_optional(self.marker_id)

    @property
    def kind(self) -> str:
        """``checkerboard`` or ``aruco``."""
        return "checkerboard" if self.checkerboard is not None else "aruco"

    def kwargs(self) -> dict[str, Any]:
        """The reference's keyword arguments of :func:`deformctl.vision.measure_object_size`."""
        if self.checkerboard is not None:
            return {
                "marker_dict": self.marker_dict or DEFAULT_MARKER_DICT,
                "checkerboard": self.checkerboard,
                "square_size_cm": float(self.square_size_cm or 0.0),
            }
        out: dict[str, Any] = {
            "marker_dict": self.marker_dict or DEFAULT_MARKER_DICT,
            "marker_size_cm": float(self.marker_size_cm or 0.0),
        }
        if self.marker_id is not None:
            out["marker_id"] = self.marker_id
        return out

    def as_dict(self) -> dict[str, Any]:
        """The reference, for provenance."""
        return {"reference": self.kind, **self.kwargs()}


@dataclass(frozen=True)
class ObjectMask:
    """How the object is told from the scene (default: the difference from a smooth background).

    Attributes:
        color_range: ``(lower, upper)`` OpenCV HSV bounds (H 0..179, S and V 0..255) of the
            object's colour.
        background: the empty scenes ``(top, side)``; the object is what differs.

    Raises:
        UsageError: both, a value out of range, or a lower bound above the upper (exit 2).
    """

    color_range: tuple[HSV, HSV] | None = None
    background: tuple[str, str] | None = None

    def __post_init__(self) -> None:
        if self.color_range is not None and self.background is not None:
            raise UsageError("--color-range and --background cannot be used together")
        if self.color_range is not None:
            lower, upper = self.color_range
            for bound in (lower, upper):
                if not (0 <= bound[0] <= 179 and 0 <= bound[1] <= 255 and 0 <= bound[2] <= 255):
                    raise UsageError(
                        f"--color-range: H must be 0..179, S and V 0..255, got {_hsv(self)!r}"
                    )
            if any(lo > hi for lo, hi in zip(lower, upper, strict=True)):
                raise UsageError(
                    f"--color-range: lower bound above the upper bound in {_hsv(self)!r}"
                )
        if self.background is not None:
            object.__setattr__(self, "background", tuple(self.background))

    def kwargs(self) -> dict[str, Any]:
        """The mask's keyword arguments of :func:`deformctl.vision.measure_object_size`."""
        out: dict[str, Any] = {}
        if self.color_range is not None:
            out["color_range"] = self.color_range
        if self.background is not None:
            out["background_image"] = tuple(self.background)
        return out

    def as_dict(self) -> dict[str, Any]:
        """The mask, for provenance."""
        color = None if self.color_range is None else [list(b) for b in self.color_range]
        background = None if self.background is None else list(self.background)
        return {"color_range": color, "background": background}


def _hsv(mask: ObjectMask) -> str:
    assert mask.color_range is not None
    return ":".join(",".join(str(v) for v in bound) for bound in mask.color_range)


def parse_hsv_pair(text: str) -> tuple[HSV, HSV] | None:
    """``H,S,V:H,S,V`` as two integer triples, or None when malformed."""
    bounds: list[HSV] = []
    parts = text.split(":")
    for part in parts if len(parts) == 2 else []:
        values: Sequence[str] = part.split(",")
        if len(values) != 3 or not all(v.strip().isdigit() for v in values):
            return None
        bounds.append((int(values[0]), int(values[1]), int(values[2])))
    return (bounds[0], bounds[1]) if len(bounds) == 2 else None


#: The command's defaults, for signatures.
DEFAULT_SEGMENTATION = Segmentation()
DEFAULT_SQUEEZE_PROTOCOL = SqueezeProtocol()
