"""What the simulated lifting force depends on: the evidence behind the grip model's form.

``python -m deformctl.repro.grip_study [--jobs 2]`` (``make grip-study``, 2-4 minutes on 2 cores)
simulates, with the default ``lift --sim`` preset and the ``refine`` search to 0.2 %:

1. **Friction.** Objects at μ = 0.2, 0.25, 0.5 and 1.0: L_f / F_w per μ and its spread. If the
   spread is within the search tolerance, μ changes L_f only through F_w = W / (2 μ).
2. **Two groups.** Object pairs with equal natural frequency ω_n = √(D/m) and damping ratio
   ζ = λ / (2 √(D m)) but weights 16x apart (W, D and λ all scaled by 4 or 1/4, which keeps both):
   L_f / F_w of the pair. If equal, W and D matter only through ω_n and ζ.
3. **Size.** The same (W, D, λ, μ) in four box sizes (10-20 cm): the spread of L_f / F_w, the
   noise floor of a model that does not know the size.
4. **The landscape.** L_f / F_w over ζ at three ω_n (a 12 x 12 x 10 cm box, μ = 1).

Each table prints as it is simulated; nothing is written. The numbers are quoted in
docs/explanation/model.md.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

from deformctl.units import GRAVITY_M_S2

#: Relative bracket width of each search (finer than ``lift``'s 0.5 %).
SEARCH_TOLERANCE = 0.002
BOX_CM = (12.0, 12.0, 10.0)


@dataclass(frozen=True)
class Case:
    """One object to simulate: W (N), D (N/cm), λ (N·s/cm), μ, box size (cm); and its law's
    parameters (:class:`deformctl.sim.ObjectSpec`'s): the stiffness exponent n (Hunt–Crossley
    above 1, D and λ then stated at F_w), the arm spring k2 (N/cm) and relaxation time τ (s) of a
    standard linear solid (none: k2 = 0)."""

    weight_n: float
    deformability_n_per_cm: float
    damping_ns_per_cm: float
    friction_mu: float
    size_cm: tuple[float, float, float] = BOX_CM
    stiffness_exponent: float = 1.0
    arm_stiffness_n_per_cm: float = 0.0
    relaxation_time_s: float = math.inf


def lift_ratio(case: Case) -> float:
    """L_f / F_w of ``case`` under the default preset (the refine search to 0.2 %)."""
    from deformctl.lift.search import find_min_lift_force
    from deformctl.presets import sim_preset
    from deformctl.sim import ObjectSpec

    preset = sim_preset()
    spec = ObjectSpec(
        "study",
        case.size_cm,
        case.weight_n,
        case.friction_mu,
        case.deformability_n_per_cm,
        case.damping_ns_per_cm,
        case.stiffness_exponent,
        case.arm_stiffness_n_per_cm,
        case.relaxation_time_s,
    )
    result = find_min_lift_force(
        lambda force_n, _i: preset.lift_attempt(spec, force_n),
        weight_n=spec.weight_n,
        friction_mu=spec.friction_mu,
        tolerance_rel=SEARCH_TOLERANCE,
    )
    return float(result.lift_force_n / result.f_w_n)


def critical_damping_ns_per_cm(weight_n: float, deformability_n_per_cm: float) -> float:
    """λ of ζ = 1: 2 √(D m), in N·s/cm."""
    return 2.0 * math.sqrt(deformability_n_per_cm * 100.0 * weight_n / GRAVITY_M_S2) / 100.0


def omega(weight_n: float, deformability_n_per_cm: float) -> float:
    return math.sqrt(deformability_n_per_cm * 100.0 * GRAVITY_M_S2 / weight_n)


#: (W, D, ζ): objects of the friction and size studies (grippable at μ = 0.2 in a 12 cm box).
BASE = ((2.0, 8.0, 0.0), (5.0, 20.0, 0.3), (20.0, 40.0, 0.1), (20.0, 40.0, 1.0), (30.0, 60.0, 3.0))
FRICTIONS = (0.2, 0.25, 0.5, 1.0)
SIZES = ((10.0, 10.0, 8.0), (20.0, 20.0, 20.0), (10.0, 20.0, 20.0), (20.0, 10.0, 8.0))
#: (W, D, ζ) of the pairs: W, D, λ times 4 keeps ω_n and ζ.
PAIRS = ((0.6, 6.0, 0.0), (1.0, 10.0, 0.2), (2.0, 5.0, 0.6), (3.0, 12.0, 2.0), (4.0, 15.0, 0.05))
#: (ω_n rad/s, W N) of the landscape rows; D follows from ω_n and W.
LANDSCAPE = ((15.0, 80.0), (60.0, 10.0), (240.0, 0.6))
LANDSCAPE_ZETA = (0.0, 0.05, 0.2, 0.5, 1.0, 2.0, 5.0)


def _case(w: float, d: float, zeta: float, mu: float, size: Sequence[float] = BOX_CM) -> Case:
    lam = zeta * critical_damping_ns_per_cm(w, d)
    return Case(w, d, lam, mu, (float(size[0]), float(size[1]), float(size[2])))


def _run(cases: list[Case], jobs: int) -> list[float]:
    if jobs <= 1:
        return [lift_ratio(c) for c in cases]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(lift_ratio, cases))


def _spread(values: Sequence[float]) -> float:
    return max(values) / min(values) - 1.0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m deformctl.repro.grip_study")
    parser.add_argument("--jobs", type=int, default=2, help="Processes (default 2).")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()

    print("1. friction: L_f / F_w of one object at each μ (12 x 12 x 10 cm)")
    cases = [_case(w, d, z, mu) for w, d, z in BASE for mu in FRICTIONS]
    ratios = _run(cases, args.jobs)
    print(
        f"{'W N':>6} {'D N/cm':>7} {'zeta':>5} "
        + " ".join(f"mu {m:<4g}" for m in FRICTIONS)
        + "  spread"
    )
    worst = 0.0
    for i, (w, d, z) in enumerate(BASE):
        row = ratios[i * len(FRICTIONS) : (i + 1) * len(FRICTIONS)]
        worst = max(worst, _spread(row))
        print(
            f"{w:>6g} {d:>7g} {z:>5g} "
            + " ".join(f"{r:>7.4f}" for r in row)
            + f"  {_spread(row):6.2%}"
        )
    print(
        f"worst spread over μ: {worst:.2%} (search tolerance {SEARCH_TOLERANCE:.1%})\n", flush=True
    )

    print("2. two groups: W, D, λ x 4 keeps ω_n and ζ (μ = 0.5, 12 x 12 x 10 cm)")
    cases = [c for w, d, z in PAIRS for c in (_case(w, d, z, 0.5), _case(4 * w, 4 * d, z, 0.5))]
    ratios = _run(cases, args.jobs)
    print(f"{'W N':>6} {'D N/cm':>7} {'omega':>6} {'zeta':>5} {'ratio':>7} {'ratio x4':>8}  diff")
    worst = 0.0
    for i, (w, d, z) in enumerate(PAIRS):
        a, b = ratios[2 * i], ratios[2 * i + 1]
        worst = max(worst, abs(b / a - 1))
        print(f"{w:>6g} {d:>7g} {omega(w, d):>6.1f} {z:>5g} {a:>7.4f} {b:>8.4f}  {b / a - 1:+.2%}")
    print(f"worst pair difference: {worst:.2%}\n", flush=True)

    print("3. size: the same object in four boxes (μ = 0.5)")
    cases = [_case(w, d, z, 0.5, s) for w, d, z in BASE for s in SIZES]
    ratios = _run(cases, args.jobs)
    labels = " ".join(f"{'x'.join(f'{v:g}' for v in s):>9}" for s in SIZES)
    print(f"{'W N':>6} {'D N/cm':>7} {'zeta':>5} {labels}  spread")
    worst = 0.0
    for i, (w, d, z) in enumerate(BASE):
        row = ratios[i * len(SIZES) : (i + 1) * len(SIZES)]
        worst = max(worst, _spread(row))
        print(
            f"{w:>6g} {d:>7g} {z:>5g} "
            + " ".join(f"{r:>9.4f}" for r in row)
            + f"  {_spread(row):6.2%}"
        )
    print(f"worst spread over sizes: {worst:.2%}\n", flush=True)

    print("4. landscape: L_f / F_w over ζ at three ω_n (μ = 1, 12 x 12 x 10 cm)")
    cases = []
    for om, w in LANDSCAPE:
        d = om * om * (w / GRAVITY_M_S2) / 100.0
        cases += [_case(w, d, z, 1.0) for z in LANDSCAPE_ZETA]
    ratios = _run(cases, args.jobs)
    print(f"{'omega':>6} {'W N':>5} " + " ".join(f"z {z:<5g}" for z in LANDSCAPE_ZETA))
    for i, (om, w) in enumerate(LANDSCAPE):
        row = ratios[i * len(LANDSCAPE_ZETA) : (i + 1) * len(LANDSCAPE_ZETA)]
        print(f"{om:>6g} {w:>5g} " + " ".join(f"{r:>7.4f}" for r in row))
    print(f"\n{time.perf_counter() - t0:.0f} s wall")
    return 0


if __name__ == "__main__":
    sys.exit(main())
