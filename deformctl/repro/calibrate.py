"""Calibrate the ``paper`` simulator preset to the seed paper's 13 simulated lifting forces.

The points: Table II's simulation column for the four bags of Table I (their catalog sizes,
``datasets/paper/objects.csv``) and Table III's "expected" column for its nine (W, D, λ) inputs,
which have no sizes: they are cubes of density 1 g/cm³. Every point has μ = 0.5 (the paper does
not state it; it is the catalog's assumption).

Two parameters are fitted (:data:`deformctl.presets.CALIBRATED_PARAMETERS`, with their plausible
ranges as the bounds): the shear-to-squeeze damping ratio r and the lift's constant acceleration a.
Everything else is fixed (:data:`deformctl.presets.PAPER_FIXED`).

Method:

1. Simulate every point's L_f (the ``refine`` search to 0.2 %) on a grid of (r, a): ``r`` log-spaced
   over its range, ``a`` evenly spaced.
2. Interpolate each point's L_f on the grid (cubic in log r and a) and fit (r, a) by minimising the
   *worst* relative error over the 13 points (the paper preset's acceptance is a worst error), on
   the interpolants, within the bounds.
3. Leave-one-out: refit without each point in turn and simulate the left-out point at the refit
   values; the worst of those 13 errors is the leave-one-out error.
4. Simulate all 13 at the fitted values (the table printed and written is these direct runs, not
   interpolations), and Table III's cubes again at 0.5 g/cm³ (how much the assumed density
   matters).

Command line (``make calibrate``)::

    python -m deformctl.repro.calibrate [--write datasets/calibration/paper.json] [--jobs 2]
        [--convergence] [--quiet]

prints each point's L_f ours vs paper, the worst error and the leave-one-out worst error, and with
``--write`` stores the fitted values (and everything printed) in the file the ``paper`` preset
reads. ``--convergence`` also reruns the 13 points at half the time step and on a finer lattice
(13 particles per side) and prints how far each L_f moves. It ends with the commands' summary
line (:mod:`deformctl.summary`; ``--quiet`` drops it): the points done, the points flagged
(:func:`flagged_points`: left out of the fit, the refit misses them by more than the worst
in-sample error; a warning names them) and 0 failed (a search that does not converge stops the
run with an error).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from deformctl.catalog import CATALOG_COLUMNS, CatalogObject
from deformctl.errors import DeformctlError
from deformctl.physics import damping_ratio, rigid_grip_force_n
from deformctl.presets import CALIBRATED_PARAMETERS, PAPER_FIXED, SimPreset, paper_preset
from deformctl.resources import dataset_path
from deformctl.sim.objects import ObjectSpec
from deformctl.summary import RunClock
from deformctl.units import GRAVITY_M_S2
from deformctl.version import __version__

#: Density of Table III's cubes, g/cm³ (the paper gives no sizes), and the alternative checked.
CUBE_DENSITY_G_CM3 = 1.0
ALT_DENSITY_G_CM3 = 0.5
FRICTION_MU = 0.5
#: Relative bracket width of each calibration search (finer than ``lift``'s default).
SEARCH_TOLERANCE = 0.002
#: The default grid: r log-spaced, a evenly spaced, over the bounds.
GRID_R = tuple(round(float(x), 5) for x in np.geomspace(0.03, 0.3, 5))
GRID_A = (0.4, 0.8, 1.2, 1.6)


@dataclass(frozen=True)
class Point:
    """One published point: the simulated object and the paper's L_f, N."""

    label: str
    spec: ObjectSpec
    paper_lift_force_n: float

    @property
    def f_w_n(self) -> float:
        """F_w = W / (2 mu), N."""
        return rigid_grip_force_n(self.spec.weight_n, self.spec.friction_mu)

    @property
    def zeta(self) -> float:
        """The lumped damping ratio (:func:`deformctl.physics.damping_ratio`)."""
        s = self.spec
        return float(damping_ratio(s.weight_n, s.stiffness_n_per_cm, s.damping_ns_per_cm))


def cube_side_cm(weight_n: float, density_g_cm3: float) -> float:
    """Side of a cube of weight W and the given density, cm."""
    return float((weight_n / GRAVITY_M_S2 * 1000.0 / density_g_cm3) ** (1.0 / 3.0))


def table3_cube_catalog(density_g_cm3: float = CUBE_DENSITY_G_CM3) -> pd.DataFrame:
    """Table III's nine (W, D, λ) inputs as an object catalog: cubes of ``density_g_cm3``, μ 0.5.

    ``datasets/paper/table3_cubes.csv`` is this catalog at 1 g/cm³ (checked by a test), so
    ``make reproduce`` can run Table III's inputs through ``deformctl lift --sim``.
    """
    table3 = pd.read_csv(dataset_path("paper", "table3.csv"))
    rows = []
    for i, row in enumerate(table3.to_dict("records"), start=1):
        side = round(cube_side_cm(float(row["weight_n"]), density_g_cm3), 4)
        rows.append(  # in CATALOG_COLUMNS order: id, sizes x y z, weight, mu, D, lambda
            (f"T3-{i}", side, side, side, float(row["weight_n"]), FRICTION_MU,
             float(row["deformability_n_per_cm"]), float(row["damping_ns_per_cm"]))
        )  # fmt: skip
    return pd.DataFrame(rows, columns=list(CATALOG_COLUMNS))


def published_points(density_g_cm3: float = CUBE_DENSITY_G_CM3) -> list[Point]:
    """The 13 points: Table II (Table I's bags) then Table III (cubes of ``density_g_cm3``)."""
    objects = pd.read_csv(dataset_path("paper", "objects.csv"))
    table2 = pd.read_csv(dataset_path("paper", "table2.csv")).set_index("object_id")
    points = []
    for row in objects.to_dict("records"):
        obj = CatalogObject.from_row(row)
        spec = obj.to_sim_spec()
        name = str(row.get("name", obj.object_id))
        points.append(
            Point(name, spec, float(table2.loc[obj.object_id, "lift_force_simulation_n"]))
        )
    table3 = pd.read_csv(dataset_path("paper", "table3.csv"))
    cubes = table3_cube_catalog(density_g_cm3)
    for row, cube in zip(table3.to_dict("records"), cubes.to_dict("records"), strict=True):
        spec = CatalogObject.from_row(cube).to_sim_spec()
        points.append(Point(spec.object_id, spec, float(row["lift_force_expected_n"])))
    return points


def simulated_lift_force_n(
    spec: ObjectSpec, preset: SimPreset, tolerance_rel: float = SEARCH_TOLERANCE
) -> float:
    """L_f of ``spec`` under ``preset``: the ``refine`` search (from F_w) to ``tolerance_rel``.

    Raises:
        DeformctlError: the search did not converge (the message names the object).
    """
    from deformctl.lift.search import find_min_lift_force
    from deformctl.sim.engine import clear_model_cache

    def runner(force_n: float, _index: int) -> Any:
        return preset.lift_attempt(spec, force_n)

    try:
        result = find_min_lift_force(
            runner,
            weight_n=spec.weight_n,
            friction_mu=spec.friction_mu,
            protocol="refine",
            tolerance_rel=tolerance_rel,
            object_id=spec.object_id,
        )
    finally:
        clear_model_cache()
    if not result.converged:
        raise DeformctlError(result.message)
    return float(result.lift_force_n)


def _run_job(job: tuple[ObjectSpec, SimPreset]) -> float:
    return simulated_lift_force_n(*job)


def run_jobs(jobs: Sequence[tuple[ObjectSpec, SimPreset]], n_jobs: int) -> list[float]:
    """L_f of each (spec, preset), on ``n_jobs`` processes (in order)."""
    if n_jobs <= 1 or len(jobs) <= 1:
        return [_run_job(job) for job in jobs]
    # one BLAS thread per worker: the solves are sparse and the workers share the cores
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=n_jobs, mp_context=context) as pool:
        return list(pool.map(_run_job, jobs, chunksize=1))


def preset_for(r: float, a: float, **settings: Any) -> SimPreset:
    """The paper preset at (r, a), with optional SimSettings overrides."""
    preset = paper_preset(shear_damping_ratio=r, lift_accel_m_s2=a)
    if settings:
        preset = replace(preset, settings=replace(preset.settings, **settings))
    return preset


def grid_lift_forces(
    points: Sequence[Point],
    grid_r: Sequence[float],
    grid_a: Sequence[float],
    n_jobs: int,
    progress: Callable[[str], None] | None = None,
) -> np.ndarray:
    """L_f of every point at every grid node, N, ``[n_points, len(grid_r), len(grid_a)]``."""
    jobs = [(p.spec, preset_for(r, a)) for p in points for r in grid_r for a in grid_a]
    t0 = time.perf_counter()
    values = run_jobs(jobs, n_jobs)
    if progress is not None:
        progress(f"grid: {len(jobs)} searches in {time.perf_counter() - t0:.0f} s")
    return np.asarray(values).reshape(len(points), len(grid_r), len(grid_a))


@dataclass(frozen=True)
class Fit:
    """A fitted (r, a) and the worst relative error of its (interpolated) points."""

    shear_damping_ratio: float
    lift_accel_m_s2: float
    worst_interpolated: float


def fit_minimax(
    ratios: np.ndarray,
    grid_r: Sequence[float],
    grid_a: Sequence[float],
    use: Sequence[int],
) -> Fit:
    """Minimise the worst |L_f / paper - 1| over the points ``use``, on the interpolants.

    Args:
        ratios: ``L_f / paper`` per point and grid node, ``[n_points, n_r, n_a]``.
    """
    from scipy.interpolate import RegularGridInterpolator
    from scipy.optimize import minimize

    log_r = np.log(np.asarray(grid_r))
    method = "cubic" if min(len(grid_r), len(grid_a)) >= 4 else "linear"
    interps = [
        RegularGridInterpolator((log_r, np.asarray(grid_a)), ratios[i], method=method) for i in use
    ]

    def worst(x: np.ndarray) -> float:
        xy = np.array(
            [[min(max(x[0], log_r[0]), log_r[-1]), min(max(x[1], grid_a[0]), grid_a[-1])]]
        )
        return float(max(abs(float(f(xy)[0]) - 1.0) for f in interps))

    # dense scan of the box, then Nelder-Mead from the best node (the max is not smooth)
    lr = np.linspace(log_r[0], log_r[-1], 61)
    aa = np.linspace(grid_a[0], grid_a[-1], 61)
    mesh = np.array([[u, v] for u in lr for v in aa])
    table = np.max(np.abs(np.stack([f(mesh) for f in interps]) - 1.0), axis=0)
    start = mesh[int(np.argmin(table))]
    res = minimize(worst, start, method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-6})
    best = res.x if res.fun <= table.min() else start
    r = float(np.exp(min(max(best[0], log_r[0]), log_r[-1])))
    a = float(min(max(best[1], grid_a[0]), grid_a[-1]))
    return Fit(r, a, worst(np.array([np.log(r), a])))


def calibrate(
    *,
    grid_r: Sequence[float] = GRID_R,
    grid_a: Sequence[float] = GRID_A,
    n_jobs: int = 2,
    convergence: bool = False,
    labels: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = print,
) -> dict[str, Any]:
    """Run the whole calibration (see the module docstring) and return its record.

    Returns:
        JSON-serialisable: ``fitted`` (the two parameters), ``bounds``, ``fixed``, ``points``
        (each point's ours vs paper at the fitted values), ``worst_error``, ``leave_one_out``
        (per point and ``worst``), ``density_check`` and, with ``convergence``, the moves under
        dt/2 and a finer lattice.

    Args:
        labels: calibrate on these points only (default: all 13; for quick checks).
    """
    say = progress or (lambda _msg: None)
    points = [p for p in published_points() if labels is None or p.label in labels]
    paper = np.array([p.paper_lift_force_n for p in points])
    grid = grid_lift_forces(points, grid_r, grid_a, n_jobs, say)
    ratios = grid / paper[:, None, None]
    everyone = list(range(len(points)))
    fit = fit_minimax(ratios, grid_r, grid_a, everyone)
    say(
        f"fit: r = {fit.shear_damping_ratio:.4f}, a = {fit.lift_accel_m_s2:.4f} m/s^2 "
        f"(worst interpolated error {fit.worst_interpolated:.1%})"
    )
    loo_fits = [
        fit_minimax(ratios, grid_r, grid_a, [j for j in everyone if j != i]) for i in everyone
    ]
    preset = preset_for(fit.shear_damping_ratio, fit.lift_accel_m_s2)
    jobs = [(p.spec, preset) for p in points]
    jobs += [
        (p.spec, preset_for(f.shear_damping_ratio, f.lift_accel_m_s2))
        for p, f in zip(points, loo_fits, strict=True)
    ]
    alt_specs = {p.label: p.spec for p in published_points(ALT_DENSITY_G_CM3)}
    cubes = [i for i, p in enumerate(points) if p.label.startswith("T3-")]
    jobs += [(alt_specs[points[i].label], preset) for i in cubes]
    values = run_jobs(jobs, n_jobs)
    n = len(points)
    ours, loo, alt = values[:n], values[n : 2 * n], values[2 * n :]
    record: dict[str, Any] = {
        "what": "the paper simulator preset's fitted parameters (deformctl.presets)",
        "command": "make calibrate (python -m deformctl.repro.calibrate --write "
        "datasets/calibration/paper.json --convergence)",
        "deformctl_version": __version__,
        "fitted": {
            "shear_damping_ratio": round(fit.shear_damping_ratio, 5),
            "lift_accel_m_s2": round(fit.lift_accel_m_s2, 5),
        },
        "bounds": {k: list(v) for k, v in CALIBRATED_PARAMETERS.items()},
        "objective": "minimise the worst |L_f / L_f,paper - 1| over the 13 points",
        "fixed": PAPER_FIXED,
        "cube_density_g_cm3": CUBE_DENSITY_G_CM3,
        "friction_mu": FRICTION_MU,
        "search_tolerance_rel": SEARCH_TOLERANCE,
        "grid": {"shear_damping_ratio": list(grid_r), "lift_accel_m_s2": list(grid_a)},
        "points": [],
        "leave_one_out": {"points": []},
    }
    for i, p in enumerate(points):
        record["points"].append(
            {
                "point": p.label,
                "weight_n": p.spec.weight_n,
                "deformability_n_per_cm": p.spec.stiffness_n_per_cm,
                "damping_ns_per_cm": p.spec.damping_ns_per_cm,
                "size_cm": list(p.spec.size_cm),
                "zeta": round(p.zeta, 4),
                "lift_force_paper_n": p.paper_lift_force_n,
                "lift_force_ours_n": round(ours[i], 4),
                "ratio_paper": round(p.paper_lift_force_n / p.f_w_n, 4),
                "ratio_ours": round(ours[i] / p.f_w_n, 4),
                "error": round(ours[i] / p.paper_lift_force_n - 1.0, 4),
            }
        )
        record["leave_one_out"]["points"].append(
            {
                "point": p.label,
                "shear_damping_ratio": round(loo_fits[i].shear_damping_ratio, 5),
                "lift_accel_m_s2": round(loo_fits[i].lift_accel_m_s2, 5),
                "lift_force_ours_n": round(loo[i], 4),
                "error": round(loo[i] / p.paper_lift_force_n - 1.0, 4),
            }
        )
    record["worst_error"] = max(abs(q["error"]) for q in record["points"])
    record["leave_one_out"]["worst"] = max(
        abs(q["error"]) for q in record["leave_one_out"]["points"]
    )
    record["density_check"] = {
        "density_g_cm3": ALT_DENSITY_G_CM3,
        "moves": {points[i].label: round(alt[k] / ours[i] - 1.0, 4) for k, i in enumerate(cubes)},
    }
    record["density_check"]["worst_move"] = max(
        (abs(v) for v in record["density_check"]["moves"].values()), default=0.0
    )
    if convergence:
        record["convergence"] = convergence_study(points, preset, ours, n_jobs)
    return record


def convergence_study(
    points: Sequence[Point], preset: SimPreset, ours: Sequence[float], n_jobs: int
) -> dict[str, Any]:
    """How far each L_f moves at half the time step and at 13 particles per side."""
    s = preset.settings
    half_dt = replace(preset, settings=replace(s, dt_s=s.dt_s / 2.0))
    fine = replace(preset, settings=replace(s, particles_per_side=13, memory_budget_gib=8.0))
    jobs = [(p.spec, half_dt) for p in points] + [(p.spec, fine) for p in points]
    values = run_jobs(jobs, n_jobs)
    n = len(points)
    out: dict[str, Any] = {"half_dt": {}, "particles_per_side_13": {}}
    for i, p in enumerate(points):
        out["half_dt"][p.label] = round(values[i] / ours[i] - 1.0, 4)
        out["particles_per_side_13"][p.label] = round(values[n + i] / ours[i] - 1.0, 4)
    for key in ("half_dt", "particles_per_side_13"):
        out[f"worst_{key}"] = max(abs(v) for v in out[key].values())
    return out


def format_record(record: dict[str, Any]) -> str:
    """The calibration as a human-readable table."""
    fitted = record["fitted"]
    lines = [
        f"paper preset: shear_damping_ratio r = {fitted['shear_damping_ratio']:.4f}, "
        f"lift_accel a = {fitted['lift_accel_m_s2']:.4f} m/s^2 (fitted to 13 points)",
        f"{'point':8s} {'zeta':>6s} {'L_f ours':>9s} {'L_f paper':>9s} {'ours/F_w':>8s} "
        f"{'paper/F_w':>9s} {'error':>7s} {'LOO error':>9s}",
    ]
    for q, lo in zip(record["points"], record["leave_one_out"]["points"], strict=True):
        lines.append(
            f"{q['point']:8s} {q['zeta']:6.2f} {q['lift_force_ours_n']:9.3f} "
            f"{q['lift_force_paper_n']:9.3f} {q['ratio_ours']:8.3f} {q['ratio_paper']:9.3f} "
            f"{q['error']:+7.1%} {lo['error']:+9.1%}"
        )
    lines.append(
        f"worst error {record['worst_error']:.1%}; leave-one-out worst error "
        f"{record['leave_one_out']['worst']:.1%}"
    )
    dc = record["density_check"]
    lines.append(
        f"Table III cubes at {dc['density_g_cm3']} g/cm^3 instead of "
        f"{record['cube_density_g_cm3']}: worst move {dc['worst_move']:.1%}"
    )
    if "convergence" in record:
        c = record["convergence"]
        lines.append(
            f"convergence: dt/2 moves L_f by at most {c['worst_half_dt']:.1%}, 13 particles per "
            f"side by at most {c['worst_particles_per_side_13']:.1%}"
        )
        for label in c["half_dt"]:
            lines.append(
                f"  {label:8s} dt/2 {c['half_dt'][label]:+.1%}  "
                f"n=13 {c['particles_per_side_13'][label]:+.1%}"
            )
    return "\n".join(lines)


def flagged_points(record: dict[str, Any]) -> list[str]:
    """The points the fit leans on: left out, the refit misses them by more than the fit misses
    any point (its leave-one-out error is above the in-sample worst error), each as
    ``label (error)``."""
    worst = record["worst_error"]
    return [
        f"{q['point']} ({q['error']:+.1%})"
        for q in record["leave_one_out"]["points"]
        if abs(q["error"]) > worst
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m deformctl.repro.calibrate``: see the module docstring."""
    clock = RunClock("calibrate")
    parser = argparse.ArgumentParser(prog="python -m deformctl.repro.calibrate")
    parser.add_argument("--write", metavar="FILE", help="write the calibration record here")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument(
        "--convergence", action="store_true", help="also rerun at dt/2 and 13 particles per side"
    )
    parser.add_argument(
        "--quiet", "-q", action="store_true", help="no summary line at the end (warnings stay)"
    )
    args = parser.parse_args(argv)
    try:
        record = calibrate(n_jobs=max(1, args.jobs), convergence=args.convergence)
    except DeformctlError as err:
        print(f"error: {err}", file=sys.stderr)
        return err.exit_code
    print(format_record(record))
    if args.write:
        Path(args.write).write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    flagged = flagged_points(record)
    if flagged:
        print(
            f"warning: left out of the fit, {len(flagged)} point(s) miss by more than the "
            f"worst in-sample error {record['worst_error']:.1%}: {', '.join(flagged)}",
            file=sys.stderr,
        )
    clock.finish(
        done=len(record["points"]),
        flagged=len(flagged),
        failed=0,
        output=args.write or "stdout",
        quiet=args.quiet,
    )
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
