"""``lift rig --slip-from-frames``: judge rig answers that carry camera frames.

A rig that only takes pictures answers ``{"before_frame": ..., "after_frame": ...}``; deformctl
then decides ``lifted`` and ``slip_m`` with :func:`deformctl.vision.slip_from_frames`, bound
here to the command-line options with :func:`functools.partial`.
"""

from __future__ import annotations

import functools
import os
import re
from typing import TYPE_CHECKING, Annotated, Any

import typer

from deformctl.cli._options import HEAVY_DEFAULTS, OptionGroup, default
from deformctl.errors import UsageError
from deformctl.quantities import MARKER_SIZE_CM, SLIP_TOLERANCE_M

if TYPE_CHECKING:  # pragma: no cover - the rig runner (pandas, MCAP) loads when it runs
    from deformctl.lift.runners.rig import SlipFromFrames

#: Default ``--slip-tolerance-m`` (``detect_slip``'s): the object may fall behind the palms so
#: far, m.
DEFAULT_SLIP_TOLERANCE_M = float(str(HEAVY_DEFAULTS["detect_slip.tolerance_m"]))


def parse_palm_marker_ids(text: str) -> tuple[int, ...]:
    """Parse ``L,R`` marker ids (integers >= 0, at least one, no repeats).

    Raises:
        UsageError: a malformed list.
    """
    parts = [p.strip() for p in text.split(",")]
    if not parts or not all(p.isdigit() for p in parts) or len(set(parts)) != len(parts):
        raise UsageError(f"--palm-marker-ids: expected distinct ids L,R (e.g. 1,2), got {text!r}")
    return tuple(int(p) for p in parts)


def parse_palm_regions(text: str) -> tuple[tuple[int, int, int, int], ...]:
    """Parse ``x,y,w,h;x,y,w,h`` (px in the before frame, one rectangle per palm).

    Raises:
        UsageError: a malformed list (sizes and bounds are checked against the frame later).
    """
    regions = []
    for part in text.split(";"):
        if not re.fullmatch(r"\s*\d+\s*,\s*\d+\s*,\s*\d+\s*,\s*\d+\s*", part):
            raise UsageError(
                f"--palm-regions: expected x,y,w,h;x,y,w,h (px, one per palm), got {text!r}"
            )
        x, y, w, h = (int(v) for v in part.split(","))
        regions.append((x, y, w, h))
    return tuple(regions)


def frames_judge(
    *,
    enabled: bool,
    palm_marker_ids: str | None,
    palm_regions: str | None,
    frame_marker_size_cm: float | None,
    slip_tolerance_m: float | None,
    marker_dict: str | None,
    debug_dir: str | None,
) -> SlipFromFrames | None:
    """The ``(before, after) -> (lifted, slip_m)`` callable the options ask for, or None.

    Raises:
        UsageError: frame options without ``--slip-from-frames``, neither or both of the palm
            options, no ``--frame-marker-size-cm``, a bad tolerance or marker size.
    """
    given = [
        ("--palm-marker-ids", palm_marker_ids),
        ("--palm-regions", palm_regions),
        ("--frame-marker-size-cm", frame_marker_size_cm),
        ("--slip-tolerance-m", slip_tolerance_m),
        ("--frame-marker-dict", marker_dict),
        ("--debug-dir", debug_dir),
    ]
    if not enabled:
        used = [flag for flag, value in given if value is not None]
        if used:
            raise UsageError(f"{', '.join(used)} needs --slip-from-frames")
        return None
    if (palm_marker_ids is None) == (palm_regions is None):
        raise UsageError("--slip-from-frames needs one of --palm-marker-ids or --palm-regions")
    if frame_marker_size_cm is None:
        raise UsageError(
            "--slip-from-frames needs --frame-marker-size-cm (the side of the markers in view, "
            "for the image scale)"
        )
    MARKER_SIZE_CM.check(frame_marker_size_cm, label="--frame-marker-size-cm")
    tolerance_m = DEFAULT_SLIP_TOLERANCE_M if slip_tolerance_m is None else slip_tolerance_m
    SLIP_TOLERANCE_M.check(tolerance_m)
    if debug_dir is not None and os.path.exists(debug_dir) and not os.path.isdir(debug_dir):
        raise UsageError(f"--debug-dir {debug_dir!r} exists and is not a directory")
    options: dict[str, Any] = {
        "marker_size_cm": float(frame_marker_size_cm),
        "tolerance_m": float(tolerance_m),
        "marker_dict": marker_dict or str(HEAVY_DEFAULTS["detect_slip.marker_dict"]),
    }
    if palm_marker_ids is not None:
        options["palm_marker_ids"] = parse_palm_marker_ids(palm_marker_ids)
    else:
        assert palm_regions is not None
        options["palm_regions"] = parse_palm_regions(palm_regions)
    if debug_dir is not None:
        options["debug_dir"] = debug_dir
    from deformctl.vision import slip_from_frames  # deferred: OpenCV

    return functools.partial(slip_from_frames, **options)


PalmMarkerIds = Annotated[
    str | None,
    typer.Option("--palm-marker-ids", metavar="L,R", help="Frames: the palms' ArUco marker ids."),
]
PalmRegions = Annotated[
    str | None,
    typer.Option(
        "--palm-regions",
        metavar="x,y,w,h;...",
        help="Frames: the palms' rectangles in the before frame, px.",
    ),
]
FrameMarkerSizeCm = Annotated[
    float | None,
    typer.Option(
        "--frame-marker-size-cm", metavar="S", help="Frames: side of the markers in view, cm."
    ),
]
FrameMarkerDict = Annotated[
    str | None,
    typer.Option(
        "--frame-marker-dict",
        metavar="DICT",
        help=f"Frames: ArUco dictionary {default('detect_slip.marker_dict')}.",
    ),
]
FrameSlipToleranceM = Annotated[
    float | None,
    typer.Option(
        "--slip-tolerance-m",
        metavar="T",
        help=f"Frames: slip that fails an attempt, m {default('detect_slip.tolerance_m')}.",
    ),
]
SlipFromFramesOption = Annotated[
    bool,
    typer.Option("--slip-from-frames", help="Judge slip from the rig's before/after frames."),
]
DebugDir = Annotated[
    str | None,
    typer.Option("--debug-dir", metavar="DIR", help="Frames: write annotated frames here."),
]


def _judge(
    *,
    slip_from_frames: bool,
    palm_marker_ids: str | None,
    palm_regions: str | None,
    frame_marker_size_cm: float | None,
    frame_marker_dict: str | None,
    slip_tolerance_m: float | None,
    debug_dir: str | None,
) -> SlipFromFrames | None:
    return frames_judge(
        enabled=slip_from_frames,
        palm_marker_ids=palm_marker_ids,
        palm_regions=palm_regions,
        frame_marker_size_cm=frame_marker_size_cm,
        slip_tolerance_m=slip_tolerance_m,
        marker_dict=frame_marker_dict,
        debug_dir=debug_dir,
    )


#: ``--slip-from-frames`` and its options as one judge of the rig's frames (or None).
FRAMES = OptionGroup(
    "judge",
    (
        ("slip_from_frames", SlipFromFramesOption, False),
        ("palm_marker_ids", PalmMarkerIds, None),
        ("palm_regions", PalmRegions, None),
        ("frame_marker_size_cm", FrameMarkerSizeCm, None),
        ("frame_marker_dict", FrameMarkerDict, None),
        ("slip_tolerance_m", FrameSlipToleranceM, None),
        ("debug_dir", DebugDir, None),
    ),
    _judge,
)


__all__ = ["DEFAULT_SLIP_TOLERANCE_M", "FRAMES", "frames_judge", "parse_palm_marker_ids"]
