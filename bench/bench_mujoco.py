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

The squeeze is the one the simulator's benchmarks have long timed (ramp 0.25 s, hold 0.75 s: 1 s
simulated); a short one (ramp 0.1 s, hold 0.1 s) is timed too. Both engines run the whole of
each: MuJoCo's 16^3 squeeze takes about 2.5 CPU minutes.

Prints, per size: each engine's CPU seconds per simulated second on each squeeze (both run on
one thread; the process's CPU time is what a shared machine's load inflates least, and on an
idle machine it is the wall time), ours best of 3, MuJoCo's one run (its steps are
~100-1,000 x dearer, so one run of hundreds of steps is its own average); their ratio, per
simulated second and per step; each engine's compression at the end of the squeeze (the two
model the same squeeze, not the same numbers); the fitted exponent of the cost against the
particle count; MuJoCo's CPU time per step in the ramp and in the hold at the largest size (about
the same: its step's cost does not depend on the phase); and where our call spends its time there
(:func:`ours_breakdown`: the step loop against the whole call, and per step in the ramp and in
the hold the CPU time, the CG's V-cycles and products). Our steps cost more in the ramp than in
the hold, so the ratio on the short squeeze, mostly ramp, is lower.
``python -m bench.bench_mujoco --sizes 5 8 11 16 21`` chooses the sizes (default
:data:`SIZES`). Without MuJoCo (``pip install -e '.[bench]'``, which ``make bench`` does) it says
so and returns.
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from typing import NamedTuple

import numpy as np

from deformctl.arraytypes import FloatArray
from deformctl.sim import ObjectSpec, SimSettings, squeeze
from deformctl.sim.engine import build_model, run_model
from deformctl.sim.hunt_crossley import implicit_reference_m

#: the damped cube: 9 cm, 5 N, mu 0.5, D 20 N/cm, lambda 1 N·s/cm
DAMPED = ObjectSpec("damped", (9.0, 9.0, 9.0), 5.0, 0.5, 20.0, 1.0)
PEAK_N = 10.0
#: the squeeze compared: the force ramp and the hold at the peak, s (1 s simulated)
RAMP_S = 0.25
HOLD_S = 0.75
#: a short squeeze also timed (0.2 s simulated), ramp and hold, s
SHORT_RAMP_S = 0.1
SHORT_HOLD_S = 0.1
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


def mujoco_squeeze(
    n: int,
    dt_s: float,
    ramp_s: float = RAMP_S,
    hold_s: float = HOLD_S,
    phases: list[float] | None = None,
) -> tuple[float, float] | None:
    """MuJoCo's squeeze at ``n``^3 and step ``dt_s`` (ramp ``ramp_s``, hold ``hold_s``): (CPU s,
    compression m at the end), or None when MuJoCo warned (unstable, ill-conditioned) during it.
    ``phases``, when given, receives the CPU s of the ramp's steps and of the hold's."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(mjcf(n, dt_s))
    data = mujoco.MjData(model)
    left, right = (int(model.jnt_qposadr[j]) for j in range(2))
    steps = round((ramp_s + hold_s) / dt_s)
    ramp_steps = round(ramp_s / dt_s)
    t0 = time.process_time()
    t_ramp = t0
    for i in range(steps):
        if i == ramp_steps:
            t_ramp = time.process_time()
        data.ctrl[:] = PEAK_N * min(data.time / ramp_s, 1.0)
        mujoco.mj_step(model, data)
        if i % 20 == 0 and _warned(data):
            return None
    t1 = time.process_time()
    if _warned(data) or not np.isfinite(data.qpos).all():
        return None
    if phases is not None:
        phases[:] = [t_ramp - t0, t1 - t_ramp]
    return t1 - t0, float(data.qpos[left] - data.qpos[right])


def mujoco_largest_dt(
    n: int, ramp_s: float, hold_s: float, first: int = 0, phases: list[float] | None = None
) -> tuple[int, float, float] | None:
    """MuJoCo's squeeze at the largest of ``MUJOCO_DT_S[first:]`` at which it does not warn:
    (the step's index, CPU s, compression m), or None when it warns at every one."""
    for i in range(first, len(MUJOCO_DT_S)):
        run = mujoco_squeeze(n, MUJOCO_DT_S[i], ramp_s, hold_s, phases)
        if run is not None:
            return i, run[0], run[1]
    return None


def ours_squeeze(n: int, ramp_s: float = RAMP_S, hold_s: float = HOLD_S) -> tuple[float, float]:
    """Our squeeze at ``n``^3 (model built and kernels loaded first): (CPU s, compression m)."""
    settings = SimSettings(particles_per_side=n, dt_s=OURS_DT_S)
    run = lambda: squeeze(  # noqa: E731
        DAMPED, peak_force_n=PEAK_N, ramp_s=ramp_s, hold_s=hold_s, settings=settings
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
    look-up and series), and per step in the ramp and in the hold: CPU time, the CG's V-cycles
    and its explicit products ``A dv`` (the others are carried from step to step). The hold's
    figures are the whole loop's less the ramp's alone (the run is deterministic)."""
    settings = SimSettings(particles_per_side=n, dt_s=OURS_DT_S)
    model = build_model(
        DAMPED, settings, gripped=True, reference_m=implicit_reference_m(DAMPED, PEAK_N)
    )
    steps = round((RAMP_S + HOLD_S) / OURS_DT_S)
    ramp_steps = round(RAMP_S / OURS_DT_S)
    force = PEAK_N * np.clip(np.arange(steps + 1) * OURS_DT_S / RAMP_S, 0.0, 1.0)

    def loop(n_steps: int) -> tuple[float, FloatArray]:
        model.solver_stats[:] = 0
        t0 = time.process_time()
        run_model(model, force[: n_steps + 1], np.zeros(n_steps + 1))
        return time.process_time() - t0, model.solver_stats.astype(float)

    call = whole = ramp = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        squeeze(DAMPED, peak_force_n=PEAK_N, ramp_s=RAMP_S, hold_s=HOLD_S, settings=settings)
        call = min(call, time.process_time() - t0)
        whole_s, whole_stats = loop(steps)
        ramp_s, ramp_stats = loop(ramp_steps)
        whole, ramp = min(whole, whole_s), min(ramp, ramp_s)
    hold_steps = steps - ramp_steps
    hold_stats = whole_stats - ramp_stats

    def phase(cpu_s: float, stats: FloatArray, n_steps: int) -> str:
        return (
            f"{cpu_s / n_steps * 1e6:.0f} us, {stats[1] / n_steps:.3f} V-cycles and "
            f"{stats[4] / n_steps:.2f} products"
        )

    return (
        f"ours at {n}^3: a squeeze {call * 1e3:.1f} ms CPU, its step loop alone "
        f"{whole * 1e3:.1f} ms (the rest, checks, model look-up and series: "
        f"{(call - whole) * 1e3:+.1f} ms); per step in the ramp "
        f"{phase(ramp, ramp_stats, ramp_steps)}, in the hold "
        f"{phase(whole - ramp, hold_stats, hold_steps)} (explicit products A dv of the CG)"
    )


def _exponent(particles: list[int], cost: list[float]) -> float:
    return float(np.polyfit(np.log(particles), np.log(cost), 1)[0])


class _Row(NamedTuple):
    """One size's CPU s per simulated s: ours and MuJoCo's on the squeeze and the short one."""

    particles: int
    ours: float
    mujoco: float
    ours_short: float
    mujoco_short: float


def _best_ours(n: int, ramp_s: float, hold_s: float) -> tuple[float, float]:
    """Our best of 3 at ``n``^3: (CPU s, compression m)."""
    runs = [ours_squeeze(n, ramp_s, hold_s) for _ in range(3)]
    return min(r[0] for r in runs), runs[0][1]


def _size_row(n: int) -> tuple[str, _Row | None, str]:
    """One size: the printed row, its costs (None when MuJoCo warned at every step) and MuJoCo's
    CPU time per step in the squeeze's ramp and in its hold. MuJoCo's step is searched on the
    short squeeze first (cheaper), then the squeeze runs at the largest step at which it does
    not warn either."""
    sim_s = RAMP_S + HOLD_S
    short_s = SHORT_RAMP_S + SHORT_HOLD_S
    ours_short, _ = _best_ours(n, SHORT_RAMP_S, SHORT_HOLD_S)
    mj_short = mujoco_largest_dt(n, SHORT_RAMP_S, SHORT_HOLD_S)
    phases: list[float] = []
    mj = mujoco_largest_dt(n, RAMP_S, HOLD_S, mj_short[0] if mj_short else 0, phases)
    ours, ours_c = _best_ours(n, RAMP_S, HOLD_S)
    if mj is None or mj_short is None:
        return f"{n:>3}^3 {n**3:>9} {ours / sim_s:>7.3f}   MuJoCo warned at every dt", None, ""
    dt_s, dt_short = MUJOCO_DT_S[mj[0]], MUJOCO_DT_S[mj_short[0]]
    ramp_steps = round(RAMP_S / dt_s)
    per_step = (
        f"MuJoCo at {n}^3 per step: {phases[0] / ramp_steps * 1e3:.1f} ms CPU in the ramp, "
        f"{phases[1] / (round((RAMP_S + HOLD_S) / dt_s) - ramp_steps) * 1e3:.1f} ms in the hold"
    )
    row = _Row(n**3, ours / sim_s, mj[1] / sim_s, ours_short / short_s, mj_short[1] / short_s)
    text = (
        f"{n:>3}^3 {n**3:>9} {row.ours:>7.3f} {row.mujoco:>8.2f} {dt_s * 1e3:>6.2f} "
        f"{row.mujoco / row.ours:>6.0f}x {row.mujoco * dt_s / (row.ours * OURS_DT_S):>6.0f}x"
        f"   {row.ours_short:>7.3f} {row.mujoco_short:>8.2f} {dt_short * 1e3:>6.2f} "
        f"{row.mujoco_short / row.ours_short:>6.0f}x   {ours_c * 1e3:>6.2f} / {mj[2] * 1e3:<.2f}"
    )
    return text, row, per_step


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.bench_mujoco")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    sizes = parser.parse_args(argv).sizes
    if importlib.util.find_spec("mujoco") is None:
        print("MuJoCo is not installed (pip install -e '.[bench]'): no comparison")
        return
    import mujoco

    print(
        f"damped 9 cm cube (5 N, D 20 N/cm, lambda 1 N·s/cm) on the table, palms ramped to "
        f"{PEAK_N:g} N in {RAMP_S:g} s and held {HOLD_S:g} s ({RAMP_S + HOLD_S:g} s simulated by "
        f"each), and a short squeeze ({SHORT_RAMP_S:g} s + {SHORT_HOLD_S:g} s); ours at dt "
        f"{OURS_DT_S * 1e3:g} ms (best of 3), MuJoCo {mujoco.__version__} flex at its largest "
        "warning-free dt (one run each); CPU s per simulated s, same run:"
    )
    print(f"{'':>14}{'squeeze, 1 s':-^39}   {'short, 0.2 s':-^32}   compression")
    print(
        f"{'n':>4} {'particles':>9} {'ours':>7} {'MuJoCo':>8} {'MJ dt':>6} {'ratio':>7} "
        f"{'/ step':>7}   {'ours':>7} {'MuJoCo':>8} {'MJ dt':>6} {'ratio':>7}   mm ours / MJ"
    )
    print(
        "  (ratio: MuJoCo's CPU s per simulated s over ours; / step: its step over ours; "
        "MJ dt in ms)"
    )
    rows: list[_Row] = []
    per_step = ""
    for n in sizes:
        text, row, per_step = _size_row(n)
        print(text, flush=True)
        if row is not None:
            rows.append(row)
    big = [r for r in rows if r.particles >= 8**3]
    if len(big) >= 2:
        p = [r.particles for r in big]
        fit = [_exponent(p, [getattr(r, f) for r in big]) for f in _Row._fields[1:]]
        print(
            f"fitted exponent of CPU s per simulated s vs particle count, "
            f"{round(p[0] ** (1 / 3))}^3..{round(p[-1] ** (1 / 3))}^3, squeeze (short one): ours "
            f"{fit[0]:.2f} ({fit[2]:.2f}), MuJoCo {fit[1]:.2f} ({fit[3]:.2f})"
        )
    if per_step:
        print(per_step)
    if rows:
        print(ours_breakdown(round(rows[-1].particles ** (1 / 3))))
    at16 = [r for r in rows if r.particles == 16**3]
    if at16:
        r = at16[0]
        print(
            f"target: >= 1000 x MuJoCo at 16^3: {r.mujoco / r.ours:.0f} x on the squeeze "
            f"({r.mujoco_short / r.ours_short:.0f} x on the short one)"
        )


if __name__ == "__main__":
    main()
