"""Object size from a top and a side image with a scale reference (``measure --images``).

:func:`measure_object_size` measures an object's x, y, z size in cm; :func:`catalog_row` turns the
result into an object-catalog row. The geometry the user must set up, the parallax correction
and the segmentation are described in :mod:`deformctl.vision`.
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
from deformctl.catalog import catalog_row as new_catalog_row
from deformctl.errors import InputDataError, UsageError
from deformctl.reprs import short_repr
from deformctl.vision.camera import CameraCalibration, undistort
from deformctl.vision.reference import (
    DEFAULT_HFOV_DEG,
    MARKER_MASK_GROWTH,
    ImageSource,
    ViewName,
    _apply_h,
    _camera_center,
    _Debug,
    _default_camera_matrix,
    _f64,
    _find_reference,
    _label,
    _rect_along_axes,
    _Reference,
    _section_rect,
    _u8,
    load_image,
)

#: Fixed-point iterations coupling the top view (needs the height) and the side view (the depth).
_VIEW_ITERATIONS = 4


# --------------------------------------------------------------------------------------------
# Segmentation
# --------------------------------------------------------------------------------------------


#: Terms of the background surface at each trimming pass: constant, plane, then the quadratic.
_BACKGROUND_STAGES = (1, 3, 3, 6, 6, 6, 6)


def _quadratic_terms(u: FloatArray, v: FloatArray) -> list[FloatArray]:
    return [np.ones_like(u + v), u, v, u * u, u * v, v * v]


def _background_model(img: NDArray[np.uint8], exclude: NDArray[np.bool_]) -> FloatArray:
    """A smooth background, a quadratic surface per channel fitted robustly; float ``[h, w, 3]``.

    Fitted on a coarse grid by iteratively trimmed least squares (pixels more than three robust
    standard deviations from the surface, i.e. the object and the marker, are dropped). The fit
    grows from a constant (the median colour: the background must cover most of the photo) to a
    plane to the quadratic, so that a large or strongly coloured object cannot bend the first
    surface towards itself and hide in it (a full quadratic fitted first to a photo with a 16 %
    orange box on grey absorbed the box: no object was found).
    """
    h, w = img.shape[:2]
    step = max(1, round(max(h, w) / 160))
    ys = np.arange(0, h, step)
    xs = np.arange(0, w, step)
    vals = img[ys][:, xs].reshape(-1, 3).astype(np.float64)
    gv, gu = np.meshgrid(
        ys / max(h - 1, 1) * 2.0 - 1.0, xs / max(w - 1, 1) * 2.0 - 1.0, indexing="ij"
    )
    design = np.column_stack([t.ravel() for t in _quadratic_terms(gu, gv)])  # [n, 6]
    allowed = ~exclude[ys][:, xs].ravel()
    keep = allowed.copy()
    coef = np.zeros((6, 3))
    for n_terms in _BACKGROUND_STAGES:
        a = design[keep][:, :n_terms]
        coef = np.zeros((6, 3))
        if n_terms == 1:
            coef[0] = np.median(vals[keep], axis=0)
        else:
            gram = a.T @ a + 1e-9 * np.eye(n_terms)
            coef[:n_terms] = _f64(np.linalg.solve(gram, a.T @ vals[keep]))  # [n_terms, 3]
        resid = np.linalg.norm(vals - design @ coef, axis=1)
        sigma = 1.4826 * float(np.median(resid[keep])) + 1e-6
        keep = (resid < 3.0 * sigma + 2.0) & allowed
    u = (np.arange(w) / max(w - 1, 1) * 2.0 - 1.0)[None, :]
    v = (np.arange(h) / max(h - 1, 1) * 2.0 - 1.0)[:, None]
    terms = _quadratic_terms(u, v)
    model = np.empty((h, w, 3))
    for ch in range(3):
        model[..., ch] = sum(c * t for c, t in zip(coef[:, ch], terms, strict=True))
    return model


def _otsu_threshold(diff: FloatArray, valid: NDArray[np.bool_]) -> float:
    """Threshold a difference image: Otsu's split, then the midpoint of the two class means.

    Otsu alone is ambiguous for two narrow, well separated modes (any threshold between them
    scores the same, and OpenCV takes the lowest, which grows the object by about half a pixel);
    the midpoint of the class means puts a blurred edge at half its contrast, where it belongs.
    """
    d8 = np.clip(diff, 0, 255).astype(np.uint8)
    values = d8[valid]
    thresh, _ = cv2.threshold(values.reshape(-1, 1), 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    for _ in range(3):
        hi = values > thresh
        if not hi.any() or hi.all():
            break
        thresh = 0.5 * (float(values[hi].mean()) + float(values[~hi].mean()))
    return float(thresh)


@dataclass(frozen=True)
class _Foreground:
    """A foreground mask and, when it came from a threshold, the score image it thresholds."""

    mask: NDArray[np.bool_]  # [h, w]
    score: FloatArray | None  # [h, w], foreground where score > threshold
    threshold: float


def _foreground(
    img: NDArray[np.uint8],
    exclude: NDArray[np.bool_],
    *,
    color_range: tuple[Sequence[int], Sequence[int]] | None,
    background: NDArray[np.uint8] | None,
) -> _Foreground:
    """Foreground ``[h, w]`` (before cleaning), with ``exclude`` removed."""
    valid = ~exclude
    if color_range is not None:
        lower = np.asarray(color_range[0], dtype=np.uint8)
        upper = np.asarray(color_range[1], dtype=np.uint8)
        hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV)
        mask = np.asarray(cv2.inRange(hsv, lower, upper) > 0, dtype=np.bool_) & valid
        return _Foreground(mask, None, 0.5)
    if background is not None:
        diff = np.linalg.norm(img.astype(np.float64) - background.astype(np.float64), axis=2)
    else:
        model = _background_model(img, exclude)
        diff = np.linalg.norm(img.astype(np.float64) - model, axis=2)
    diff = cv2.GaussianBlur(diff, (3, 3), 0)
    # A threshold that does not clear the background's own variation (noise, lighting left
    # over by the model) separates nothing: then there is no object.
    floor = max(_MIN_CONTRAST, 4.0 * float(np.median(diff[valid])))
    thresh = max(_otsu_threshold(diff, valid), floor)
    return _Foreground((diff > thresh) & valid, np.where(valid, diff, 0.0), thresh)


#: Smallest colour difference from the background (0..255 scale, Euclidean over B, G, R) that
#: counts as foreground.
_MIN_CONTRAST = 12.0
#: Upsampling factor for the sub-pixel object outline.
_SUBPIXEL = 4


def _subpixel_hull(obj: NDArray[np.uint8], fg: _Foreground) -> FloatArray:
    """Convex hull of the object's outline with sub-pixel precision, px ``[k, 2]``.

    The score image is interpolated bilinearly by ``_SUBPIXEL`` around the object and thresholded
    again (close to a marching-squares iso-line), restricted to the grown pixel mask. The hull of
    the fine cells' corners lies within ``0.5 / _SUBPIXEL`` px of the threshold iso-line whatever
    the edge direction (the hull of whole pixels would be biased outwards on slanted edges).
    """
    up = _SUBPIXEL
    ys, xs = np.nonzero(obj)
    h, w = obj.shape
    y0, y1 = max(0, int(ys.min()) - 2), min(h, int(ys.max()) + 3)
    x0, x1 = max(0, int(xs.min()) - 2), min(w, int(xs.max()) + 3)
    grown = cv2.dilate(obj[y0:y1, x0:x1], np.ones((3, 3), np.uint8))
    size = ((x1 - x0) * up, (y1 - y0) * up)
    if fg.score is None:
        fine = cv2.resize(obj[y0:y1, x0:x1], size, interpolation=cv2.INTER_NEAREST) > 0
    else:
        score = cv2.resize(fg.score[y0:y1, x0:x1], size, interpolation=cv2.INTER_LINEAR)
        keep = cv2.resize(grown, size, interpolation=cv2.INTER_NEAREST) > 0
        fine = (score > fg.threshold) & keep
    comp = _largest_component(fine.astype(np.uint8) * 255)
    if comp is None:  # pragma: no cover - the coarse component is never empty here
        comp = _u8(cv2.resize(obj[y0:y1, x0:x1], size, interpolation=cv2.INTER_NEAREST))
    contours, _ = cv2.findContours(comp, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    pts = np.concatenate([c.reshape(-1, 2) for c in contours]).astype(np.float32)
    hull = cv2.convexHull(pts).reshape(-1, 2).astype(np.float64)
    offsets = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    corners = (hull[:, None, :] + offsets[None, :, :]).reshape(-1, 2)
    # fine cell centre (i + 0.5) / up - 0.5 in coarse pixel coordinates
    corners = (corners + 0.5) / up - 0.5 + np.array([x0, y0], dtype=np.float64)
    return cv2.convexHull(corners.astype(np.float32)).reshape(-1, 2).astype(np.float64)


def _clean(mask: NDArray[np.bool_]) -> NDArray[np.uint8]:
    m = mask.astype(np.uint8) * 255
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
    m = _u8(cv2.morphologyEx(m, cv2.MORPH_OPEN, kernel))
    return np.asarray(cv2.morphologyEx(m, cv2.MORPH_CLOSE, kernel), dtype=np.uint8)


def _largest_component(mask: NDArray[np.uint8]) -> NDArray[np.uint8] | None:
    """The largest 8-connected component, holes filled; ``None`` when the mask is empty."""
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    if n <= 1:
        return None
    best = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    comp = (labels == best).astype(np.uint8) * 255
    contours, _ = cv2.findContours(comp, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    filled = np.zeros_like(comp)
    cv2.drawContours(filled, contours, -1, 255, thickness=cv2.FILLED)
    return filled


def _quad_mask(shape: tuple[int, ...], quads: Sequence[FloatArray]) -> NDArray[np.bool_]:
    m = np.zeros(shape[:2], dtype=np.uint8)
    for q in quads:
        cv2.fillPoly(m, [np.round(q).astype(np.int32)], 255)
    return m > 0


def _grow_quad(quad: FloatArray, factor: float) -> FloatArray:
    """Grow a quad about its centre by ``factor``, in the quad's own (projective) plane."""
    unit = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    h = cv2.getPerspectiveTransform(unit.astype(np.float32), quad.astype(np.float32))
    grown = (unit - 0.5) * factor + 0.5
    return _apply_h(np.asarray(h, dtype=np.float64), grown)


# --------------------------------------------------------------------------------------------
# Size measurement
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ViewMeasurement:
    """What was measured in one image (top or side), in the reference's plane frame.

    Attributes:
        view: ``"top"`` or ``"side"``.
        image_shape: ``(h, w)`` in px.
        reference: ``"aruco"`` or ``"checkerboard"``.
        marker_id: the ArUco id used as scale reference (``None`` for a checkerboard).
        reference_outline_px: the reference's outer quad in the image, px ``[4, 2]``.
        homography_img_to_plane: image px to plane cm, ``[3, 3]``.
        scale_px_per_cm: image scale at the reference, px per cm (sqrt of the area ratio).
        camera_center_cm: camera centre in the plane frame, cm ``[3]`` (z < 0 faces the print).
        contour_px: the object's outer contour in the image, px ``[n, 2]``.
        section_cm: the object's cross-section after the parallax correction, cm ``[m, 2]``.
        rect_corners_cm: its minimum-area rectangle, cm ``[4, 2]``.
        size_along_x_cm: rectangle side more nearly parallel to the reference x axis, cm.
        size_along_y_cm: the other side, cm.
        angle_deg: angle of the along-x side from the reference x axis, degrees in (-45, 45].
    """

    __repr__ = short_repr

    view: ViewName
    image_shape: tuple[int, int]
    reference: Literal["aruco", "checkerboard"]
    marker_id: int | None
    reference_outline_px: FloatArray
    homography_img_to_plane: FloatArray
    scale_px_per_cm: float
    camera_center_cm: FloatArray
    contour_px: FloatArray
    section_cm: FloatArray
    rect_corners_cm: FloatArray
    size_along_x_cm: float
    size_along_y_cm: float
    angle_deg: float


@dataclass(frozen=True)
class SizeMeasurement:
    """An object's size from a top and a side image.

    Attributes:
        size_x_cm: top view, the side of the footprint more nearly parallel to the marker x axis.
        size_y_cm: top view, the other side of the footprint.
        size_z_cm: side view, the height (along the upright marker's y axis).
        top: details of the top view.
        side: details of the side view (``side.size_along_x_cm`` is the visible width, a
            cross-check of ``size_x_cm`` or ``size_y_cm``).
        height_correction_pct: how much the parallax correction for the object's height changed
            the top view's footprint, % (mean of both sides; negative: the flat reading was
            too large, as the top face is nearer the camera than the marker).
        assumed_hfov_deg: the horizontal field of view assumed for want of a camera matrix,
            degrees; None when one was given.
    """

    __repr__ = short_repr

    size_x_cm: float
    size_y_cm: float
    size_z_cm: float
    top: ViewMeasurement
    side: ViewMeasurement
    height_correction_pct: float = 0.0
    assumed_hfov_deg: float | None = None


@dataclass(frozen=True)
class _Silhouette:
    ref: _Reference
    h_img_to_plane: FloatArray
    scale_px_per_cm: float
    center_cm: FloatArray
    contour_px: FloatArray
    hull_cm: FloatArray
    mask: NDArray[np.uint8]


def _silhouette(
    img: NDArray[np.uint8],
    *,
    view: ViewName,
    path: str | None,
    marker_size_cm: float | None,
    marker_dict: str,
    marker_id: int | None,
    checkerboard: tuple[int, int] | None,
    square_size_cm: float | None,
    color_range: tuple[Sequence[int], Sequence[int]] | None,
    background: NDArray[np.uint8] | None,
    camera_matrix: FloatArray | None,
    debug: _Debug | None,
) -> _Silhouette:
    ref = _find_reference(
        img,
        view=view,
        path=path,
        marker_size_cm=marker_size_cm,
        marker_dict=marker_dict,
        marker_id=marker_id,
        checkerboard=checkerboard,
        square_size_cm=square_size_cm,
        debug=debug,
    )
    h_img_to_plane = _f64(cv2.findHomography(ref.image_pts, ref.plane_pts_cm)[0])
    area_px = abs(cv2.contourArea(ref.image_pts[_hull_order(ref.image_pts)].astype(np.float32)))
    area_cm = abs(
        cv2.contourArea(ref.plane_pts_cm[_hull_order(ref.plane_pts_cm)].astype(np.float32))
    )
    scale = math.sqrt(area_px / area_cm)
    k = _default_camera_matrix(img.shape) if camera_matrix is None else camera_matrix
    center = _camera_center(ref, k)

    grow = MARKER_MASK_GROWTH if ref.kind == "aruco" else 1.1
    quads = [_grow_quad(ref.outline_px, grow)]
    quads += [_grow_quad(q, MARKER_MASK_GROWTH) for q in ref.other_markers_px]
    exclude = _quad_mask(img.shape, quads)
    fore = _foreground(img, exclude, color_range=color_range, background=background)
    fg = _clean(fore.mask)
    obj = _largest_component(fg)
    if debug is not None:
        debug.write_mask(f"{view}_mask.png", fg)
    if obj is None or int(np.count_nonzero(obj)) < 50:
        raise InputDataError(
            f"no object found in the {view} image; use a uniform background that differs from "
            "the object, or give a colour range or a background image (see --debug-dir)",
            path=path,
        )
    if obj[0, :].any() or obj[-1, :].any() or obj[:, 0].any() or obj[:, -1].any():
        raise InputDataError(
            f"the object touches the border of the {view} image; the whole object must be "
            "visible (move the camera back)",
            path=path,
        )
    contours, _ = cv2.findContours(obj, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    contour = np.asarray(max(contours, key=cv2.contourArea), dtype=np.float64).reshape(-1, 2)
    hull_px = _subpixel_hull(obj, fore)
    hull_cm = _apply_h(h_img_to_plane, hull_px)
    return _Silhouette(ref, h_img_to_plane, scale, center, contour, hull_cm, obj)


def _hull_order(pts: FloatArray) -> NDArray[np.intp]:
    idx = cv2.convexHull(pts.astype(np.float32), returnPoints=False)
    return np.asarray(idx, dtype=np.intp).ravel()


def _view_from(
    view: ViewName, sil: _Silhouette, shape: tuple[int, ...], near_cm: float, far_cm: float
) -> ViewMeasurement:
    corners, section = _section_rect(sil.hull_cm, sil.center_cm, near_cm, far_cm)
    along_x, along_y, angle = _rect_along_axes(corners)
    return ViewMeasurement(
        view=view,
        image_shape=(int(shape[0]), int(shape[1])),
        reference=sil.ref.kind,
        marker_id=sil.ref.marker_id,
        reference_outline_px=sil.ref.outline_px,
        homography_img_to_plane=sil.h_img_to_plane,
        scale_px_per_cm=sil.scale_px_per_cm,
        camera_center_cm=sil.center_cm,
        contour_px=sil.contour_px,
        section_cm=section,
        rect_corners_cm=corners,
        size_along_x_cm=along_x,
        size_along_y_cm=along_y,
        angle_deg=angle,
    )


def measure_view(
    image: ImageSource,
    *,
    view: ViewName,
    marker_size_cm: float | None = None,
    marker_dict: str = "DICT_4X4_50",
    marker_id: int | None = None,
    checkerboard: tuple[int, int] | None = None,
    square_size_cm: float | None = None,
    color_range: tuple[Sequence[int], Sequence[int]] | None = None,
    background_image: ImageSource | None = None,
    camera_matrix: ArrayLikeMatrix | None = None,
    normal_extent_cm: tuple[float, float] = (0.0, 0.0),
    debug_dir: str | PathLike[str] | None = None,
) -> ViewMeasurement:
    """Measure one view: the object's cross-section in the reference plane.

    ``normal_extent_cm = (far, near)`` is the object's extent along the plane normal, positive
    towards the camera (top view: ``(0, height)``; side view: ``(-depth, 0)``); ``(0, 0)`` treats
    the object as flat in the reference plane (no parallax correction). Other arguments as in
    :func:`measure_object_size`.
    """
    img = load_image(image, name=f"{view} image")
    bg = _load_background(background_image, img, view)
    debug = None if debug_dir is None else _Debug(debug_dir)
    sil = _silhouette(
        img,
        view=view,
        path=_label(image, view),
        marker_size_cm=marker_size_cm,
        marker_dict=marker_dict,
        marker_id=marker_id,
        checkerboard=checkerboard,
        square_size_cm=square_size_cm,
        color_range=color_range,
        background=bg,
        camera_matrix=_camera_matrix(camera_matrix),
        debug=debug,
    )
    far, near = normal_extent_cm
    result = _view_from(view, sil, img.shape, near, far)
    if debug is not None:
        text = f"{view}: {result.size_along_x_cm:.2f} x {result.size_along_y_cm:.2f} cm"
        debug.write_view(result, img, text)
    return result


ArrayLikeMatrix = NDArray[np.float64] | Sequence[Sequence[float]]


def _camera_matrix(k: ArrayLikeMatrix | None) -> FloatArray | None:
    if k is None:
        return None
    arr = np.asarray(k, dtype=np.float64)
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)) or arr[0, 0] <= 0 or arr[1, 1] <= 0:
        raise UsageError("camera_matrix must be a finite 3x3 pinhole matrix with fx, fy > 0")
    return arr


def _load_background(
    background_image: ImageSource | None, img: NDArray[np.uint8], view: str
) -> NDArray[np.uint8] | None:
    if background_image is None:
        return None
    bg = load_image(background_image, name=f"{view} background image")
    if bg.shape != img.shape:
        raise InputDataError(
            f"the {view} background image is {bg.shape[1]}x{bg.shape[0]} px but the {view} "
            f"image is {img.shape[1]}x{img.shape[0]} px; they must match",
            path=_label(background_image, view),
        )
    return bg


def measure_object_size(
    top_image: ImageSource,
    side_image: ImageSource,
    *,
    marker_size_cm: float | None = None,
    marker_dict: str = "DICT_4X4_50",
    marker_id: int | None = None,
    checkerboard: tuple[int, int] | None = None,
    square_size_cm: float | None = None,
    color_range: tuple[Sequence[int], Sequence[int]] | None = None,
    background_image: ImageSource | tuple[ImageSource, ImageSource] | None = None,
    camera_matrix: ArrayLikeMatrix | None = None,
    debug_dir: str | PathLike[str] | None = None,
    camera: CameraCalibration | None = None,
) -> SizeMeasurement:
    """Measure an object's x, y, z size from a top image and a side image.

    See the module docstring for the geometry the images must follow.

    Args:
        top_image: path or BGR/grey uint8 array; the camera looks down at the table.
        side_image: path or array; the camera looks at the object's front face.
        marker_size_cm: side of the ArUco marker's black square, cm (required for markers).
        marker_dict: OpenCV predefined dictionary name, e.g. ``"DICT_4X4_50"``.
        marker_id: use only the marker with this id (others are ignored and masked out).
        checkerboard: ``(cols, rows)`` inner corners; use a checkerboard instead of a marker.
        square_size_cm: the checkerboard's square side, cm.
        color_range: ``(hsv_lower, hsv_upper)`` (OpenCV HSV, H in 0..179) selecting the object.
        background_image: the empty scene, one image or ``(top, side)``; the object is what
            differs from it.
        camera_matrix: 3x3 intrinsic matrix ``K`` (px), used for both views; default: 60-degree
            horizontal field of view, principal point at the centre.
        debug_dir: write annotated PNGs here (``top.png``, ``side.png``, masks, failures).
        camera: a calibrated camera (:func:`deformctl.vision.camera.load_camera_calibration`)
            instead of ``camera_matrix``: its ``K`` is used, and the photos (and backgrounds) are
            undistorted with its distortion coefficients first; photos of another size than
            the calibration's are refused.

    Returns:
        The sizes in cm and the per-view details.

    Raises:
        MissingInputError: an image path does not exist.
        InputDataError: unreadable image; no marker or several; no object; object on the border.
        UsageError: a bad option (unknown dictionary, missing marker size, bad camera matrix).
    """
    bg_top: ImageSource | None
    bg_side: ImageSource | None
    if isinstance(background_image, tuple):
        bg_top, bg_side = background_image
    else:
        bg_top = bg_side = background_image
    if camera is not None and camera_matrix is not None:
        raise UsageError("give camera or camera_matrix, not both")
    k = camera.camera_matrix if camera is not None else _camera_matrix(camera_matrix)
    debug = None if debug_dir is None else _Debug(debug_dir)
    common = {
        "marker_size_cm": marker_size_cm,
        "marker_dict": marker_dict,
        "marker_id": marker_id,
        "checkerboard": checkerboard,
        "square_size_cm": square_size_cm,
        "color_range": color_range,
        "camera_matrix": k,
        "debug": debug,
    }
    top_img = load_image(top_image, name="top image")
    side_img = load_image(side_image, name="side image")
    top_bg = _load_background(bg_top, top_img, "top")
    side_bg = _load_background(bg_side, side_img, "side")
    if camera is not None:
        camera.check_image(top_img.shape, "top image", _label(top_image, "top"))
        camera.check_image(side_img.shape, "side image", _label(side_image, "side"))
        top_img, side_img = undistort(top_img, camera), undistort(side_img, camera)
        top_bg = None if top_bg is None else undistort(top_bg, camera)
        side_bg = None if side_bg is None else undistort(side_bg, camera)
    top_sil = _silhouette(
        top_img,
        view="top",
        path=_label(top_image, "top"),
        background=top_bg,
        **common,  # type: ignore[arg-type]
    )
    side_sil = _silhouette(
        side_img,
        view="side",
        path=_label(side_image, "side"),
        background=side_bg,
        **common,  # type: ignore[arg-type]
    )
    # Fixed point: the top view needs the height, the side view the depth (the top-view side
    # that does not match the side view's visible width).
    height, depth = 0.0, 0.0
    top = flat = _view_from("top", top_sil, top_img.shape, 0.0, 0.0)
    side = _view_from("side", side_sil, side_img.shape, 0.0, 0.0)
    for _ in range(_VIEW_ITERATIONS):
        side = _view_from("side", side_sil, side_img.shape, 0.0, -depth)
        height = side.size_along_y_cm
        top = _view_from("top", top_sil, top_img.shape, height, 0.0)
        width = side.size_along_x_cm
        x, y = top.size_along_x_cm, top.size_along_y_cm
        depth = y if abs(width - x) <= abs(width - y) else x
    result = SizeMeasurement(
        size_x_cm=top.size_along_x_cm,
        size_y_cm=top.size_along_y_cm,
        size_z_cm=side.size_along_y_cm,
        top=top,
        side=side,
        height_correction_pct=100.0
        * (
            (top.size_along_x_cm + top.size_along_y_cm)
            / (flat.size_along_x_cm + flat.size_along_y_cm)
            - 1.0
        ),
        assumed_hfov_deg=DEFAULT_HFOV_DEG if k is None else None,
    )
    if debug is not None:
        debug.write_view(top, top_img, f"x {result.size_x_cm:.2f} cm, y {result.size_y_cm:.2f} cm")
        debug.write_view(side, side_img, f"z {result.size_z_cm:.2f} cm")
    return result


def catalog_row(
    size: SizeMeasurement,
    *,
    object_id: str,
    weight_n: float,
    friction_mu: float | None = None,
) -> dict[str, object]:
    """An object-catalog row from a size measurement (sizes rounded to 0.01 cm).

    Returns:
        ``{"object_id", "size_x_cm", "size_y_cm", "size_z_cm", "weight_n"}`` plus
        ``"friction_mu"`` when given (see :func:`deformctl.catalog.catalog_row`).
    """
    return new_catalog_row(
        object_id, (size.size_x_cm, size.size_y_cm, size.size_z_cm), weight_n, friction_mu
    )
