"""Slip from two frames (deformctl.vision.slip) on scenes rendered with known geometry.

A box between two palms is rendered before and after a lift of the palms by 3 cm; the object
rises by 3, 2.8, 1.5 or 0 cm, and ``detect_slip`` must call it lifted, partly slipped or dropped,
with the palms found by regions or by their own markers. Frames read from files, the lift height
instead of palms, and bad inputs (one-line errors) are checked too.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from deformctl import vision
from deformctl.errors import InputDataError, MissingInputError, UsageError
from deformctl.units import CM
from tests._helpers.vision_render import Box, Camera, Marker, Scene, camera_side, render

from ._common import FOCAL_PX, _one_line

SLIP_OBJECT = (8.0, 6.0, 6.0)  # cm
PALM_WIDTH_CM = 3.0
PALM_BOTTOM_CM = 1.0
SLIP_MARKER_CM = 2.4
PALM_RISE_CM = 3.0


def _slip_scene(object_rise_cm: float, palm_rise_cm: float, *, palm_markers: bool) -> Scene:
    sx, sy, sz = SLIP_OBJECT
    y_front = -sy / 2
    obj = Box((0.0, 0.0), SLIP_OBJECT, (180, 70, 40), z0=object_rise_cm)
    z0 = PALM_BOTTOM_CM + palm_rise_cm
    palms = [
        Box(
            (side * (sx / 2 + PALM_WIDTH_CM / 2), 0.0),
            (PALM_WIDTH_CM, sy, sz + 3.0),
            (110, 110, 110),
            z0=z0,
        )
        for side in (-1.0, 1.0)
    ]
    markers = [Marker.upright(11.0, y_front, 1.0, SLIP_MARKER_CM, marker_id=0)]  # static scale
    if palm_markers:
        for mid, side in ((1, -1.0), (2, 1.0)):
            x0 = side * (sx / 2 + PALM_WIDTH_CM / 2) - SLIP_MARKER_CM / 2
            markers.append(
                Marker.upright(x0, y_front - 0.05, z0 + sz - 1.0, SLIP_MARKER_CM, marker_id=mid)
            )
    return Scene(boxes=[obj, *palms], markers=markers)


def _slip_camera() -> Camera:
    return camera_side((2.0, -SLIP_OBJECT[1] / 2, 4.0), 45.0, 0.0, focal_px=FOCAL_PX)


def _palm_regions(cam: Camera) -> list[tuple[int, int, int, int]]:
    """Each palm's lower end in the before frame (its lowest 3 cm plus 10 px below), px."""
    sx, sy, _ = SLIP_OBJECT
    regions = []
    for side in (-1.0, 1.0):
        cx = side * (sx / 2 + PALM_WIDTH_CM / 2)
        pts = np.array(
            [
                [cx + dx, -sy / 2, z]
                for dx in (-1.2, 1.2)
                for z in (PALM_BOTTOM_CM, PALM_BOTTOM_CM + 3)
            ]
        )
        px = cam.project(pts)
        x0, y0 = np.floor(px.min(axis=0)).astype(int)
        x1, y1 = np.ceil(px.max(axis=0)).astype(int)
        regions.append((int(x0), int(y0), int(x1 - x0), int(y1 - y0 + 10)))
    return regions


SLIP_CASES = [("lifted", 3.0), ("lifted", 2.8), ("partial_slip", 1.5), ("dropped", 0.0)]


@pytest.mark.parametrize("palm_markers", [False, True], ids=["regions", "markers"])
@pytest.mark.parametrize(("status", "object_rise_cm"), SLIP_CASES)
def test_slip_classification(status: str, object_rise_cm: float, palm_markers: bool) -> None:
    cam = _slip_camera()
    before = render(_slip_scene(0.0, 0.0, palm_markers=palm_markers), cam, seed=11)
    after = render(
        _slip_scene(object_rise_cm, PALM_RISE_CM, palm_markers=palm_markers), cam, seed=12
    )
    options: dict[str, object] = {"marker_size_cm": SLIP_MARKER_CM, "tolerance_m": 0.005}
    if palm_markers:
        options["palm_marker_ids"] = (1, 2)
    else:
        options["palm_regions"] = _palm_regions(cam)
    res = vision.detect_slip(before, after, **options)  # type: ignore[arg-type]
    assert res.status == status
    assert res.lifted == (status == "lifted")
    assert res.slipped == (not res.lifted)
    assert res.palm_rise_m == pytest.approx(PALM_RISE_CM * CM, abs=0.5e-3)
    assert res.object_rise_m == pytest.approx(object_rise_cm * CM, abs=0.5e-3)
    assert res.slip_m == pytest.approx((PALM_RISE_CM - object_rise_cm) * CM, abs=0.7e-3)


def test_slip_from_frames_files_and_lift_height(tmp_path: Path) -> None:
    cam = _slip_camera()
    b, a = tmp_path / "before.png", tmp_path / "after.png"
    cv2.imwrite(str(b), render(_slip_scene(0.0, 0.0, palm_markers=False), cam, seed=13))
    cv2.imwrite(str(a), render(_slip_scene(1.5, PALM_RISE_CM, palm_markers=False), cam, seed=14))
    lifted, slip_m = vision.slip_from_frames(
        b,
        a,
        palm_regions=_palm_regions(cam),
        marker_size_cm=SLIP_MARKER_CM,
        debug_dir=tmp_path / "d",
    )
    assert lifted is False
    assert slip_m == pytest.approx(0.015, abs=0.7e-3)
    assert (tmp_path / "d" / "slip_after.png").exists()
    # Without palm tracking, the commanded lift height stands in for the palms' rise; the object
    # region (its columns in the before frame) keeps the palms out of the object's band.
    (x0, y0), (x1, y1) = cam.project(np.array([[-3.0, -3.0, 0.0], [3.0, -3.0, 6.0]]))
    region = (round(x0), round(y1), round(x1 - x0), round(y0 - y1))
    res = vision.detect_slip(
        b, a, lift_height_m=0.03, marker_size_cm=SLIP_MARKER_CM, object_region=region
    )
    assert res.status == "partial_slip"
    assert res.slip_m == pytest.approx(0.015, abs=1e-3)


def test_slip_bad_inputs(tmp_path: Path) -> None:
    cam = _slip_camera()
    before = render(_slip_scene(0.0, 0.0, palm_markers=False), cam, seed=15)
    small = cv2.resize(before, (640, 480))
    with pytest.raises(InputDataError) as err:
        vision.detect_slip(before, small, lift_height_m=0.03, marker_size_cm=SLIP_MARKER_CM)
    text = _one_line(err)
    assert "960x720" in text
    assert "640x480" in text
    bad = tmp_path / "after.png"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    with pytest.raises(InputDataError) as err2:
        vision.slip_from_frames(
            _write(tmp_path, before), bad, lift_height_m=0.03, marker_size_cm=SLIP_MARKER_CM
        )
    assert "not a readable image" in _one_line(err2)
    with pytest.raises(MissingInputError):
        vision.slip_from_frames(tmp_path / "nope.png", bad, lift_height_m=0.03)
    # Frames in the wrong order / no lift: the palms did not rise.
    with pytest.raises(InputDataError) as err3:
        vision.detect_slip(
            before, before, palm_regions=_palm_regions(cam), marker_size_cm=SLIP_MARKER_CM
        )
    assert "palms rose only" in _one_line(err3)
    with pytest.raises(UsageError):
        vision.detect_slip(before, before, marker_size_cm=SLIP_MARKER_CM)  # no palms, no height
    with pytest.raises(UsageError):
        vision.detect_slip(before, before, lift_height_m=0.03)  # no scale


def _write(tmp_path: Path, img: NDArray[np.uint8]) -> Path:
    p = tmp_path / "frame.png"
    cv2.imwrite(str(p), img)
    return p
