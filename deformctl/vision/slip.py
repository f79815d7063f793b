"""Slip from a frame before and a frame after a lift (``lift --rig ... --slip-from-frames``).

:func:`detect_slip` decides whether the object rose with the palms; :func:`slip_from_frames` is
the ``(before_path, after_path) -> (lifted, slip_m)`` callable the external rig runner accepts.
The camera set-up is described in :mod:`deformctl.vision`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from typing import Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from deformctl.arraytypes import FloatArray
from deformctl.errors import InputDataError, UsageError
from deformctl.reprs import short_repr
from deformctl.units import CM
from deformctl.vision.reference import (
    MARKER_MASK_GROWTH,
    ImageSource,
    _Debug,
    _detect_markers,
    _gray,
    _label,
    _refine_quad_edges,
    _u8,
    load_image,
)
from deformctl.vision.size import (
    _clean,
    _foreground,
    _grow_quad,
    _largest_component,
    _quad_mask,
)

# --------------------------------------------------------------------------------------------
# Slip from frames
# --------------------------------------------------------------------------------------------

SlipStatus = Literal["lifted", "partial_slip", "dropped"]
Region = tuple[int, int, int, int]


@dataclass(frozen=True)
class SlipResult:
    """Outcome of comparing a frame before and a frame after a lift.

    Rises are upwards (image ``-y``); ``slip_m = palm_rise_m - object_rise_m``.

    Attributes:
        lifted: the object rose with the palms within the tolerance.
        slipped: ``not lifted``.
        status: ``"lifted"``; ``"dropped"`` (the object did not rise, or fell back, by more than
            the tolerance); ``"partial_slip"`` (it rose, but fell behind the palms by more).
        object_rise_px: the object's rise, px.
        palm_rise_px: the palms' mean rise, px (``lift_height_m`` converted when not tracked).
        object_rise_m: the object's rise, m.
        palm_rise_m: the palms' rise, m.
        slip_m: how far the object fell behind the palms, m.
        tolerance_m: the tolerance used, m.
        scale_px_per_m: the image scale used, px per m.
        palm_rises_px: each tracked palm's rise, px (empty when the palms were not tracked).
    """

    __repr__ = short_repr

    lifted: bool
    slipped: bool
    status: SlipStatus
    object_rise_px: float
    palm_rise_px: float
    object_rise_m: float
    palm_rise_m: float
    slip_m: float
    tolerance_m: float
    scale_px_per_m: float
    palm_rises_px: tuple[float, ...]


def _match_subpixel(image: NDArray[np.uint8], template: NDArray[np.uint8]) -> tuple[float, float]:
    """Top-left position of ``template`` in ``image`` (normalised correlation, parabolic peak)."""
    res = np.asarray(cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED), dtype=np.float64)
    _, _, _, (bx, by) = cv2.minMaxLoc(res)

    def vertex(a: float, b: float, c: float) -> float:
        den = a - 2.0 * b + c
        return 0.0 if abs(den) < 1e-12 else 0.5 * (a - c) / den

    dx = vertex(res[by, bx - 1], res[by, bx], res[by, bx + 1]) if 0 < bx < res.shape[1] - 1 else 0.0
    dy = vertex(res[by - 1, bx], res[by, bx], res[by + 1, bx]) if 0 < by < res.shape[0] - 1 else 0.0
    return bx + dx, by + dy


def _check_region(region: Sequence[int], shape: tuple[int, ...], label: str) -> Region:
    if len(region) != 4:
        raise UsageError(f"{label} must be x,y,w,h; got {list(region)}")
    x, y, w, h = (int(v) for v in region)
    if w < 4 or h < 4 or x < 0 or y < 0 or x + w > shape[1] or y + h > shape[0]:
        raise UsageError(
            f"{label} {x},{y},{w},{h} is not a region of at least 4x4 px inside the "
            f"{shape[1]}x{shape[0]} px frame"
        )
    return x, y, w, h


def _marker_dict_quads(gray: NDArray[np.uint8], marker_dict: str) -> dict[int, FloatArray]:
    quads, ids, _ = _detect_markers(gray, marker_dict)
    out: dict[int, FloatArray] = {}
    for q, i in zip(quads, ids, strict=True):
        out[i] = _refine_quad_edges(gray, q)
    return out


def _quad_side_px(q: FloatArray) -> float:
    return float(np.mean(np.hypot(*(np.roll(q, -1, axis=0) - q).T)))


def detect_slip(
    before_frame: ImageSource,
    after_frame: ImageSource,
    *,
    palm_regions: Sequence[Sequence[int]] | None = None,
    palm_marker_ids: Sequence[int] | None = None,
    object_region: Sequence[int] | None = None,
    lift_height_m: float | None = None,
    tolerance_m: float = 0.005,
    marker_size_cm: float | None = None,
    marker_dict: str = "DICT_4X4_50",
    scale_px_per_m: float | None = None,
    color_range: tuple[Sequence[int], Sequence[int]] | None = None,
    debug_dir: str | PathLike[str] | None = None,
) -> SlipResult:
    """Decide from a frame before and a frame after a lift whether the object rose with the palms.

    A fixed camera looks at the gripper from the side, roughly perpendicular to the plane of the
    palms' and the object's visible faces. The palms are tracked by template matching of
    ``palm_regions`` (``x, y, w, h`` in the before frame; each must contain a distinctive part of
    a palm, e.g. its lower end, not only a uniform surface) or by ArUco markers on the palms
    (``palm_marker_ids``); with neither, the palms' rise is ``lift_height_m`` (the commanded lift)
    and, if the palms touch the object in the image, ``object_region`` must keep them out.
    The object is the largest foreground region in the columns between the palms (central 60 %;
    or in ``object_region``), with markers removed; its rise is the shift of that region's
    centroid. Scale: ``scale_px_per_m``, else the mean side of the markers in view of known size
    ``marker_size_cm``.

    Classification: ``lifted`` if ``palm_rise - object_rise <= tolerance_m``; otherwise
    ``dropped`` if the object rose by at most ``tolerance_m``, else ``partial_slip``.

    Args:
        before_frame: path or uint8 image, taken with the object gripped, before the lift.
        after_frame: path or image of the same size, taken after the lift.
        palm_regions: palm rectangles ``[(x, y, w, h), ...]`` in the before frame, px.
        palm_marker_ids: ids of ArUco markers fixed to the palms.
        object_region: ``(x, y, w, h)`` in the before frame; its columns (which should show only
            the object and the background) are where the object is tracked. Optional.
        lift_height_m: the commanded lift, m (used when the palms are not tracked).
        tolerance_m: largest shortfall of the object's rise that still counts as lifted, m.
        marker_size_cm: side of the markers in view, cm (for the scale).
        marker_dict: ArUco dictionary of the markers.
        scale_px_per_m: image scale in the plane of the palms, px per m (overrides markers).
        color_range: ``(hsv_lower, hsv_upper)`` selecting the object instead of the background
            difference.
        debug_dir: write ``slip_before.png`` and ``slip_after.png`` with the tracked regions.

    Returns:
        The :class:`SlipResult`.

    Raises:
        MissingInputError: a frame path does not exist.
        InputDataError: unreadable frame, frames of different sizes, palm markers or the object
            not found, palms that did not rise.
        UsageError: bad regions, no way to get the scale or the palms' rise.
    """
    before = load_image(before_frame, name="before frame")
    after = load_image(after_frame, name="after frame")
    if before.shape != after.shape:
        raise InputDataError(
            f"the before frame is {before.shape[1]}x{before.shape[0]} px but the after frame is "
            f"{after.shape[1]}x{after.shape[0]} px; both frames must come from one camera",
            path=_label(after_frame, "after"),
        )
    if not (math.isfinite(tolerance_m) and tolerance_m > 0):
        raise UsageError(f"tolerance_m must be positive, got {tolerance_m}")
    g0 = _gray(before)
    g1 = _gray(after)
    markers0 = _marker_dict_quads(g0, marker_dict)
    markers1 = _marker_dict_quads(g1, marker_dict)

    # Scale.
    if scale_px_per_m is not None:
        if not (math.isfinite(scale_px_per_m) and scale_px_per_m > 0):
            raise UsageError(f"scale_px_per_m must be positive, got {scale_px_per_m}")
        scale = float(scale_px_per_m)
    elif marker_size_cm is not None and markers0:
        scale = float(np.mean([_quad_side_px(q) for q in markers0.values()])) / (
            marker_size_cm * CM
        )
    else:
        raise UsageError(
            "no image scale: give scale_px_per_m, or marker_size_cm with a marker in view"
        )

    # Palms: rectangles in both frames (for the object's column band and the debug output).
    palm_rises: list[float] = []
    palms0: list[Region] = []
    palms1: list[Region] = []
    if palm_regions:
        for k, reg in enumerate(palm_regions):
            x, y, w, h = _check_region(reg, before.shape, f"palm region {k + 1}")
            # Colour template, searched in a band of columns around the palm: the lift is
            # vertical, and a uniform palm's lower end can look like the object's in grey.
            sx0, sx1 = max(0, x - max(w, 20)), min(before.shape[1], x + w + max(w, 20))
            mx, my = _match_subpixel(after[:, sx0:sx1], _u8(before[y : y + h, x : x + w]))
            mx += sx0
            palm_rises.append(y - my)
            palms0.append((x, y, w, h))
            palms1.append((round(mx), round(my), w, h))
    elif palm_marker_ids:
        for mid in palm_marker_ids:
            if mid not in markers0 or mid not in markers1:
                frame = "before" if mid not in markers0 else "after"
                raise InputDataError(
                    f"palm marker {mid} ({marker_dict}) not found in the {frame} frame; rerun "
                    "with --debug-dir DIR to see the detection",
                    path=_label(before_frame if frame == "before" else after_frame, frame),
                )
            q0, q1 = markers0[mid], markers1[mid]
            palm_rises.append(float(q0[:, 1].mean() - q1[:, 1].mean()))
            for q, dest in ((q0, palms0), (q1, palms1)):
                x0, y0 = np.floor(q.min(axis=0)).astype(int)
                x1, y1 = np.ceil(q.max(axis=0)).astype(int)
                dest.append((int(x0), int(y0), int(x1 - x0), int(y1 - y0)))
    elif lift_height_m is None:
        raise UsageError("give palm_regions, palm_marker_ids or lift_height_m")

    if palm_rises:
        palm_rise_px = float(np.mean(palm_rises))
    else:
        assert lift_height_m is not None
        palm_rise_px = float(lift_height_m) * scale

    # Object: foreground without markers and palms.
    def object_mask(
        img: NDArray[np.uint8], markers: dict[int, FloatArray], palms: list[Region]
    ) -> NDArray[np.uint8]:
        exclude = _quad_mask(
            img.shape, [_grow_quad(q, MARKER_MASK_GROWTH) for q in markers.values()]
        )
        for x, y, w, h in palms:
            exclude[max(0, y - 2) : y + h + 2, max(0, x - 2) : x + w + 2] = True
        fore = _foreground(img, exclude, color_range=color_range, background=None)
        return _clean(fore.mask)

    m0 = object_mask(before, markers0, palms0)
    m1 = object_mask(after, markers1, palms1)
    if object_region is not None:
        ox, _, ow, _ = _check_region(object_region, before.shape, "object region")
        c0, c1 = ox, ox + ow
    elif len(palms0) >= 2:
        inner = sorted(palms0, key=lambda r: r[0])
        left_edge = inner[0][0] + inner[0][2]
        right_edge = inner[-1][0]
        if right_edge - left_edge < 10:
            raise InputDataError("the palms overlap in the image; cannot see the object between")
        pad = 0.2 * (right_edge - left_edge)
        c0, c1 = round(left_edge + pad), round(right_edge - pad)
    else:
        comp = _largest_component(m0)
        if comp is None:
            raise InputDataError(
                "no object found in the before frame", path=_label(before_frame, "")
            )
        xs = np.nonzero(comp.any(axis=0))[0]
        pad = 0.2 * (xs.max() - xs.min())
        c0, c1 = round(xs.min() + pad), round(xs.max() - pad) + 1

    def centroid_y(mask: NDArray[np.uint8], frame: str, src: ImageSource) -> float:
        band = np.zeros_like(mask)
        band[:, c0:c1] = mask[:, c0:c1]
        comp = _largest_component(band)
        if comp is None:
            raise InputDataError(
                f"no object found between the palms in the {frame} frame; rerun with "
                "--debug-dir DIR to see the segmentation",
                path=_label(src, frame),
            )
        comp = comp & band  # hole filling must not add pixels outside the band
        ys = np.nonzero(comp)[0]
        return float(ys.mean())

    obj_rise_px = centroid_y(m0, "before", before_frame) - centroid_y(m1, "after", after_frame)
    tol_px = tolerance_m * scale
    if palm_rise_px <= tol_px:
        raise InputDataError(
            f"the palms rose only {palm_rise_px / scale * 1000:.1f} mm between the frames (not "
            f"more than the {tolerance_m * 1000:.1f} mm tolerance); are the frames in order?"
        )
    slip_px = palm_rise_px - obj_rise_px
    lifted = slip_px <= tol_px
    status: SlipStatus
    if lifted:
        status = "lifted"
    elif obj_rise_px <= tol_px:
        status = "dropped"
    else:
        status = "partial_slip"
    if debug_dir is not None:
        dbg = _Debug(debug_dir)
        for name, frame_img, rects in (("before", before, palms0), ("after", after, palms1)):
            out = frame_img.copy()
            for x, y, w, h in rects:
                cv2.rectangle(out, (x, y), (x + w, y + h), (255, 0, 0), 2)
            cv2.line(out, (c0, 0), (c0, out.shape[0] - 1), (0, 255, 255), 1)
            cv2.line(out, (c1, 0), (c1, out.shape[0] - 1), (0, 255, 255), 1)
            cv2.putText(out, f"{status}: slip {slip_px / scale * 1000:.1f} mm", (10, 25),
                        cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 255), 2)  # fmt: skip
            dbg._write(f"slip_{name}.png", out)
    return SlipResult(
        lifted=lifted,
        slipped=not lifted,
        status=status,
        object_rise_px=obj_rise_px,
        palm_rise_px=palm_rise_px,
        object_rise_m=obj_rise_px / scale,
        palm_rise_m=palm_rise_px / scale,
        slip_m=slip_px / scale,
        tolerance_m=float(tolerance_m),
        scale_px_per_m=scale,
        palm_rises_px=tuple(palm_rises),
    )


def slip_from_frames(
    before_path: str | PathLike[str], after_path: str | PathLike[str], **options: object
) -> tuple[bool, float]:
    """``(lifted, slip_m)`` from two frame files; the callable the external rig runner accepts.

    ``options`` are :func:`detect_slip`'s keyword arguments; bind them with
    ``functools.partial(slip_from_frames, palm_regions=..., marker_size_cm=...)``.
    """
    result = detect_slip(before_path, after_path, **options)  # type: ignore[arg-type]
    return result.lifted, result.slip_m
