"""Cost of one complete object at each simulator preset (target: <= 2 s per object).

For each Table I object: three squeezes (as ``measure --sim`` does) and the default ``refine``
search (to 0.5 %) at the ``paper`` and at the ``table`` preset, wall seconds and attempts, both
measured in this run so the ratio between presets is meaningful on a noisy machine.
"""

from __future__ import annotations

import time

import pandas as pd

from deformctl.catalog import CatalogObject
from deformctl.lift.search import DEFAULT_TOLERANCE_REL, find_min_lift_force
from deformctl.measure import default_peak_force_n
from deformctl.presets import SimPreset, sim_preset
from deformctl.resources import dataset_path
from deformctl.sim import ObjectSpec, squeeze_many
from deformctl.sim.engine import build_model

TARGET_S = 2.0


def complete_object(spec: ObjectSpec, preset: SimPreset) -> tuple[float, int, float]:
    """(wall s, attempts, L_f N) of 3 squeezes + the refine search, from a cold model cache."""
    build_model.cache_clear()
    t0 = time.perf_counter()
    squeeze_many(spec, 3, peak_force_n=default_peak_force_n(spec), settings=preset.settings)
    result = find_min_lift_force(
        lambda force_n, _i: preset.lift_attempt(spec, force_n),
        weight_n=spec.weight_n,
        friction_mu=spec.friction_mu,
        tolerance_rel=DEFAULT_TOLERANCE_REL,
    )  # fmt: skip
    return time.perf_counter() - t0, result.attempts, float(result.lift_force_n)


def main() -> None:
    objects = pd.read_csv(dataset_path("paper", "objects.csv"))
    specs = [CatalogObject.from_row(r).to_sim_spec() for r in objects.to_dict("records")]
    # warm the numba caches once, outside the timings
    complete_object(specs[0], sim_preset("paper"))
    print(f"one complete object (3 squeezes + refine to {DEFAULT_TOLERANCE_REL:.1%}), wall s:")
    print(f"{'object':>8} {'paper s':>8} {'attempts':>8} {'table s':>8} {'attempts':>8}")
    worst = 0.0
    for spec in specs:
        tp, ap, _ = complete_object(spec, sim_preset("paper"))
        tt, at, _ = complete_object(spec, sim_preset("table"))
        worst = max(worst, tp)
        print(f"{spec.object_id:>8} {tp:>8.2f} {ap:>8d} {tt:>8.2f} {at:>8d}", flush=True)
    print(f"worst paper-preset object {worst:.2f} s (target <= {TARGET_S:.0f} s)")


if __name__ == "__main__":
    main()
