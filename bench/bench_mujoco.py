"""Our simulator against MuJoCo flex on the same damped-cube squeeze, both timed in this run.

The cube: 9 cm, 5 N, D 20 N/cm, lambda 1 N·s/cm, on the table under gravity, squeezed by two
palms whose force ramps linearly to 10 N and holds (:data:`RAMP_S` + :data:`HOLD_S` simulated).
Ours is :func:`deformctl.sim.squeeze` with ``particles_per_side = n`` at its default step (1 ms).
MuJoCo's is an MJCF ``<flexcomp type="grid" dim="3">`` of the same n^3 points (its tetrahedral
volume elasticity: Young's modulus ``D / L``, so that the uniaxial stiffness ``E A / L`` is D;
Poisson 0.25, the cubic spring lattice's; Rayleigh damping ``lambda / D`` seconds, so that the
damping force is that time times the elastic one) between a ground plane and two 50 g palms on
x sliders, each pushed by a motor with the same force ramp; contact friction 0.5 (the cube's
mu), no self-collision. MuJoCo 4 integrates flex elasticity stably only with its ``discrete``
integrator; the sparse Jacobian and the CG solver are its fastest settings for these models
(the dense ones and Newton were 3-12 x slower at 8^3). Its step is the largest of
:data:`MUJOCO_DT_S` at which MuJoCo raises no warning over the whole squeeze.

Prints, per size: each engine's CPU seconds per simulated second (both run on one thread; the
process's CPU time is what a shared machine's load inflates least, and on an idle machine it is
the wall time), ours best of 3 (before and after MuJoCo's run), MuJoCo's one run (its steps are
~100-1,000 x dearer, so one run of hundreds of steps is its own average); their ratio, per
simulated second and per step; each engine's compression at the end (the two model the same
squeeze, not the same numbers); the fitted exponent of the cost against the particle count; and,
at the largest size, where our call spends its time (:func:`ours_breakdown`: the step loop
against the whole call, the CG's V-cycles and products per step).
The window is short (0.2 s, so that MuJoCo's 16^3 fits in minutes); our steps cost more in the
ramp than in the hold, so the short window does not favour ours.
``python -m bench.bench_mujoco --sizes 5 8 11 16 21`` chooses the sizes (default
:data:`SIZES`). Without MuJoCo (``pip install -e '.[bench]'``, which ``make bench`` does) it says
so and returns.
"""

from __future__ import annotations

import argparse
import importlib.util
import time

import numpy as np

from deformctl.sim import ObjectSpec, SimSettings, squeeze
from deformctl.sim.engine import build_model, run_model
from deformctl.sim.hunt_crossley import implicit_reference_m

#: the damped cube: 9 cm, 5 N, mu 0.5, D 20 N/cm, lambda 1 N·s/cm
DAMPED = ObjectSpec("damped", (9.0, 9.0, 9.0), 5.0, 0.5, 20.0, 1.0)
PEAK_N = 10.0
RAMP_S = 0.1
HOLD_S = 0.1
SIZES = (5, 8, 11, 16)
#: MuJoCo's candidate steps, s, largest first
MUJOCO_DT_S = (1e-3, 5e-4, 2.5e-4, 1.25e-4)
OURS_DT_S = SimSettings().dt_s
PALM_KG = 0.05
G = 9.81


def mjcf(n: int, dt_s: float, spec: ObjectSpec = DAMPED) -> str:
    """The MJCF of ``spec`` as an ``n``^3 flex grid squeezed between two force-driven palms."""
    side = spec.size_cm[0] / 100.0
    d_n_per_m = spec.stiffness_n_per_cm * 100.0
    lam = spec.damping_ns_per_cm * 100.0
    h = side / (n - 1)
    r = min(0.005, 0.25 * h)  # the flex vertices' collision radius
    z = side / 2 + r
    palm = 0.01  # half thickness
    return f"""<mujoco>
  <option timestep="{dt_s}" integrator="discrete" gravity="0 0 -{G}" solver="CG"
          jacobian="sparse"/>
  <worldbody>
    <geom type="plane" size="1 1 0.01"/>
    <body name="left" pos="{-side / 2 - r - palm} 0 {z}">
      <joint name="left" type="slide" axis="1 0 0"/>
      <geom type="box" size="{palm} {side} {side}" mass="{PALM_KG}"/>
    </body>
    <body name="right" pos="{side / 2 + r + palm} 0 {z}">
      <joint name="right" type="slide" axis="1 0 0"/>
      <geom type="box" size="{palm} {side} {side}" mass="{PALM_KG}"/>
    </body>
    <flexcomp name="cube" type="grid" dim="3" count="{n} {n} {n}" spacing="{h} {h} {h}"
              pos="0 0 {z}" radius="{r}" mass="{spec.weight_n / G}">
      <edge equality="false"/>
      <elasticity young="{d_n_per_m / side}" poisson="0.25" damping="{lam / d_n_per_m}"/>
      <contact selfcollide="none" condim="3" friction="{spec.friction_mu}"/>
    </flexcomp>
  </worldbody>
  <actuator>
    <motor joint="left" gear="1"/>
    <motor joint="right" gear="-1"/>
  </actuator>
</mujoco>"""


def _warned(data: object) -> bool:
    """Whether MuJoCo has raised any warning on ``data`` (an ``MjData``)."""
    return any(int(w.number) > 0 for w in data.warning)  # type: ignore[attr-defined]


def mujoco_squeeze(n: int, dt_s: float) -> tuple[float, float] | None:
    """MuJoCo's squeeze at ``n``^3 and step ``dt_s``: (CPU s, compression m at the end), or
    None when MuJoCo warned (unstable, ill-conditioned) during it."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(mjcf(n, dt_s))
    data = mujoco.MjData(model)
    left, right = (int(model.jnt_qposadr[j]) for j in range(2))
    steps = round((RAMP_S + HOLD_S) / dt_s)
    t0 = time.process_time()
    for i in range(steps):
        data.ctrl[:] = PEAK_N * min(data.time / RAMP_S, 1.0)
        mujoco.mj_step(model, data)
        if i % 20 == 0 and _warned(data):
            return None
    cpu = time.process_time() - t0
    if _warned(data) or not np.isfinite(data.qpos).all():
        return None
    return cpu, float(data.qpos[left] - data.qpos[right])


def ours_squeeze(n: int) -> tuple[float, float]:
    """Our squeeze at ``n``^3 (model built and kernels loaded first): (CPU s, compression m)."""
    settings = SimSettings(particles_per_side=n, dt_s=OURS_DT_S)
    run = lambda: squeeze(  # noqa: E731
        DAMPED, peak_force_n=PEAK_N, ramp_s=RAMP_S, hold_s=HOLD_S, settings=settings
    )
    series = run()
    build_model(DAMPED, settings, gripped=True)
    t0 = time.process_time()
    run()
    return time.process_time() - t0, float(series.compression_m[-1])


def ours_breakdown(n: int, repeats: int = 3) -> str:
    """Where one of our squeezes at ``n``^3 spends its CPU time: the whole call against the step
    loop alone (the kernel on the model :func:`squeeze` builds and caches, with the same force
    ramp; best of ``repeats`` each, alternating; the difference is the call's checks, model
    look-up and series), and the CG's work per step (V-cycles, and explicit products ``A dv``:
    the others are carried from step to step)."""
    settings = SimSettings(particles_per_side=n, dt_s=OURS_DT_S)
    model = build_model(
        DAMPED, settings, gripped=True, reference_m=implicit_reference_m(DAMPED, PEAK_N)
    )
    steps = round((RAMP_S + HOLD_S) / OURS_DT_S)
    force = PEAK_N * np.clip(np.arange(steps + 1) * OURS_DT_S / RAMP_S, 0.0, 1.0)

    call = loop = float("inf")
    model.solver_stats[:] = 0
    for _ in range(repeats):
        t0 = time.process_time()
        squeeze(DAMPED, peak_force_n=PEAK_N, ramp_s=RAMP_S, hold_s=HOLD_S, settings=settings)
        call = min(call, time.process_time() - t0)
        t0 = time.process_time()
        run_model(model, force, np.zeros(steps + 1))
        loop = min(loop, time.process_time() - t0)
    stats = model.solver_stats / (2 * repeats)  # the same steps in both
    return (
        f"ours at {n}^3: a squeeze {call * 1e3:.1f} ms CPU, its step loop alone "
        f"{loop * 1e3:.1f} ms (the rest, checks, model look-up and series: "
        f"{(call - loop) * 1e3:+.1f} ms); per step {loop / steps * 1e6:.0f} us, "
        f"{stats[1] / steps:.2f} V-cycles and {stats[4] / steps:.2f} explicit products A dv of "
        "the CG"
    )


def _exponent(particles: list[int], cost: list[float]) -> float:
    return float(np.polyfit(np.log(particles), np.log(cost), 1)[0])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.bench_mujoco")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    sizes = parser.parse_args(argv).sizes
    if importlib.util.find_spec("mujoco") is None:
        print("MuJoCo is not installed (pip install -e '.[bench]'): no comparison")
        return
    import mujoco

    sim_s = RAMP_S + HOLD_S
    print(
        f"damped 9 cm cube (5 N, D 20 N/cm, lambda 1 N·s/cm) on the table, palms ramped to "
        f"{PEAK_N:g} N in {RAMP_S:g} s and held {HOLD_S:g} s ({sim_s:g} s simulated by each); "
        f"ours at dt {OURS_DT_S * 1e3:g} ms (best of 3), MuJoCo {mujoco.__version__} flex at its "
        "largest warning-free dt (one run); CPU s per simulated s, same run:"
    )
    print(
        f"{'n':>4} {'particles':>9} {'ours':>8} {'MuJoCo':>9} {'MJ dt ms':>8} {'ratio':>8} "
        f"{'per step':>8} {'compression mm ours / MJ':>25}"
    )
    print("  (ratio: MuJoCo's CPU s per simulated s over ours; per step: its step over ours)")
    rows: list[tuple[int, float, float]] = []
    for n in sizes:
        ours_s, ours_c = ours_squeeze(n)
        mj = None
        for dt_s in MUJOCO_DT_S:
            mj = mujoco_squeeze(n, dt_s)
            if mj is not None:
                break
        ours_s = min(ours_s, ours_squeeze(n)[0], ours_squeeze(n)[0])
        if mj is None:
            print(f"{n:>3}^3 {n**3:>9} {ours_s / sim_s:>8.3f}   MuJoCo warned at every dt")
            continue
        mj_s, mj_c = mj
        rows.append((n**3, ours_s / sim_s, mj_s / sim_s))
        print(
            f"{n:>3}^3 {n**3:>9} {ours_s / sim_s:>8.3f} {mj_s / sim_s:>9.2f} {dt_s * 1e3:>8.2f} "
            f"{mj_s / ours_s:>7.0f}x {mj_s * dt_s / (ours_s * OURS_DT_S):>7.0f}x "
            f"{ours_c * 1e3:>12.2f} / {mj_c * 1e3:<.2f}",
            flush=True,
        )
    big = [r for r in rows if r[0] >= 8**3]
    if len(big) >= 2:
        particles = [r[0] for r in big]
        print(
            f"fitted exponent of CPU s per simulated s vs particle count, "
            f"{round(particles[0] ** (1 / 3))}^3..{round(particles[-1] ** (1 / 3))}^3: ours "
            f"{_exponent(particles, [r[1] for r in big]):.2f}, MuJoCo "
            f"{_exponent(particles, [r[2] for r in big]):.2f}"
        )
    if rows:
        print(ours_breakdown(round(rows[-1][0] ** (1 / 3))))
    at16 = [r for r in rows if r[0] == 16**3]
    if at16:
        print(f"target: >= 1000 x MuJoCo at 16^3: {at16[0][2] / at16[0][1]:.0f} x")


if __name__ == "__main__":
    main()
