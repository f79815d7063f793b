"""Write a synthetic coefficients table and lift-results table, so `table`/`train`/`predict` run
without the simulator.

The objects are the paper's population (:func:`deformctl.population.make_population`: 73 objects,
W 20-60 N, D 30-50 N/cm, λ 0-13 N·s/cm, μ = 0.5). Their "measured" coefficients are the catalog's
true material values, and their minimum lifting force is not simulated but given by a smooth
formula shaped like the physics (the rigid-object force F_w = W / (2 μ) plus a surplus that grows
with W / D and shrinks with damping)::

    L_f = F_w * (1 + 0.6 * W / D * (0.5 + 0.5 * exp(-λ / 4)))

times a seeded ±1 % noise standing in for the tolerance of the lifting-force search. The numbers
are therefore illustrative only; `make reproduce` runs the real pipeline.

Usage::

    python examples/synthetic_index.py OUTDIR [--n 73] [--seed 0] [--force]

writes ``OUTDIR/objects.csv`` (the catalog), ``OUTDIR/coefficients.parquet`` and
``OUTDIR/lift.parquet``; then::

    deformctl table OUTDIR/coefficients.parquet OUTDIR/lift.parquet -o OUTDIR/index.parquet
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from deformctl.artifacts import Provenance, write_catalog, write_table
from deformctl.physics import rigid_grip_force_n
from deformctl.population import make_population

#: Relative amplitude of the uniform noise on L_f.
NOISE_REL = 0.01


def synthetic_tables(n: int = 73, seed: int = 0) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """``(catalog, coefficients, lift_results)`` for ``n`` objects of the paper's population.

    Returns:
        Three frames matching ``schemas/catalog.columns.json``,
        ``schemas/coefficients.columns.json`` and ``schemas/lift_results.columns.json``, one row
        per object.
    """
    cat = make_population(n, seed=seed)
    w = cat["weight_n"].to_numpy()
    d = cat["material_stiffness_n_per_cm"].to_numpy()
    lam = cat["material_damping_ns_per_cm"].to_numpy()
    mu = cat["friction_mu"].to_numpy()
    f_w = rigid_grip_force_n(w, mu)
    lift = f_w * (1.0 + 0.6 * w / d * (0.5 + 0.5 * np.exp(-lam / 4.0)))
    lift *= 1.0 + NOISE_REL * np.random.default_rng(seed + 1000).uniform(-1.0, 1.0, n)
    coefficients = pd.DataFrame(
        {
            "object_id": cat["object_id"],
            "deformability_n_per_cm": d,
            "damping_ns_per_cm": lam,
            "method": "synthetic",
        }
    )
    lift_results = pd.DataFrame(
        {
            "object_id": cat["object_id"],
            "weight_n": w,
            "friction_mu": mu,
            "f_w_n": f_w,
            "lift_force_n": lift,
            "f_d_n": lift - f_w,
            "attempts": 0,
            "converged": True,
            "protocol": "synthetic",
        }
    )
    return cat, coefficients, lift_results


def main(argv: list[str] | None = None) -> int:
    """Write the two tables into the directory given on the command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--n", type=int, default=73)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--force", action="store_true")
    args = parser.parse_args(argv)
    args.outdir.mkdir(parents=True, exist_ok=True)
    catalog, coefficients, lift_results = synthetic_tables(args.n, args.seed)
    write_catalog(catalog, args.outdir / "objects.csv", force=args.force)
    print(f"wrote {args.outdir / 'objects.csv'}: {len(catalog)} objects", file=sys.stderr)
    prov = Provenance.from_invocation(
        seed=args.seed, settings={"n": args.n, "source": "examples/synthetic_index.py"}
    )
    for frame, name, kind in (
        (coefficients, "coefficients.parquet", "coefficients"),
        (lift_results, "lift.parquet", "lift_results"),
    ):
        write_table(frame, args.outdir / name, kind, provenance=prov, force=args.force)
        print(f"wrote {args.outdir / name}: {len(frame)} objects", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
