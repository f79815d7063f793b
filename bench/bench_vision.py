"""Size errors of ``deformctl.vision`` on rendered scenes, over the test cases and more seeds.

Prints, per case and seed, the measured x, y, z sizes and their errors against the rendered
geometry, then the maximum absolute and relative error and the time per measurement. Then the
calibrated-camera scenes of tests/vision/test_camera.py (a 13.7 x 9.3 x 6.1 cm orange box on grey
from 45 cm, pinhole cameras of 45 and 70 degrees, lighting gradients of 0-20 %), each measured
with the camera matrix and with the 60-degree guess, with the height correction applied.
"""

from __future__ import annotations

import time

from deformctl import vision
from deformctl.vision import synth
from tests._helpers.vision_render import render
from tests.vision.test_camera import BOX_CM, ORANGE, camera_matrix
from tests.vision.test_size import CASES, MARKER_CM, _k, _scenes

SEEDS = (0, 1, 2)


def main() -> None:
    worst_cm, worst_rel, worst_ratio, times = 0.0, 0.0, 0.0, []
    for case in CASES:
        top_scene, cam_top, side_scene, cam_side = _scenes(case)
        for seed in SEEDS:
            top = render(top_scene, cam_top, seed=100 + seed)
            side = render(side_scene, cam_side, seed=200 + seed)
            t0 = time.perf_counter()
            m = vision.measure_object_size(top, side, marker_size_cm=MARKER_CM, camera_matrix=_k())
            times.append(time.perf_counter() - t0)
            got = (m.size_x_cm, m.size_y_cm, m.size_z_cm)
            errs = [g - s for g, s in zip(got, case.size_cm, strict=True)]
            for e, s in zip(errs, case.size_cm, strict=True):
                worst_cm = max(worst_cm, abs(e))
                worst_rel = max(worst_rel, abs(e) / s)
                worst_ratio = max(worst_ratio, abs(e) / max(0.03 * s, 0.2))
            print(
                f"{case.name:12s} seed {seed}: "
                + "  ".join(f"{g:6.3f} ({e:+.3f})" for g, e in zip(got, errs, strict=True))
                + " cm"
            )
    print(
        f"max |error| {worst_cm * 10:.2f} mm, max relative {worst_rel * 100:.2f} %, "
        f"max error / tolerance {worst_ratio:.2f}; {sum(times) / len(times):.2f} s per object"
    )

    camera_scenes()


def camera_scenes() -> None:
    """Relative size errors with and without the camera matrix, per lens and gradient."""
    worst = {True: 0.0, False: 0.0}
    for hfov in (45.0, 70.0):
        k = camera_matrix(hfov)
        for gradient in ((1.0, 1.0), (0.88, 1.0), (0.8, 1.0)):
            setup = {"top_height_cm": 45.0, "side_distance_cm": 45.0, "seed": 3}
            top, side = synth.box_views(
                BOX_CM, ORANGE, focal_px=k[0, 0], gradient=gradient, **setup
            )
            for calibrated in (True, False):
                m = vision.measure_object_size(
                    top, side, marker_size_cm=5.0, camera_matrix=k if calibrated else None
                )
                got = (m.size_x_cm, m.size_y_cm, m.size_z_cm)
                rel = [100.0 * (g / s - 1.0) for g, s in zip(got, BOX_CM, strict=True)]
                worst[calibrated] = max(worst[calibrated], *(abs(r) for r in rel))
                print(
                    f"{hfov:g}° camera, gradient {100 * (1 - min(gradient)):.0f} %, "
                    f"{'camera matrix' if calibrated else '60° guess    '}: "
                    + " x ".join(f"{g:.2f}" for g in got)
                    + " cm ("
                    + ", ".join(f"{r:+.1f} %" for r in rel)
                    + f"), height correction {m.height_correction_pct:+.1f} %"
                )
    print(
        f"max |relative error| with the camera matrix {worst[True]:.2f} %, "
        f"with the 60° guess {worst[False]:.2f} %"
    )


if __name__ == "__main__":
    main()
