"""Object size from a top and a side image, and slip from frames before and after a lift (OpenCV).

Two jobs, both on ordinary camera images:

* :func:`measure_object_size` measures an object's x, y, z size in cm from a *top* image and a
  *side* image that each contain a scale reference of known size (an ArUco marker by default, or a
  checkerboard). :func:`catalog_row` turns the result into an object-catalog row.
* :func:`detect_slip` decides from a frame before and a frame after a lift whether the object rose
  with the palms; :func:`slip_from_frames` is the ``(before_path, after_path) -> (lifted, slip_m)``
  callable the external rig runner of ``lift`` accepts.

Geometry the user must set up (the measurement is exact for boxes and right prisms under it)
-------------------------------------------------------------------------------------------
*Reference plane.* The marker (or checkerboard) defines a metric plane: its homography maps image
pixels to plane coordinates in cm, with the marker's own axes: ``x`` along the marker's printed top
edge (left to right), ``y`` along its left edge (top to bottom of the print).

*Top view.* The marker lies flat on the table beside the object (not touching it); the camera looks
down, roughly perpendicular to the table (tilts up to ~15 degrees are corrected). ``size_x_cm`` is
the side of the object's minimum-area rectangle that is more nearly parallel to the marker's x
axis, ``size_y_cm`` the other side; so orient the marker's top edge along the squeeze axis.

*Side view.* The marker stands upright (printed top edge up) in the plane of the object's front
face, beside the object, e.g. taped to a block flush with that face; the camera looks horizontally,
roughly perpendicular to that face, best from about the object's mid-height. ``size_z_cm`` is the
side of the minimum-area rectangle more nearly parallel to the marker's y axis (the vertical).

*Parallax.* The object is not flat: its top face (top view) is nearer to the camera than the
marker plane, and its back (side view) is farther. The silhouette mapped into the marker plane is
therefore the object's "shadow" cast from the camera centre, not its cross-section. We undo this
exactly for a right prism: the camera centre ``C`` (in the marker frame, from ``cv2.solvePnP`` with
the camera matrix) and the prism's extent along the plane normal (top view: from the table up to
``size_z``; side view: from the front face back by the object's depth) give, for every direction,
the cross-section's support value from the silhouette's (see :func:`_section_support`). The two
views depend on each other (the top needs the height, the side needs the depth), so they are
solved by a short fixed-point iteration. Pass the calibrated ``camera_matrix`` (from
``cv2.calibrateCamera``) for best accuracy; without it a pinhole camera with a 60-degree
horizontal field of view and the principal point at the image centre is assumed, which only
affects the (small) parallax correction, not the in-plane scale. Lens distortion is not modelled:
undistort images first if the lens has visible distortion.

*Segmentation.* The object is the largest foreground region that is not the marker: by default
the difference from a smooth background (a quadratic surface per colour channel fitted robustly
to the image, which absorbs uneven lighting) thresholded with Otsu's method; or a colour range
(HSV lower/upper); or the difference from an image of the empty scene. Use a uniform background
that differs from the object and keep the whole object inside the image.

Slip from frames
----------------
A fixed camera looks at the gripper from the side. The palms are tracked by template matching of
given regions (``x, y, w, h`` in the before frame, each containing a distinctive part of a palm
such as its lower end) or by ArUco markers on the palms; the object is the foreground between the
palms. Rises are measured upwards in the image (``-dy``) and converted to metres with the scale of
the markers in view (``marker_size_cm``) or an explicit ``scale_px_per_m``; all of them must lie
roughly in one plane perpendicular to the camera.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from deformctl.errors import InputDataError, MissingInputError, UsageError
from deformctl.units import CM

__all__ = [
    "ImageSource",
    "SizeMeasurement",
    "SlipResult",
    "ViewMeasurement",
    "catalog_row",
    "detect_slip",
    "load_image",
    "measure_object_size",
    "measure_view",
    "slip_from_frames",
]

ImageSource = str | PathLike[str] | NDArray[np.uint8]
FloatArray = NDArray[np.float64]
ViewName = Literal["top", "side"]

#: Marker quad grown by this factor (about its centre, in the marker plane) before it is removed
#: from the foreground; covers a white margin of up to 15 % of the marker side on each side.
MARKER_MASK_GROWTH = 1.3
#: Default horizontal field of view assumed when no camera matrix is given, degrees.
DEFAULT_HFOV_DEG = 60.0
#: Fixed-point iterations coupling the top view (needs the height) and the side view (the depth).
_VIEW_ITERATIONS = 4


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
# Segmentation
# --------------------------------------------------------------------------------------------


def _quadratic_terms(u: FloatArray, v: FloatArray) -> list[FloatArray]:
    return [np.ones_like(u + v), u, v, u * u, u * v, v * v]


def _background_model(img: NDArray[np.uint8], exclude: NDArray[np.bool_]) -> FloatArray:
    """A smooth background, a quadratic surface per channel fitted robustly; float ``[h, w, 3]``.

    Fitted on a coarse grid by iteratively trimmed least squares (pixels more than three robust
    standard deviations from the surface, i.e. the object and the marker, are dropped).
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
    for _ in range(5):
        a = design[keep]
        coef = _f64(np.linalg.solve(a.T @ a + 1e-9 * np.eye(6), a.T @ vals[keep]))  # [6, 3]
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

    def write_view(self, view: ViewMeasurement, img: NDArray[np.uint8], text: str) -> None:
        out = img.copy()
        cv2.polylines(out, [np.round(view.reference_outline_px).astype(np.int32)], True,
                      (255, 0, 0), 2)  # fmt: skip
        cv2.drawContours(out, [np.round(view.contour_px).astype(np.int32)], -1, (0, 255, 0), 1)
        h_plane_to_img = _f64(np.linalg.inv(view.homography_img_to_plane))
        rect_px = _apply_h(h_plane_to_img, view.rect_corners_cm)
        cv2.polylines(out, [np.round(rect_px).astype(np.int32)], True, (0, 0, 255), 1)
        cv2.putText(out, text, (10, 25), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 255), 2)
        self._write(f"{view.view}.png", out)


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
    """

    size_x_cm: float
    size_y_cm: float
    size_z_cm: float
    top: ViewMeasurement
    side: ViewMeasurement


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
    k = _camera_matrix(camera_matrix)
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
    top_sil = _silhouette(
        top_img,
        view="top",
        path=_label(top_image, "top"),
        background=_load_background(bg_top, top_img, "top"),
        **common,  # type: ignore[arg-type]
    )
    side_sil = _silhouette(
        side_img,
        view="side",
        path=_label(side_image, "side"),
        background=_load_background(bg_side, side_img, "side"),
        **common,  # type: ignore[arg-type]
    )
    # Fixed point: the top view needs the height, the side view the depth (the top-view side
    # that does not match the side view's visible width).
    height, depth = 0.0, 0.0
    top = _view_from("top", top_sil, top_img.shape, 0.0, 0.0)
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
        ``"friction_mu"`` when given.
    """
    if not object_id:
        raise UsageError("object_id must not be empty")
    if not (math.isfinite(weight_n) and weight_n > 0):
        raise UsageError(f"weight_n must be a positive number of newtons, got {weight_n}")
    row: dict[str, object] = {
        "object_id": object_id,
        "size_x_cm": round(size.size_x_cm, 2),
        "size_y_cm": round(size.size_y_cm, 2),
        "size_z_cm": round(size.size_z_cm, 2),
        "weight_n": float(weight_n),
    }
    if friction_mu is not None:
        if not (math.isfinite(friction_mu) and friction_mu > 0):
            raise UsageError(f"friction_mu must be positive, got {friction_mu}")
        row["friction_mu"] = float(friction_mu)
    return row


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
