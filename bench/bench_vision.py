"""Size errors of ``deformctl.vision`` on rendered scenes, over the test cases and more seeds.

Prints, per case and seed, the measured x, y, z sizes and their errors against the rendered
geometry, then the maximum absolute and relative error and the time per measurement.
"""

from __future__ import annotations

import time

from deformctl import vision
from tests.test_vision import CASES, MARKER_CM, _k, _scenes
from tests.vision_render import render

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


if __name__ == "__main__":
    main()
