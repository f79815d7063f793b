"""The CI dataset regression: a small fixed population through the whole pipeline.

:func:`compute_golden` runs the eight-object golden population
(:func:`deformctl.population.golden_population`) through the same library functions the
commands are thin over — simulated squeezes, the ``lsq`` fit, the refined lifting-force search
in the simulator, the index table and the 3-2-1 network — and returns the numbers that matter:
each object's D, λ and L_f, and the model's errors. ``datasets/golden/expected.json`` holds the
numbers of the last accepted run; ``make test`` recomputes them and :func:`compare` lists every
number that moved beyond its tolerance, so a physics or pipeline change that moves results fails
CI with a readable diff.

Tolerances (:data:`TOLERANCES`) are set by what legitimately varies between machines, not by
what makes the test pass: the simulator and the fits are deterministic in floating point on one
machine, but BLAS and numba builds may differ in the last bits, and the lifting-force bisection
turns a bit-level change at a slip threshold into one bisection step (≤ the 1 % search
tolerance). After an intended change, regenerate with ``python -m deformctl.repro.golden --update``
and commit the new file with the change that moved it.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from typing import Any

from deformctl.characterize import characterize
from deformctl.lift.runners.sim import sim_runner_factory
from deformctl.lift.stage import lift_catalog
from deformctl.measure import simulate_squeezes
from deformctl.population import golden_population
from deformctl.resources import dataset_path
from deformctl.series import SqueezeSeries
from deformctl.table import build_index_table
from deformctl.train import train_model

#: The expected numbers: ``datasets/golden/expected.json`` (package data ``deformctl.datasets``).
EXPECTED_PATH = dataset_path("golden", "expected.json")

#: Training split of the golden run: 6 objects train, 2 test.
GOLDEN_TRAIN_SIZE = 6
GOLDEN_SEED = 0
#: The simulator preset of the golden run (the product's default, ``--sim-preset paper``).
GOLDEN_PRESET = "paper"

#: Relative tolerance per quantity (see the module docstring for why these values).
TOLERANCES = {
    "deformability_n_per_cm": 0.005,
    "damping_ns_per_cm": 0.02,
    "lift_force_n": 0.011,
}
#: Absolute tolerances: λ near 0 (N·s/cm) and the model's relative errors (fractions).
ABS_TOLERANCES = {"damping_ns_per_cm": 0.01, "model": 0.02}


def compute_golden() -> dict[str, Any]:
    """Run the golden population through the pipeline and return its numbers.

    Returns:
        ``{"objects": {id: {deformability_n_per_cm, damping_ns_per_cm, lift_force_n, f_w_n,
        attempts}}, "model": {train_max_rel_error, test_max_rel_error, test_mae_n}}``.
    """
    from deformctl.presets import sim_preset

    preset = sim_preset(GOLDEN_PRESET)
    catalog = golden_population()
    _, squeezes = simulate_squeezes(catalog, settings=preset.settings, seed=GOLDEN_SEED)
    by_object: dict[str, list[SqueezeSeries]] = {}
    for s in squeezes:
        by_object.setdefault(s.object_id, []).append(s)
    coefficients = characterize(by_object, "lsq")
    lift = lift_catalog(catalog, sim_runner_factory(preset=preset)).table
    index = build_index_table(coefficients, lift)
    # the paper's network on (W, D, λ), although the golden objects' μ varies (which would
    # choose the grip form): the regression watches the pipeline, not the model's form
    result = train_model(
        index, train_size=GOLDEN_TRAIN_SIZE, seed=GOLDEN_SEED, hidden=(2,), form="paper"
    )
    model = result.metrics["model"]
    objects = {}
    for row in index.merge(lift[["object_id", "attempts"]], on="object_id").itertuples():
        objects[str(row.object_id)] = {
            "deformability_n_per_cm": float(row.deformability_n_per_cm),
            "damping_ns_per_cm": float(row.damping_ns_per_cm),
            "lift_force_n": float(row.lift_force_n),
            "f_w_n": float(row.f_w_n),
            "attempts": int(row.attempts),
        }
    return {
        "objects": objects,
        "model": {
            "train_max_rel_error": float(model["train"]["max_rel_error"]),
            "test_max_rel_error": float(model["test"]["max_rel_error"]),
            "test_mae_n": float(model["test"]["mae_n"]),
        },
    }


def _moved(key: str, expected: float, actual: float) -> bool:
    if not (math.isfinite(expected) and math.isfinite(actual)):
        return not (math.isnan(expected) and math.isnan(actual))
    allowed = TOLERANCES.get(key, 0.0) * abs(expected) + ABS_TOLERANCES.get(key, 0.0)
    return abs(actual - expected) > allowed


def compare(expected: dict[str, Any], actual: dict[str, Any]) -> list[str]:
    """Every number of ``actual`` that moved beyond its tolerance, one line each."""
    lines = []
    exp_ids, act_ids = set(expected["objects"]), set(actual["objects"])
    if exp_ids != act_ids:
        lines.append(f"objects differ: expected {sorted(exp_ids)}, got {sorted(act_ids)}")
    for oid in sorted(exp_ids & act_ids):
        for key in TOLERANCES:
            e, a = expected["objects"][oid][key], actual["objects"][oid][key]
            if _moved(key, e, a):
                rel = (a - e) / e if e else math.inf
                lines.append(f"{oid} {key}: expected {e:.6g}, got {a:.6g} ({100 * rel:+.2f} %)")
    for key in ("train_max_rel_error", "test_max_rel_error"):
        e, a = expected["model"][key], actual["model"][key]
        if abs(a - e) > ABS_TOLERANCES["model"]:
            lines.append(f"model {key}: expected {e:.4f}, got {a:.4f}")
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m deformctl.repro.golden [--update]``: compare with (or rewrite) the expected
    file."""
    args = list(sys.argv[1:] if argv is None else argv)
    actual = compute_golden()
    if args == ["--update"]:
        EXPECTED_PATH.parent.mkdir(parents=True, exist_ok=True)
        EXPECTED_PATH.write_text(json.dumps(actual, indent=2, sort_keys=True) + "\n")
        print(f"wrote {EXPECTED_PATH}")
        return 0
    moved = compare(json.loads(EXPECTED_PATH.read_text()), actual)
    print("\n".join(moved) if moved else "golden run matches datasets/golden/expected.json")
    return 1 if moved else 0


if __name__ == "__main__":
    sys.exit(main())
