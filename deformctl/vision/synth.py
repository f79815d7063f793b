"""Synthetic camera images with known geometry, for testing and trying :mod:`deformctl.vision`.

A small pinhole renderer: a table, printed ArUco markers or checkerboards, and boxes. World
frame: X right, Y forward (away from a side camera), Z up; the table is ``Z = 0``; lengths in cm.
The table and the backdrop share one colour (a seamless photo backdrop), so only the objects and
markers are drawn; uneven lighting is a multiplicative gradient over the image and sensor noise is
Gaussian. Faces are drawn with a painter's algorithm on a supersampled canvas that is then
area-averaged, which gives antialiased edges.

Two ready-made set-ups follow the conventions :mod:`deformctl.vision` documents:
:func:`box_views` (a top and a side image of a box with a marker beside it, for
``measure --images``) and :func:`gripper_frame` (a side view of a box between two palms, for
slip from frames). ``examples/render_scene.py`` writes both to files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from deformctl.arraytypes import FloatArray


@dataclass(frozen=True)
class Camera:
    """Pinhole camera: intrinsics ``k`` (px), rotation world->camera, centre in world (cm)."""

    k: FloatArray
    rot: FloatArray
    center: FloatArray
    width: int
    height: int

    @staticmethod
    def look_at(
        center: tuple[float, float, float],
        target: tuple[float, float, float],
        up: tuple[float, float, float],
        *,
        focal_px: float = 900.0,
        width: int = 960,
        height: int = 720,
    ) -> Camera:
        c = np.asarray(center, dtype=np.float64)
        z = np.asarray(target, dtype=np.float64) - c
        z /= np.linalg.norm(z)
        x = np.cross(z, np.asarray(up, dtype=np.float64))
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        k = np.array(
            [[focal_px, 0.0, (width - 1) / 2], [0.0, focal_px, (height - 1) / 2], [0, 0, 1.0]]
        )
        return Camera(k, np.vstack([x, y, z]), c, width, height)

    def project(self, pts: FloatArray, ss: int = 1) -> FloatArray:
        """World points ``[n, 3]`` to pixel coordinates ``[n, 2]`` of a canvas supersampled ss x."""
        cam = (np.asarray(pts, dtype=np.float64) - self.center) @ self.rot.T
        if np.any(cam[:, 2] <= 1e-6):
            raise ValueError("point behind the camera")
        uv = cam[:, :2] / cam[:, 2:3]
        px = uv * np.array([self.k[0, 0], self.k[1, 1]]) + self.k[:2, 2]
        return (px + 0.5) * ss - 0.5

    def depth(self, pts: FloatArray) -> FloatArray:
        return ((np.asarray(pts, dtype=np.float64) - self.center) @ self.rot.T)[:, 2]


@dataclass(frozen=True)
class Box:
    """An axis-aligned box (optionally turned by ``yaw_deg`` about Z), lower face at ``z0``."""

    center_xy: tuple[float, float]
    size: tuple[float, float, float]
    color_bgr: tuple[int, int, int]
    yaw_deg: float = 0.0
    z0: float = 0.0

    def faces(self) -> list[tuple[FloatArray, FloatArray]]:
        """Six faces as (corners [4, 3], outward normal [3])."""
        sx, sy, sz = (s / 2 for s in self.size)
        a = math.radians(self.yaw_deg)
        rot = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
        off = np.array([self.center_xy[0], self.center_xy[1], self.z0 + sz])
        out = []
        for axis in range(3):
            for sign in (-1.0, 1.0):
                n = np.zeros(3)
                n[axis] = sign
                u, v = [i for i in range(3) if i != axis]
                half = np.array([sx, sy, sz])
                quad = []
                for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                    p = n * half
                    p[u] = du * half[u]
                    p[v] = dv * half[v]
                    quad.append(p)
                out.append((np.array(quad) @ rot.T + off, rot @ n))
        return out


@dataclass(frozen=True)
class Marker:
    """A printed ArUco marker on a white card; ``corners`` are the black square's TL, TR, BR, BL."""

    corners: FloatArray  # [4, 3] world, cm
    marker_id: int = 0
    margin: float = 0.1  # white margin on each side, fraction of the marker side
    dictionary: int = cv2.aruco.DICT_4X4_50

    @staticmethod
    def flat(x0: float, y0: float, side: float, **kw: object) -> Marker:
        """Lying on the table, printed top edge towards +Y; TL corner at ``(x0, y0 + side)``."""
        c = np.array(
            [[x0, y0 + side, 0], [x0 + side, y0 + side, 0], [x0 + side, y0, 0], [x0, y0, 0]],
            dtype=np.float64,
        )
        return Marker(c, **kw)  # type: ignore[arg-type]

    @staticmethod
    def upright(x0: float, y: float, z0: float, side: float, **kw: object) -> Marker:
        """Standing in the plane ``Y = y`` facing -Y, printed top edge up, lower edge at ``z0``."""
        c = np.array(
            [[x0, y, z0 + side], [x0 + side, y, z0 + side], [x0 + side, y, z0], [x0, y, z0]],
            dtype=np.float64,
        )
        return Marker(c, **kw)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Checkerboard:
    """A printed checkerboard of ``(cols + 1) x (rows + 1)`` squares with a one-square white margin.

    ``corners`` are the squares' outer corners TL, TR, BR, BL in the world, cm ``[4, 3]``.
    """

    corners: FloatArray
    cols: int
    rows: int

    @staticmethod
    def flat(x0: float, y0: float, cols: int, rows: int, square: float) -> Checkerboard:
        w, h = (cols + 1) * square, (rows + 1) * square
        c = np.array([[x0, y0 + h, 0], [x0 + w, y0 + h, 0], [x0 + w, y0, 0], [x0, y0, 0]], float)
        return Checkerboard(c, cols, rows)

    @staticmethod
    def upright(
        x0: float, y: float, z0: float, cols: int, rows: int, square: float
    ) -> Checkerboard:
        w, h = (cols + 1) * square, (rows + 1) * square
        c = np.array([[x0, y, z0 + h], [x0 + w, y, z0 + h], [x0 + w, y, z0], [x0, y, z0]], float)
        return Checkerboard(c, cols, rows)


@dataclass
class Scene:
    boxes: list[Box] = field(default_factory=list)
    markers: list[Marker | Checkerboard] = field(default_factory=list)
    background_bgr: tuple[int, int, int] = (190, 195, 200)
    light_dir: tuple[float, float, float] = (0.3, -0.5, 0.8)


def render(
    scene: Scene,
    cam: Camera,
    *,
    noise_sigma: float = 3.0,
    gradient: tuple[float, float] = (0.8, 1.1),
    gradient_angle_deg: float = 30.0,
    seed: int = 0,
    ss: int = 3,
) -> NDArray[np.uint8]:
    """Render a scene to an 8-bit BGR image ``[h, w, 3]``."""
    w, h = cam.width * ss, cam.height * ss
    canvas = np.empty((h, w, 3), dtype=np.float32)
    canvas[:] = scene.background_bgr
    light = np.asarray(scene.light_dir, dtype=np.float64)
    light /= np.linalg.norm(light)

    items: list[tuple[float, str, object]] = []
    for m in scene.markers:
        items.append((float(cam.depth(m.corners).mean()), "marker", m))
    for b in scene.boxes:
        for quad, normal in b.faces():
            centre = quad.mean(axis=0)
            if float(np.dot(normal, cam.center - centre)) <= 1e-9:
                continue  # back face
            shade = 0.55 + 0.45 * max(0.0, float(np.dot(normal, light)))
            color = tuple(float(c) * shade for c in b.color_bgr)
            items.append((float(cam.depth(centre[None])[0]), "face", (quad, color)))
    items.sort(key=lambda it: -it[0])  # far to near
    for _, kind, item in items:
        if kind == "face":
            quad, color = item  # type: ignore[misc]
            _fill_convex(canvas, cam.project(quad, ss), color)
        else:
            _draw_marker(canvas, item, cam, ss)  # type: ignore[arg-type]

    img = np.asarray(
        cv2.resize(canvas, (cam.width, cam.height), interpolation=cv2.INTER_AREA), np.float32
    )
    yy, xx = np.mgrid[0 : cam.height, 0 : cam.width].astype(np.float32)
    a = math.radians(gradient_angle_deg)
    t = xx / cam.width * math.cos(a) + yy / cam.height * math.sin(a)
    t = (t - t.min()) / (t.max() - t.min())
    img *= (gradient[0] + (gradient[1] - gradient[0]) * t)[..., None]
    rng = np.random.default_rng(seed)
    img += noise_sigma * rng.standard_normal(img.shape, dtype=np.float32)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def _fill_convex(canvas: NDArray[np.float32], pts: FloatArray, color: tuple[float, ...]) -> None:
    """Fill a convex polygon: every (sub)pixel whose centre lies inside it (no edge bias)."""
    h, w = canvas.shape[:2]
    x0, y0 = (max(0, int(np.floor(v))) for v in pts.min(axis=0))
    x1, y1 = (int(np.ceil(v)) + 1 for v in pts.max(axis=0))
    x1, y1 = min(w, x1), min(h, y1)
    if x0 >= x1 or y0 >= y1:
        return
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    area2 = float(np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1]))
    sign = 1.0 if area2 > 0 else -1.0
    inside = np.ones(xx.shape, dtype=bool)
    for i in range(len(pts)):
        (ax, ay), (bx, by) = pts[i], pts[(i + 1) % len(pts)]
        inside &= sign * ((bx - ax) * (yy - ay) - (by - ay) * (xx - ax)) >= 0
    canvas[y0:y1, x0:x1][inside] = color


def _card_texture(m: Marker | Checkerboard) -> tuple[NDArray[np.uint8], FloatArray]:
    """The card's texture and its world corners (the printed pattern plus the white margin)."""
    c = m.corners
    ex, ey = (c[1] - c[0]), (c[3] - c[0])
    if isinstance(m, Marker):
        side_px = 240
        dictionary = cv2.aruco.getPredefinedDictionary(m.dictionary)
        tex = cv2.aruco.generateImageMarker(dictionary, m.marker_id, side_px)
        pad = round(m.margin * side_px)
        fx = fy = m.margin
    else:
        sq = 40
        nx, ny = m.cols + 1, m.rows + 1
        iy, ix = np.mgrid[0 : ny * sq, 0 : nx * sq] // sq
        tex = np.where((ix + iy) % 2 == 0, 0, 255).astype(np.uint8)
        pad = sq
        fx, fy = 1.0 / nx, 1.0 / ny
    bordered: NDArray[np.uint8] = np.asarray(
        cv2.copyMakeBorder(tex, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=255), np.uint8
    )
    card = np.array(
        [
            c[0] - fx * ex - fy * ey,
            c[1] + fx * ex - fy * ey,
            c[2] + fx * ex + fy * ey,
            c[3] - fx * ex + fy * ey,
        ],
        dtype=np.float64,
    )
    return bordered, card


def _draw_marker(
    canvas: NDArray[np.float32], m: Marker | Checkerboard, cam: Camera, ss: int
) -> None:
    tex, card = _card_texture(m)
    nh, nw = tex.shape
    dst = cam.project(card, ss)
    h, w = canvas.shape[:2]
    x0, y0 = (max(0, int(np.floor(v)) - 1) for v in dst.min(axis=0))
    x1, y1 = min(w, int(np.ceil(dst[:, 0].max())) + 2), min(h, int(np.ceil(dst[:, 1].max())) + 2)
    if x0 >= x1 or y0 >= y1:
        return
    src = np.array(
        [[-0.5, -0.5], [nw - 0.5, -0.5], [nw - 0.5, nh - 0.5], [-0.5, nh - 0.5]], np.float32
    )
    hmat = cv2.getPerspectiveTransform(src, (dst - [x0, y0]).astype(np.float32))
    size = (x1 - x0, y1 - y0)
    warped = cv2.warpPerspective(tex.astype(np.float32), hmat, size, flags=cv2.INTER_LINEAR)
    mask = cv2.warpPerspective(np.ones((nh, nw), np.float32), hmat, size, flags=cv2.INTER_LINEAR)
    roi = canvas[y0:y1, x0:x1]
    roi *= (1.0 - mask)[..., None]
    roi += (warped * mask)[..., None]


def camera_tilted_down(
    target: tuple[float, float], height_cm: float, tilt_deg: float, azimuth_deg: float, **kw: object
) -> Camera:
    """A camera ``height_cm`` above the table looking at ``target``, ``tilt_deg`` from vertical."""
    t = math.radians(tilt_deg)
    az = math.radians(azimuth_deg)
    r = height_cm * math.tan(t)
    center = (target[0] - r * math.cos(az), target[1] - r * math.sin(az), height_cm)
    return Camera.look_at(center, (target[0], target[1], 0.0), (0.0, 1.0, 0.0), **kw)  # type: ignore[arg-type]


def camera_side(
    target: tuple[float, float, float],
    distance: float,
    elevation_deg: float,
    yaw_deg: float = 0.0,
    **kw: object,
) -> Camera:
    """A camera in front (-Y) of ``target`` at ``distance`` cm, raised by ``elevation_deg``."""
    e, y = math.radians(elevation_deg), math.radians(yaw_deg)
    d = np.array([math.sin(y) * math.cos(e), math.cos(y) * math.cos(e), -math.sin(e)])
    center = tuple(np.asarray(target) - distance * d)
    return Camera.look_at(center, target, (0.0, 0.0, 1.0), **kw)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------
# Ready-made set-ups
# --------------------------------------------------------------------------------------------

#: Horizontal field of view of the default cameras, degrees: the one :mod:`deformctl.vision`
#: assumes when it is given no camera matrix.
DEFAULT_HFOV_DEG = 60.0


def focal_for_hfov(width: int, hfov_deg: float = DEFAULT_HFOV_DEG) -> float:
    """Focal length, px, of a pinhole camera ``width`` px wide with this horizontal view angle."""
    return (width / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)


def box_scenes(
    size_cm: tuple[float, float, float],
    color_bgr: tuple[int, int, int],
    *,
    marker_size_cm: float = 5.0,
    marker_id: int = 0,
    yaw_deg: float = 0.0,
    tilt_deg: float = 0.0,
    azimuth_deg: float = 0.0,
    elevation_deg: float = 0.0,
    side_yaw_deg: float = 0.0,
    top_height_cm: float = 55.0,
    side_distance_cm: float = 45.0,
    focal_px: float | None = None,
    width: int = 960,
    height: int = 720,
) -> tuple[Scene, Camera, Scene, Camera]:
    """A box on the table seen from above and from the front, with a marker as vision expects.

    Top view: the marker lies flat beside the box, its printed top edge along the box's x side
    (so ``size_x_cm`` is ``size_cm[0]`` for ``yaw_deg = 0``); the camera is ``top_height_cm``
    above the table, tilted ``tilt_deg`` from vertical towards ``azimuth_deg``. Side view: the
    marker stands upright in the plane of the box's front face (``Y = -size_y / 2``), to its
    right; the camera looks at the front face from ``side_distance_cm``, raised by
    ``elevation_deg`` and turned by ``side_yaw_deg``.

    Args:
        size_cm: the box's ``(x, y, z)`` size, cm.
        color_bgr: its colour (faces are shaded by a fixed light).
        marker_size_cm: side of the marker's black square, cm.
        marker_id: the marker's id in ``DICT_4X4_50``.
        yaw_deg: the box turned about the vertical in the top view, degrees.
        tilt_deg: the top camera's tilt from vertical, degrees.
        azimuth_deg: the direction of that tilt, degrees.
        elevation_deg: the side camera's elevation above the horizontal, degrees.
        side_yaw_deg: the side camera turned about the vertical, degrees.
        top_height_cm: the top camera's height above the table, cm.
        side_distance_cm: the side camera's distance from its target, cm.
        focal_px: focal length, px; default: a 60-degree horizontal field of view.
        width: image width, px.
        height: image height, px.

    Returns:
        ``(top_scene, top_camera, side_scene, side_camera)``.
    """
    sx, sy, sz = size_cm
    r = math.hypot(sx, sy) / 2
    f = focal_for_hfov(width) if focal_px is None else focal_px
    cam_kw: dict[str, object] = {"focal_px": f, "width": width, "height": height}
    top = Scene(
        boxes=[Box((0.0, 0.0), size_cm, color_bgr, yaw_deg=yaw_deg)],
        markers=[Marker.flat(r + 2.0, -r - 2.0, marker_size_cm, marker_id=marker_id)],
    )
    cam_top = camera_tilted_down(
        (r / 2 + 2.0, -r / 2 - 1.0), top_height_cm, tilt_deg, azimuth_deg, **cam_kw
    )
    side = Scene(
        boxes=[Box((0.0, 0.0), size_cm, color_bgr)],
        markers=[Marker.upright(sx / 2 + 2.0, -sy / 2, 0.6, marker_size_cm, marker_id=marker_id)],
    )
    cam_side = camera_side(
        (marker_size_cm / 2 + 1.0, -sy / 2, sz / 2),
        side_distance_cm,
        elevation_deg,
        side_yaw_deg,
        **cam_kw,
    )
    return top, cam_top, side, cam_side


def box_views(
    size_cm: tuple[float, float, float],
    color_bgr: tuple[int, int, int] = (40, 40, 200),
    *,
    seed: int = 0,
    noise_sigma: float = 3.0,
    gradient: tuple[float, float] = (0.8, 1.1),
    with_box: bool = True,
    **setup: object,
) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    """Render the top and the side image of :func:`box_scenes` (same keyword arguments).

    Args:
        size_cm: the box's ``(x, y, z)`` size, cm.
        color_bgr: its colour.
        seed: noise seed (the side image uses ``seed + 1``).
        noise_sigma: Gaussian noise, grey levels.
        gradient: lighting factor from one image corner to the other.
        with_box: False renders the empty scenes (background images).
        **setup: the other arguments of :func:`box_scenes`.

    Returns:
        ``(top, side)``, uint8 BGR ``[height, width, 3]`` each.
    """
    top, cam_top, side, cam_side = box_scenes(size_cm, color_bgr, **setup)  # type: ignore[arg-type]
    if not with_box:
        top.boxes.clear()
        side.boxes.clear()
    kw: dict[str, object] = {"noise_sigma": noise_sigma, "gradient": gradient}
    return (
        render(top, cam_top, seed=seed, **kw),  # type: ignore[arg-type]
        render(side, cam_side, seed=seed + 1, **kw),  # type: ignore[arg-type]
    )


@dataclass(frozen=True)
class Gripper:
    """A side view of a box held between two palms, for slip from frames.

    The box (``object_size_cm``) stands centred at the origin; the palms are boxes
    ``palm_width_cm`` wide on either side along X, their lower ends ``palm_bottom_cm`` above the
    table. A static marker (id ``scale_marker_id``, side ``marker_size_cm``) stands upright in the
    plane of the box's front face, to the right, for the image scale; with ``palm_markers`` each
    palm also carries a marker (ids ``palm_marker_ids``) on its front face.
    """

    object_size_cm: tuple[float, float, float] = (8.0, 6.0, 6.0)
    object_color_bgr: tuple[int, int, int] = (180, 70, 40)
    palm_width_cm: float = 3.0
    palm_bottom_cm: float = 1.0
    marker_size_cm: float = 2.4
    scale_marker_id: int = 0
    palm_markers: bool = True
    palm_marker_ids: tuple[int, int] = (1, 2)
    distance_cm: float = 45.0
    focal_px: float | None = None
    width: int = 960
    height: int = 720

    def camera(self) -> Camera:
        f = focal_for_hfov(self.width) if self.focal_px is None else self.focal_px
        target = (2.0, -self.object_size_cm[1] / 2, 4.0)
        return camera_side(
            target, self.distance_cm, 0.0, focal_px=f, width=self.width, height=self.height
        )

    def scene(self, object_rise_cm: float, palm_rise_cm: float) -> Scene:
        """The scene with the box raised by ``object_rise_cm`` and the palms by ``palm_rise_cm``."""
        sx, sy, sz = self.object_size_cm
        front = -sy / 2
        obj = Box((0.0, 0.0), self.object_size_cm, self.object_color_bgr, z0=object_rise_cm)
        z0 = self.palm_bottom_cm + palm_rise_cm
        palms = [
            Box(
                (side * (sx / 2 + self.palm_width_cm / 2), 0.0),
                (self.palm_width_cm, sy, sz + 3.0),
                (110, 110, 110),
                z0=z0,
            )
            for side in (-1.0, 1.0)
        ]
        m = self.marker_size_cm
        markers: list[Marker | Checkerboard] = [
            Marker.upright(
                sx / 2 + self.palm_width_cm + 4.0, front, 1.0, m, marker_id=self.scale_marker_id
            )
        ]
        if self.palm_markers:
            for mid, side in zip(self.palm_marker_ids, (-1.0, 1.0), strict=True):
                x0 = side * (sx / 2 + self.palm_width_cm / 2) - m / 2
                markers.append(Marker.upright(x0, front - 0.05, z0 + sz - 1.0, m, marker_id=mid))
        return Scene(boxes=[obj, *palms], markers=markers)

    def palm_regions(self) -> list[tuple[int, int, int, int]]:
        """Each palm's lower end in the before frame (its lowest 3 cm and 10 px below), px."""
        sx, sy, _ = self.object_size_cm
        cam = self.camera()
        regions = []
        for side in (-1.0, 1.0):
            cx = side * (sx / 2 + self.palm_width_cm / 2)
            half = 0.4 * self.palm_width_cm
            z0 = self.palm_bottom_cm
            pts = np.array([[cx + dx, -sy / 2, z] for dx in (-half, half) for z in (z0, z0 + 3.0)])
            px = cam.project(pts)
            x0, y0 = np.floor(px.min(axis=0)).astype(int)
            x1, y1 = np.ceil(px.max(axis=0)).astype(int)
            regions.append((int(x0), int(y0), int(x1 - x0), int(y1 - y0 + 10)))
        return regions


def gripper_frame(
    gripper: Gripper,
    *,
    object_rise_cm: float,
    palm_rise_cm: float,
    seed: int = 0,
    noise_sigma: float = 3.0,
    gradient: tuple[float, float] = (0.8, 1.1),
) -> NDArray[np.uint8]:
    """Render one frame of ``gripper``: the box raised ``object_rise_cm``, palms ``palm_rise_cm``.

    Returns:
        uint8 BGR ``[gripper.height, gripper.width, 3]``.
    """
    return render(
        gripper.scene(object_rise_cm, palm_rise_cm),
        gripper.camera(),
        seed=seed,
        noise_sigma=noise_sigma,
        gradient=gradient,
    )
