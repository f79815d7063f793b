"""Calibrated cameras for ``measure --images``: ``--camera-matrix FILE``, undistortion, the warning
without it, and the default segmentation under a lighting gradient.

The scenes are the issue's: a 13.7 x 9.3 x 6.1 cm orange box on grey beside a 5 cm ArUco marker,
photographed from 45 cm through pinhole cameras (``deformctl.vision.synth``, real parallax) with
45-degree and 70-degree horizontal fields of view and a 20 % lighting gradient. With the camera's
calibration every side must come within 2 %; without it the command warns.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_catalog
from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, EXIT_NOINPUT, EXIT_USAGE, InputDataError
from deformctl.vision import load_camera_calibration, measure_object_size, synth, undistort

runner = CliRunner()
BOX_CM = (13.7, 9.3, 6.1)
ORANGE = (0, 128, 255)
WIDTH, HEIGHT = 960, 720
GRADIENT = (0.8, 1.0)  # 20 % darker in one corner than in the other
DISTORTION = np.array([-0.22, 0.07, 0.0, 0.0, 0.0])  # a wide lens' barrel distortion


def camera_matrix(hfov_deg: float) -> np.ndarray:
    f = synth.focal_for_hfov(WIDTH, hfov_deg)
    return np.array([[f, 0.0, (WIDTH - 1) / 2], [0.0, f, (HEIGHT - 1) / 2], [0.0, 0.0, 1.0]])


def distort(img: np.ndarray, k: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """What a lens with ``dist`` makes of a pinhole photo: each distorted pixel samples the
    pinhole image where its ray lands."""
    grid = np.stack(np.meshgrid(np.arange(WIDTH), np.arange(HEIGHT)), axis=-1).astype(np.float64)
    ideal = cv2.undistortPoints(grid.reshape(-1, 1, 2), k, dist, P=k).reshape(HEIGHT, WIDTH, 2)
    mx, my = ideal[..., 0].astype(np.float32), ideal[..., 1].astype(np.float32)
    return np.asarray(cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderValue=(190, 195, 200)))


@pytest.fixture(scope="module", params=[45.0, 70.0], ids=["45deg", "70deg"])
def scene(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> dict:
    hfov = float(request.param)
    k = camera_matrix(hfov)
    top, side = synth.box_views(BOX_CM, ORANGE, focal_px=k[0, 0], gradient=GRADIENT,
                                top_height_cm=45.0, side_distance_cm=45.0, seed=3)  # fmt: skip
    d = tmp_path_factory.mktemp(f"cam{int(hfov)}")
    cv2.imwrite(str(d / "top.png"), top)
    cv2.imwrite(str(d / "side.png"), side)
    return {"hfov": hfov, "k": k, "dir": d, "top": d / "top.png", "side": d / "side.png"}


def write_opencv(path: Path, k: np.ndarray, dist: np.ndarray, size: tuple[int, int]) -> Path:
    """What a calibration script saves with cv2.FileStorage (.yaml or .json by the name)."""
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", size[0])
    fs.write("image_height", size[1])
    fs.write("camera_matrix", k)
    fs.write("distortion_coefficients", dist.reshape(1, -1))
    fs.release()
    return path


def write_ros(path: Path, k: np.ndarray, dist: np.ndarray, size: tuple[int, int]) -> Path:
    """A ROS camera_info YAML as camera_calibration writes it (ost.yaml)."""
    path.write_text(
        f"image_width: {size[0]}\nimage_height: {size[1]}\ncamera_name: narrow_stereo\n"
        f"camera_matrix:\n  rows: 3\n  cols: 3\n  data: {k.ravel().tolist()}\n"
        "distortion_model: plumb_bob\n"
        f"distortion_coefficients:\n  rows: 1\n  cols: {dist.size}\n  data: {dist.tolist()}\n"
        "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
        f"projection_matrix:\n  rows: 3\n  cols: 4\n  data: {np.hstack([k, np.zeros((3, 1))]).ravel().tolist()}\n"  # noqa: E501
    )
    return path


def _measure(top: Path, side: Path, out: Path, *extra: str) -> tuple[int, str]:
    res = runner.invoke(app, ["measure", "images", str(top), str(side), "--marker-size-cm",
                              "5", "--object-id", "box", "--weight-n", "3", "--friction-mu", "0.5",
                              "-o", str(out), *extra])  # fmt: skip
    return res.exit_code, res.stderr


def _sizes(out: Path) -> np.ndarray:
    row = read_catalog(out).iloc[0]
    return np.array([row["size_x_cm"], row["size_y_cm"], row["size_z_cm"]])


@pytest.mark.parametrize("kind", ["opencv.yaml", "opencv.json", "ros.yaml"])
def test_with_the_camera_matrix_every_side_is_within_2_percent(
    scene: dict, tmp_path: Path, kind: str
) -> None:
    writer = write_ros if kind.startswith("ros") else write_opencv
    calib = writer(tmp_path / kind, scene["k"], np.zeros(5), (WIDTH, HEIGHT))
    out = tmp_path / "objects.csv"
    code, err = _measure(scene["top"], scene["side"], out, "--camera-matrix", str(calib))
    assert code == 0, err
    assert "warning" not in err
    rel = _sizes(out) / np.array(BOX_CM) - 1.0
    print(f"\n{scene['hfov']:g}° {kind}: {_sizes(out)} rel {np.round(100 * rel, 2)} %")
    assert np.all(np.abs(rel) < 0.02), rel


def test_without_it_one_warning_names_the_guess_and_the_correction(
    scene: dict, tmp_path: Path
) -> None:
    out = tmp_path / "objects.csv"
    code, err = _measure(scene["top"], scene["side"], out)
    assert code == 0, err
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1
    assert "no --camera-matrix: assumed a 60° horizontal field of view" in warnings[0]
    assert "height correction applied to the top view is -" in warnings[0]
    rel = _sizes(out)[:2] / np.array(BOX_CM[:2]) - 1.0
    print(f"\n{scene['hfov']:g}° without a camera matrix: {_sizes(out)} rel {100 * rel} %")
    # the guess is wrong for both lenses: the footprint is off by more than the 2 % kept with K
    assert np.all(np.abs(rel) > 0.02)


def test_a_distorted_photo_is_undistorted_with_the_calibration(tmp_path: Path) -> None:
    k = camera_matrix(70.0)
    top, side = synth.box_views(BOX_CM, ORANGE, focal_px=k[0, 0], gradient=GRADIENT,
                                top_height_cm=45.0, side_distance_cm=45.0, seed=5)  # fmt: skip
    paths = []
    for name, img in (("top", top), ("side", side)):
        paths.append(tmp_path / f"{name}.png")
        cv2.imwrite(str(paths[-1]), distort(img, k, DISTORTION))
    with_dist = write_opencv(tmp_path / "lens.yaml", k, DISTORTION, (WIDTH, HEIGHT))
    code, err = _measure(paths[0], paths[1], tmp_path / "a.csv", "--camera-matrix", str(with_dist))
    assert code == 0, err
    rel = _sizes(tmp_path / "a.csv") / np.array(BOX_CM) - 1.0
    assert np.all(np.abs(rel) < 0.02), rel
    no_dist = write_opencv(tmp_path / "pinhole.yaml", k, np.zeros(5), (WIDTH, HEIGHT))
    code, err = _measure(paths[0], paths[1], tmp_path / "b.csv", "--camera-matrix", str(no_dist))
    assert code == 0, err
    rel_raw = _sizes(tmp_path / "b.csv") / np.array(BOX_CM) - 1.0
    print(f"\ndistorted 70°: undistorted {100 * rel} %, not undistorted {100 * rel_raw} %")
    assert np.max(np.abs(rel_raw)) > np.max(np.abs(rel))


@pytest.mark.parametrize("gradient", [(1.0, 1.0), (0.88, 1.0), (0.8, 1.0), (1.0, 0.8)])
def test_default_segmentation_finds_the_box_under_a_lighting_gradient(
    gradient: tuple[float, float],
) -> None:
    k = camera_matrix(45.0)
    top, side = synth.box_views(BOX_CM, ORANGE, focal_px=k[0, 0], gradient=gradient,
                                top_height_cm=45.0, side_distance_cm=45.0, seed=7)  # fmt: skip
    size = measure_object_size(top, side, marker_size_cm=5.0, camera_matrix=k)
    got = np.array([size.size_x_cm, size.size_y_cm, size.size_z_cm])
    assert np.all(np.abs(got / np.array(BOX_CM) - 1.0) < 0.02), got


def test_the_formats_read_the_same_camera(tmp_path: Path) -> None:
    k = camera_matrix(45.0)
    dist = np.array([-0.1, 0.02, 0.001, -0.002, 0.003])
    plain = tmp_path / "plain.json"
    fields = {"camera_matrix": k.tolist(), "distortion_coefficients": dist.tolist()}
    plain.write_text(json.dumps({**fields, "image_width": WIDTH, "image_height": HEIGHT}))
    files = [
        write_opencv(tmp_path / "a.yaml", k, dist, (WIDTH, HEIGHT)),
        write_opencv(tmp_path / "a.json", k, dist, (WIDTH, HEIGHT)),
        write_ros(tmp_path / "ost.yaml", k, dist, (WIDTH, HEIGHT)),
        plain,
    ]
    for path in files:
        cam = load_camera_calibration(path)
        np.testing.assert_allclose(cam.camera_matrix, k)
        np.testing.assert_allclose(cam.distortion, dist)
        assert cam.image_size == (WIDTH, HEIGHT)
        assert cam.horizontal_fov_deg == pytest.approx(45.0)
    assert [load_camera_calibration(p).source for p in files] == ["opencv", "opencv", "ros",
                                                                  "opencv"]  # fmt: skip
    # without distortion the photo is returned as it is
    img = np.full((HEIGHT, WIDTH, 3), 128, np.uint8)
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps({"camera_matrix": k.tolist()}))
    assert undistort(img, load_camera_calibration(bare)) is img


BAD_FILES = {
    "garbage.yaml": ("key: [unclosed\n", "not valid YAML"),
    "empty.yaml": ("", "not a camera calibration"),
    "nomatrix.yaml": ("image_width: 960\n", "no camera_matrix"),
    "shape.json": ('{"camera_matrix": [[1, 0], [0, 1]]}', "camera_matrix must be 3x3"),
    "focal.json": ('{"camera_matrix": [[-5, 0, 1], [0, 5, 1], [0, 0, 1]]}', "not a pinhole matrix"),
    "text.json": ('{"camera_matrix": "K"}', "camera_matrix must hold numbers"),
    "nan.json": ('{"camera_matrix": [[NaN, 0, 1], [0, 5, 1], [0, 0, 1]]}', "non-finite"),
    "rows.yaml": (
        "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0]\n",
        "camera_matrix says 3x3 but holds 6 numbers",
    ),
    "dist.json": (
        '{"camera_matrix": [[5, 0, 1], [0, 5, 1], [0, 0, 1]], '
        '"distortion_coefficients": [0.1, 0.2, 0.3]}',
        "distortion_coefficients must have 4, 5, 8, 12 or 14 values, got 3",
    ),
    "json.json": ("{not json", "not valid JSON"),
    "size.json": (
        '{"camera_matrix": [[5, 0, 1], [0, 5, 1], [0, 0, 1]], "image_width": 0, "image_height": 5}',
        "image size must be whole pixels",
    ),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_a_bad_calibration_file_is_one_line_exit_65(scene: dict, tmp_path: Path, name: str) -> None:
    if scene["hfov"] != 45.0:
        pytest.skip("one scene is enough")
    text, message = BAD_FILES[name]
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputDataError, match=message):
        load_camera_calibration(path)
    out = tmp_path / "objects.csv"
    code, err = _measure(scene["top"], scene["side"], out, "--camera-matrix", str(path))
    assert code == EXIT_DATAERR, err
    assert len(err.strip().splitlines()) == 1
    assert err.startswith(f"error: {path}: ")
    assert message in err
    assert not out.exists()


def test_photos_of_another_size_than_the_calibration_are_refused(
    scene: dict, tmp_path: Path
) -> None:
    calib = write_ros(tmp_path / "ost.yaml", scene["k"], np.zeros(5), (1280, 960))
    out = tmp_path / "objects.csv"
    code, err = _measure(scene["top"], scene["side"], out, "--camera-matrix", str(calib))
    assert code == EXIT_DATAERR
    assert err.strip() == (
        f"error: {scene['top']}: the top image is 960x720 px but the camera calibration "
        f"{calib} is for 1280x960 px images; calibrate at the photos' resolution"
    )


def test_missing_calibration_and_other_sources(scene: dict, tmp_path: Path) -> None:
    out = tmp_path / "objects.csv"
    code, err = _measure(scene["top"], scene["side"], out, "--camera-matrix", "nope.yaml")
    assert code == EXIT_NOINPUT
    assert err.startswith("error: nope.yaml: ")
    res = runner.invoke(app, ["measure", "csv", "x.csv", "--columns", "time=t,force=f,gap=g",
                              "--object-id", "a", "--weight-n", "1", "--camera-matrix",
                              "k.yaml", "-o", str(out)])  # fmt: skip
    assert res.exit_code == EXIT_USAGE
    assert "--camera-matrix" in res.stderr
