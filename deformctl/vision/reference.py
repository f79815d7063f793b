"""Images and scale references: loading, ArUco markers and checkerboards, plane geometry.

A scale reference of known size (an ArUco marker, or a checkerboard) defines a metric plane: its
homography maps image pixels to plane coordinates in cm, with the marker's own axes (``x`` along
its printed top edge, ``y`` along its left edge). :func:`load_image` reads a photo; the rest is
shared by :mod:`deformctl.vision.size` and :mod:`deformctl.vision.slip` (see
:mod:`deformctl.vision` for the set-up the measurements assume).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Literal, Protocol

import cv2
import numpy as np
from numpy.typing import NDArray

from deformctl.arraytypes import FloatArray
from deformctl.errors import InputDataError, MissingInputError, UsageError

ImageSource = str | PathLike[str] | NDArray[np.uint8]
ViewName = Literal["top", "side"]


class MeasuredView(Protocol):
    """What the debug drawing needs of a :class:`~deformctl.vision.size.ViewMeasurement`."""

    @property
    def view(self) -> str:
        """``top`` or ``side``."""

    @property
    def reference_outline_px(self) -> FloatArray:
        """The scale reference's outline, px."""

    @property
    def contour_px(self) -> FloatArray:
        """The object's contour, px."""

    @property
    def homography_img_to_plane(self) -> FloatArray:
        """Image to reference plane (cm)."""

    @property
    def rect_corners_cm(self) -> FloatArray:
        """The measured rectangle in the reference plane, cm."""


#: Marker quad grown by this factor (about its centre, in the marker plane) before it is removed
#: from the foreground; covers a white margin of up to 15 % of the marker side on each side.
MARKER_MASK_GROWTH = 1.3
#: Default horizontal field of view assumed when no camera matrix is given, degrees.
DEFAULT_HFOV_DEG = 60.0


# --------------------------------------------------------------------------------------------
# Image loading
# --------------------------------------------------------------------------------------------


def _label(source: ImageSource, name: str) -> str | None:
    return None if isinstance(source, np.ndarray) else str(source)


def _u8(arr: object) -> NDArray[np.uint8]:
    return np.asarray(arr, dtype=np.uint8)


def _f64(arr: object) -> FloatArray:
    return np.asarray(arr, dtype=np.float64)


def _gray(img: NDArray[np.uint8]) -> NDArray[np.uint8]:
    return _u8(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY))


def load_image(source: ImageSource, *, name: str = "image") -> NDArray[np.uint8]:
    """Load an image as 8-bit BGR.

    Args:
        source: a path to an image file, or an array ``[h, w]`` (grey) or ``[h, w, 3]`` (BGR),
            dtype uint8.
        name: what the image is (used in error messages), e.g. ``"top image"``.

    Returns:
        The image, uint8 ``[h, w, 3]`` BGR.

    Raises:
        MissingInputError: the path does not exist.
        InputDataError: the file is not a readable image, or the array has the wrong shape/dtype.
    """
    if isinstance(source, np.ndarray):
        arr = source
        if arr.dtype != np.uint8:
            raise InputDataError(f"{name}: expected a uint8 array, got {arr.dtype}")
        if arr.ndim == 2:
            return np.ascontiguousarray(cv2.cvtColor(arr, cv2.COLOR_GRAY2BGR))
        if arr.ndim == 3 and arr.shape[2] == 3:
            return np.ascontiguousarray(arr)
        if arr.ndim == 3 and arr.shape[2] == 4:
            return np.ascontiguousarray(cv2.cvtColor(arr, cv2.COLOR_BGRA2BGR))
        raise InputDataError(f"{name}: expected an array [h, w] or [h, w, 3], got {arr.shape}")
    path = Path(source)
    if not path.exists():
        raise MissingInputError(f"{name} does not exist", path=path)
    if not path.is_file():
        raise InputDataError(f"{name} is not a file", path=path)
    data = np.fromfile(path, dtype=np.uint8)
    # A damaged file is reported by our one-line error, not by OpenCV's own warning on stderr.
    level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    try:
        img = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    finally:
        cv2.utils.logging.setLogLevel(level)
    if img is None:
        raise InputDataError(f"{name} is not a readable image file", path=path)
    return np.asarray(img, dtype=np.uint8)


# --------------------------------------------------------------------------------------------
# Scale references
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Reference:
    """A detected scale reference: image points and their plane coordinates (cm)."""

    kind: Literal["aruco", "checkerboard"]
    image_pts: FloatArray  # [n, 2] px
    plane_pts_cm: FloatArray  # [n, 2] cm
    outline_px: FloatArray  # [4, 2] px, the reference's outer quad (for masks and drawing)
    marker_id: int | None
    other_markers_px: tuple[FloatArray, ...]  # quads of ignored markers, [4, 2] each


def _aruco_dictionary(marker_dict: str) -> cv2.aruco.Dictionary:
    code = getattr(cv2.aruco, marker_dict, None) if marker_dict.startswith("DICT_") else None
    if not isinstance(code, int):
        raise UsageError(f"unknown ArUco dictionary {marker_dict!r} (e.g. DICT_4X4_50)")
    return cv2.aruco.getPredefinedDictionary(code)


def _detect_markers(
    gray: NDArray[np.uint8], marker_dict: str
) -> tuple[list[FloatArray], list[int], list[FloatArray]]:
    """All markers of a dictionary: (quads [4, 2] px, ids, rejected candidate quads)."""
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    detector = cv2.aruco.ArucoDetector(_aruco_dictionary(marker_dict), params)
    corners, ids, rejected = detector.detectMarkers(gray)
    quads = [np.asarray(c, dtype=np.float64).reshape(4, 2) for c in corners]
    id_list = [] if ids is None else [int(i) for i in np.asarray(ids).ravel()]
    rej = [np.asarray(c, dtype=np.float64).reshape(4, 2) for c in rejected]
    return quads, id_list, rej


def _refine_quad_edges(gray: NDArray[np.uint8], quad: FloatArray) -> FloatArray:
    """Refine a marker's corners by fitting its four dark-to-light edges.

    ``cornerSubPix`` on the outer corner of a dark square is biased inwards by a fraction of a
    pixel, which the homography amplifies when it extrapolates to an object several marker sizes
    away. Instead, along each edge (away from the corners) the half-contrast crossing of the
    intensity profile across the edge is found with sub-pixel interpolation, a line is fitted to
    the crossings, and adjacent lines are intersected.

    Args:
        gray: the image, uint8 ``[h, w]``.
        quad: corners in order, px ``[4, 2]``.

    Returns:
        Refined corners, px ``[4, 2]`` (the input when an edge cannot be fitted).
    """
    # A symmetric blur keeps a straight edge's half-contrast line in place and makes the profile
    # smooth enough for linear interpolation (a sharp edge sampled on the pixel grid is not).
    img = cv2.GaussianBlur(gray.astype(np.float32), (0, 0), 1.0)
    center = quad.mean(axis=0)
    steps = np.arange(-3.0, 3.0001, 0.25)  # across the edge, px (negative: inside)
    lines = []
    for i in range(4):
        a, b = quad[i], quad[(i + 1) % 4]
        length = float(np.hypot(*(b - a)))
        if length < 12:
            return quad
        t = (b - a) / length
        n = np.array([t[1], -t[0]])
        if np.dot(n, (a + b) / 2 - center) < 0:
            n = -n  # outward
        along = np.linspace(0.15, 0.85, max(8, int(length * 0.7)))
        base = a[None, :] + along[:, None] * (b - a)[None, :]  # [k, 2]
        pts = base[:, None, :] + steps[None, :, None] * n[None, None, :]  # [k, s, 2]
        prof = cv2.remap(
            img,
            pts[..., 0].astype(np.float32),
            pts[..., 1].astype(np.float32),
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )  # [k, s]
        dark = prof[:, :3].mean(axis=1, keepdims=True)
        light = prof[:, -3:].mean(axis=1, keepdims=True)
        contrast = (light - dark).ravel()
        level = (prof - dark) / np.where(np.abs(light - dark) < 1e-6, 1.0, light - dark)
        crossings = []
        for j in range(prof.shape[0]):
            if contrast[j] < 20:
                continue
            above = np.nonzero(level[j] >= 0.5)[0]
            if above.size == 0 or above[0] == 0:
                continue
            k = int(above[0])
            l0, l1 = float(level[j, k - 1]), float(level[j, k])
            frac = (0.5 - l0) / (l1 - l0) if l1 != l0 else 0.0
            off = steps[k - 1] + frac * (steps[k] - steps[k - 1])
            crossings.append(base[j] + off * n)
        if len(crossings) < 5:
            return quad
        c = np.asarray(crossings)
        mean = c.mean(axis=0)
        _, _, vt = np.linalg.svd(c - mean)
        direction = vt[0]
        normal = np.array([-direction[1], direction[0]])
        lines.append((normal, float(normal @ mean)))
    out = np.empty((4, 2))
    for i in range(4):
        (n1, d1), (n2, d2) = lines[(i - 1) % 4], lines[i]
        mat = np.array([n1, n2])
        if abs(np.linalg.det(mat)) < 1e-6:
            return quad
        out[i] = np.linalg.solve(mat, np.array([d1, d2]))
    if np.max(np.hypot(*(out - quad).T)) > 2.0:
        return quad  # refinement disagrees with the detector: keep the detector's corners
    return out


def _find_reference(
    img: NDArray[np.uint8],
    *,
    view: str,
    path: str | None,
    marker_size_cm: float | None,
    marker_dict: str,
    marker_id: int | None,
    checkerboard: tuple[int, int] | None,
    square_size_cm: float | None,
    debug: _Debug | None,
) -> _Reference:
    gray = _gray(img)
    if checkerboard is not None:
        return _find_checkerboard(gray, view, path, checkerboard, square_size_cm, debug)
    if marker_size_cm is None or not marker_size_cm > 0:
        raise UsageError("marker_size_cm must be a positive number of cm")
    quads, ids, rejected = _detect_markers(gray, marker_dict)
    if marker_id is not None:
        chosen = [i for i, mid in enumerate(ids) if mid == marker_id]
    else:
        chosen = list(range(len(ids)))
    if not chosen:
        if debug is not None:
            debug.write_failure(view, img, rejected, quads)
        which = f"with id {marker_id} " if marker_id is not None else ""
        found = f" (found ids {sorted(ids)})" if ids else ""
        raise InputDataError(
            f"no ArUco marker {which}({marker_dict}) found in the {view} image{found}; "
            "check the marker dictionary, lighting and focus, or rerun with --debug-dir DIR "
            "to see the detection",
            path=path,
        )
    if len(chosen) > 1:
        listed = ", ".join(str(i) for i in sorted(ids[i] for i in chosen))
        raise InputDataError(
            f"found {len(chosen)} ArUco markers (ids {listed}) in the {view} image; the scale "
            "reference is ambiguous: show exactly one marker or choose one with --marker-id",
            path=path,
        )
    quad = _refine_quad_edges(gray, quads[chosen[0]])
    s = float(marker_size_cm)
    plane = np.array([[0.0, 0.0], [s, 0.0], [s, s], [0.0, s]])
    others = tuple(q for i, q in enumerate(quads) if i != chosen[0])
    return _Reference("aruco", quad, plane, quad, ids[chosen[0]], others)


def _find_checkerboard(
    gray: NDArray[np.uint8],
    view: str,
    path: str | None,
    pattern: tuple[int, int],
    square_size_cm: float | None,
    debug: _Debug | None,
) -> _Reference:
    cols, rows = int(pattern[0]), int(pattern[1])
    if cols < 2 or rows < 2:
        raise UsageError("checkerboard needs at least 2x2 inner corners (COLSxROWS)")
    if square_size_cm is None or not square_size_cm > 0:
        raise UsageError("a checkerboard needs square_size_cm > 0")
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(gray, (cols, rows), flags=flags)
    if not found:
        if debug is not None:
            debug.write_failure(view, _u8(cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)), [], [])
        raise InputDataError(
            f"no {cols}x{rows} checkerboard found in the {view} image; check COLSxROWS (inner "
            "corners) or rerun with --debug-dir DIR to see the image",
            path=path,
        )
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-3)
    corners = cv2.cornerSubPix(gray, corners, (5, 5), (-1, -1), criteria)
    pts = np.asarray(corners, dtype=np.float64).reshape(-1, 2)
    s = float(square_size_cm)
    gx, gy = np.meshgrid(np.arange(cols, dtype=np.float64), np.arange(rows, dtype=np.float64))
    plane = np.column_stack([gx.ravel(), gy.ravel()]) * s
    # The outer quad of the printed board: the inner-corner grid grown by one square.
    h_plane_to_img = _f64(cv2.findHomography(plane, pts)[0])
    outer = np.array([[-s, -s], [cols * s, -s], [cols * s, rows * s], [-s, rows * s]])
    outline = _apply_h(h_plane_to_img, outer)
    return _Reference("checkerboard", pts, plane, outline, None, ())


# --------------------------------------------------------------------------------------------
# Geometry helpers
# --------------------------------------------------------------------------------------------


def _apply_h(h: FloatArray, pts: FloatArray) -> FloatArray:
    """Apply a 3x3 homography to points ``[n, 2]``."""
    p = np.asarray(pts, dtype=np.float64).reshape(-1, 1, 2)
    return np.asarray(cv2.perspectiveTransform(p, h), dtype=np.float64).reshape(-1, 2)


def _default_camera_matrix(shape: tuple[int, ...]) -> FloatArray:
    h, w = shape[:2]
    f = (w / 2.0) / math.tan(math.radians(DEFAULT_HFOV_DEG) / 2.0)
    return np.array([[f, 0.0, (w - 1) / 2.0], [0.0, f, (h - 1) / 2.0], [0.0, 0.0, 1.0]])


def _camera_center(ref: _Reference, k: FloatArray) -> FloatArray:
    """Camera centre in the reference frame, cm ``[3]`` (its z < 0: the camera faces the print)."""
    obj = np.column_stack([ref.plane_pts_cm, np.zeros(len(ref.plane_pts_cm))])
    ok, rvec, tvec = cv2.solvePnP(
        obj, ref.image_pts.reshape(-1, 1, 2), k, None, flags=cv2.SOLVEPNP_IPPE
    )
    if not ok:  # pragma: no cover - IPPE succeeds on any non-degenerate planar quad
        raise InputDataError("could not estimate the camera pose from the scale reference")
    rot, _ = cv2.Rodrigues(rvec)
    center = -rot.T @ np.asarray(tvec, dtype=np.float64).ravel()
    if center[2] > 0:  # seen from behind: mirror (cannot happen for a detected print)
        center[2] = -center[2]
    return np.asarray(center, dtype=np.float64)


def _section_support(
    points_cm: FloatArray,
    center_cm: FloatArray,
    near_cm: float,
    far_cm: float,
    theta: FloatArray,
) -> FloatArray:
    """Support function of a right prism's cross-section from its silhouette in the plane.

    The prism spans offsets ``e`` in ``[far_cm, near_cm]`` along the plane normal, positive
    towards the camera (top view: ``[0, height]``; side view: ``[-depth, 0]``). A point at offset
    ``e`` projects from the camera centre ``C`` (distance ``D`` in front of the plane) to
    ``C_p + (p - C_p) * D / (D - e)``, so the silhouette is the union of the cross-section scaled
    about ``C_p`` by every factor in ``[D/(D - far), D/(D - near)]``. For a direction ``n`` with
    ``c = C_p . n`` its support value is ``c + (h - c) * f`` with ``f = D/(D - near)`` when the
    cross-section's support value ``h >= c`` and ``f = D/(D - far)`` otherwise (the factor
    preserves the sign of ``h - c``), which inverts direction by direction.

    Args:
        points_cm: silhouette points in the plane, cm ``[n, 2]``.
        center_cm: camera centre in the plane frame, cm ``[3]`` (z < 0 towards the camera).
        near_cm: the prism's offset nearest to the camera, cm.
        far_cm: the prism's offset farthest from the camera, cm (``far_cm <= near_cm``).
        theta: directions, rad ``[m]``.

    Returns:
        The cross-section's support values ``max_p n(theta) . p``, cm ``[m]``.
    """
    dist = -float(center_cm[2])
    if dist <= near_cm:
        raise InputDataError("the camera is inside the object's extent; move the camera away")
    normals = np.column_stack([np.cos(theta), np.sin(theta)])  # [m, 2]
    support = (points_cm @ normals.T).max(axis=0)  # [m]
    c = normals @ center_cm[:2]
    f_near = dist / (dist - near_cm)
    f_far = dist / (dist - far_cm)
    scale = np.where(support >= c, 1.0 / f_near, 1.0 / f_far)
    return np.asarray(c + (support - c) * scale, dtype=np.float64)


def _section_rect(
    points_cm: FloatArray, center_cm: FloatArray, near_cm: float, far_cm: float
) -> tuple[FloatArray, FloatArray]:
    """Minimum-area rectangle and polygon of a prism's cross-section (see :func:`_section_support`).

    The rectangle's orientation minimises ``width(t) * width(t + 90 deg)`` (widths from the
    support function), on a 0.25-degree grid refined to 0.005 degrees.

    Returns:
        ``(rect_corners_cm [4, 2], section_polygon_cm [k, 2])``.
    """

    def area(t: FloatArray) -> tuple[FloatArray, FloatArray]:
        quarter = np.concatenate([t, t + np.pi / 2, t + np.pi, t + 1.5 * np.pi])
        s = _section_support(points_cm, center_cm, near_cm, far_cm, quarter).reshape(4, -1)
        return (s[0] + s[2]) * (s[1] + s[3]), s

    coarse = np.arange(0.0, np.pi / 2, np.radians(0.25))
    a, _ = area(coarse)
    best = coarse[int(np.argmin(a))]
    fine = best + np.radians(np.arange(-0.25, 0.25, 0.005))
    a, s = area(fine)
    i = int(np.argmin(a))
    t = float(fine[i])
    s0, s1, s2, s3 = (float(v) for v in s[:, i])
    u = np.array([math.cos(t), math.sin(t)])
    v = np.array([-math.sin(t), math.cos(t)])
    corners = np.array(
        [s0 * u + s1 * v, -s2 * u + s1 * v, -s2 * u - s3 * v, s0 * u - s3 * v], dtype=np.float64
    )
    return corners, _section_polygon(points_cm, center_cm, near_cm, far_cm)


def _section_polygon(
    points_cm: FloatArray, center_cm: FloatArray, near_cm: float, far_cm: float
) -> FloatArray:
    """The cross-section as a polygon (for display): consecutive support lines every 2 degrees.

    Returns:
        Polygon vertices, cm ``[180, 2]``.
    """
    theta = np.radians(np.arange(0.0, 360.0, 2.0))
    h1 = _section_support(points_cm, center_cm, near_cm, far_cm, theta)
    n1 = np.column_stack([np.cos(theta), np.sin(theta)])
    n2, h2 = np.roll(n1, -1, axis=0), np.roll(h1, -1)
    det = n1[:, 0] * n2[:, 1] - n1[:, 1] * n2[:, 0]
    x = (h1 * n2[:, 1] - h2 * n1[:, 1]) / det
    y = (n1[:, 0] * h2 - n2[:, 0] * h1) / det
    return np.column_stack([x, y])


def _rect_along_axes(corners: FloatArray) -> tuple[float, float, float]:
    """Sides of a rectangle assigned to the reference axes.

    Args:
        corners: the rectangle's corners in order, cm ``[4, 2]``.

    Returns:
        ``(size_along_x_cm, size_along_y_cm, angle_deg)``: the side more nearly parallel to the
        reference x axis first; ``angle_deg`` in ``(-45, 45]`` is that side's angle from x.
    """
    e1 = corners[1] - corners[0]
    e2 = corners[2] - corners[1]
    l1, l2 = float(np.hypot(*e1)), float(np.hypot(*e2))
    if abs(e1[0]) * l2 >= abs(e2[0]) * l1:  # e1 has the larger |cos| to the x axis
        along_x, along_y, ex = l1, l2, e1
    else:
        along_x, along_y, ex = l2, l1, e2
    angle = math.degrees(math.atan2(ex[1], ex[0]))
    angle = (angle + 90.0) % 180.0 - 90.0
    if angle <= -45.0:
        angle += 90.0
    return along_x, along_y, angle


# --------------------------------------------------------------------------------------------
# Debug output
# --------------------------------------------------------------------------------------------


class _Debug:
    """Writes annotated PNGs into a directory (created on first use)."""

    def __init__(self, directory: str | PathLike[str]) -> None:
        self.directory = Path(directory)

    def _write(self, name: str, img: NDArray[np.uint8]) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        ok, buf = cv2.imencode(".png", img)
        if ok:
            (self.directory / name).write_bytes(buf.tobytes())

    def write_failure(
        self,
        view: str,
        img: NDArray[np.uint8],
        rejected: Sequence[FloatArray],
        markers: Sequence[FloatArray],
    ) -> None:
        out = img.copy()
        for q in rejected:
            cv2.polylines(out, [np.round(q).astype(np.int32)], True, (0, 0, 255), 1)
        for q in markers:
            cv2.polylines(out, [np.round(q).astype(np.int32)], True, (255, 0, 0), 2)
        cv2.putText(out, "no scale reference found (red: rejected candidates)", (10, 25),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 255), 2)  # fmt: skip
        self._write(f"{view}_failed.png", out)

    def write_mask(self, name: str, mask: NDArray[np.uint8]) -> None:
        self._write(name, mask)

    def write_view(self, view: MeasuredView, img: NDArray[np.uint8], text: str) -> None:
        out = img.copy()
        cv2.polylines(
            out, [np.round(view.reference_outline_px).astype(np.int32)], True, (255, 0, 0), 2
        )
        cv2.drawContours(out, [np.round(view.contour_px).astype(np.int32)], -1, (0, 255, 0), 1)
        h_plane_to_img = _f64(np.linalg.inv(view.homography_img_to_plane))
        rect_px = _apply_h(h_plane_to_img, view.rect_corners_cm)
        cv2.polylines(out, [np.round(rect_px).astype(np.int32)], True, (0, 0, 255), 1)
        cv2.putText(out, text, (10, 25), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 255), 2)
        self._write(f"{view.view}.png", out)
