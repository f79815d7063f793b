"""Simulator speed: one sponge lift attempt, one complete object, force-kernel throughput,
implicit-step cost relative to one force evaluation. Every ratio is measured in this run."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from deformctl.sim import (
    LiftProfile,
    ObjectSpec,
    SimSettings,
    f_w_n,
    lift_attempt,
    rigid_lift_force_n,
    squeeze_many,
)
from deformctl.sim.engine import build_model, run_model
from deformctl.sim.kernels import spring_forces, spring_forces_numpy
from deformctl.sim.lattice import build_lattice

SPONGE = ObjectSpec("sponge", (17.8, 19.1, 9.2), 0.7, 0.5, 49.18, 6.47)


def _best_of(fn: Callable[[], object], repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _bisect(spec: ObjectSpec, rel_tol: float = 0.01) -> tuple[float, int]:
    """Minimal local search: paper ramp from F_w (x1.2) to bracket, then bisection to rel_tol."""
    lo = hi = f_w_n(spec)
    attempts = 0
    while True:
        attempts += 1
        if lift_attempt(spec, hi).lifted:
            break
        lo, hi = hi, hi * 1.2
    if attempts == 1:
        lo = 0.0
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        attempts += 1
        if lift_attempt(spec, mid).lifted:
            hi = mid
        else:
            lo = mid
    return hi, attempts


def main() -> None:
    # warm up the numba caches and the model cache
    lift_attempt(SPONGE, 1.0)
    build_model.cache_clear()

    t_first = _best_of(lambda: (build_model.cache_clear(), lift_attempt(SPONGE, 1.0)), 3)
    t_lift = _best_of(lambda: lift_attempt(SPONGE, 1.0))
    model = build_model(SPONGE, SimSettings(), gripped=True)
    print(
        f"sponge lattice {model.lattice.shape}, {model.n_dof} DOFs, "
        f"{model.lattice.edges.shape[0]} elements, {model.row_dof.size} contact rows"
    )
    print(f"one sponge lift attempt (model cached):       {t_lift:.4f} s  (target <= 0.25 s)")
    print(f"one sponge lift attempt (incl. model build):  {t_first:.4f} s")

    def whole_object() -> tuple[float, int]:
        build_model.cache_clear()
        squeeze_many(SPONGE, 3, peak_force_n=8.0)
        return _bisect(SPONGE)

    t0 = time.perf_counter()
    lf, attempts = whole_object()
    t_object = time.perf_counter() - t0
    print(
        f"one complete object (3 squeezes + search to 1 %, {attempts} attempts): "
        f"{t_object:.3f} s  (target <= 2 s); L_f = {lf:.4f} N, "
        f"F_w = {f_w_n(SPONGE):.4f} N, rigid {rigid_lift_force_n(SPONGE, LiftProfile()):.4f} N"
    )

    # force kernel throughput on a 10 x 10 x 10 lattice
    lat = build_lattice((0.09, 0.09, 0.09), 0.01)
    rng = np.random.default_rng(0)
    x = lat.positions_m + rng.normal(0, 1e-4, lat.positions_m.shape)
    v = rng.normal(0, 1e-2, x.shape)
    k = lat.unit_stiffness * 100.0
    c = k * 0.01
    out = np.zeros_like(x)
    m = lat.edges.shape[0]
    spring_forces(x, v, lat.edges, lat.rest_length_m, k, c, out)
    reps = 200

    def numba_eval() -> None:
        for _ in range(reps):
            out[:] = 0.0
            spring_forces(x, v, lat.edges, lat.rest_length_m, k, c, out)

    def numpy_eval() -> None:
        for _ in range(reps // 10):
            spring_forces_numpy(x, v, lat.edges, lat.rest_length_m, k, c)

    t_nb = _best_of(numba_eval) / reps
    t_np = _best_of(numpy_eval) / (reps // 10)
    ref = spring_forces_numpy(x, v, lat.edges, lat.rest_length_m, k, c)
    assert np.allclose(out, ref, rtol=1e-10, atol=1e-12)
    print(
        f"force kernel, 10x10x10 lattice ({m} springs): numba {m / t_nb:.3e} springs/s, "
        f"numpy {m / t_np:.3e} springs/s, ratio {t_np / t_nb:.1f}x  (target >= 10x)"
    )

    # implicit step vs one force evaluation, on the sponge model and on a 10^3 cube
    for label, spec in (
        ("sponge (default alpha)", SPONGE),
        ("10x10x10 cube", ObjectSpec("cube", (9.0, 9.0, 9.0), 5.0, 0.5, 20.0, 1.0)),
    ):
        settings = SimSettings() if label.startswith("sponge") else SimSettings(alpha_cm=1.0)
        mdl = build_model(spec, settings, gripped=True)
        n_steps = 400
        force = np.full(n_steps + 1, 2.0)
        vz = np.zeros(n_steps + 1)
        run_model(mdl, force[:2], vz[:2])
        t_step = _best_of(lambda mdl=mdl, force=force, vz=vz: run_model(mdl, force, vz), 3)
        t_step /= n_steps
        xm = mdl.base_x
        vm = np.zeros_like(xm)
        om = np.zeros_like(xm)
        le = mdl.lattice

        def one_force(le=le, xm=xm, vm=vm, om=om, mdl=mdl) -> None:
            for _ in range(reps):
                spring_forces(
                    xm,
                    vm,
                    le.edges,
                    le.rest_length_m,
                    mdl.stiffness_n_per_m,
                    mdl.damping_ns_per_m,
                    om,
                )

        t_force = _best_of(one_force) / reps
        print(
            f"implicit step, {label} ({mdl.n_dof} DOFs, {mdl.row_dof.size} contact rows): "
            f"{t_step * 1e6:.1f} us = {t_step / t_force:.1f} x one force evaluation "
            f"({t_force * 1e6:.2f} us)"
        )


if __name__ == "__main__":
    main()
