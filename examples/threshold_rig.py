#!/usr/bin/env python3
"""A stand-in rig for ``deformctl lift --rig``: lifts when the grip beats a threshold force.

It follows the rig protocol (docs/rig-protocol.md): one JSON request on stdin, one JSON answer
on stdout, notes on stderr; to the handshake it states ``--max-force-n`` (default 500 N).
Instead of a robot it pretends each object needs ``F_w + extra`` newtons, where
``F_w = W / (2 mu)`` comes from the request and ``extra`` (``--extra-n``, default 0.5 N) plays the
part of the deformation surplus F_d. So
``deformctl lift`` should report ``f_d_n`` close to ``extra`` (within the search tolerance).
With ``--lift-force-from TABLE`` (a lift results table, e.g. the demo's of
``examples/synthetic_index.py``) each object needs that table's ``lift_force_n`` instead.

Usage (deformctl runs it once per attempt):
    deformctl lift datasets/paper/objects.csv --rig "python3 examples/threshold_rig.py" \\
        -o lift.parquet --log lift.mcap
    deformctl lift demo/objects.csv --objects P01 \\
        --rig "python3 examples/threshold_rig.py --lift-force-from demo/lift.parquet" \\
        --start-model demo/model.skops --coefficients demo/coefficients.parquet -o seeded.parquet

Replace the body of ``grip_and_lift`` with your robot driver.
"""

import argparse
import json
import sys


def grip_and_lift(
    request: dict, extra_n: float, needs_n: float | None = None
) -> tuple[bool, float]:
    """Pretend to grip with request['grip_force_n'] and lift; return (lifted, slip_m).

    The object needs ``needs_n`` newtons when given, else F_w + ``extra_n``.
    """
    f_w_n = request["weight_n"] / (2.0 * request["friction_mu"])
    lifted = request["grip_force_n"] >= (f_w_n + extra_n if needs_n is None else needs_n)
    return lifted, 0.0 if lifted else 0.02  # a slipping object stays 2 cm behind the palms


def lift_force_from(path: str, object_id: str) -> float:
    """The ``lift_force_n`` of ``object_id`` in a lift results table (Parquet)."""
    import pyarrow.parquet as pq  # only for --lift-force-from

    table = pq.read_table(path, columns=["object_id", "lift_force_n"]).to_pydict()
    return float(table["lift_force_n"][table["object_id"].index(object_id)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--extra-n", type=float, default=0.5, help="F_d the object needs, N")
    parser.add_argument("--lift-force-from", metavar="TABLE", help="each object needs its L_f here")
    parser.add_argument(
        "--max-force-n", type=float, default=500.0, help="the maximum force it states, N"
    )
    args = parser.parse_args()
    request = json.load(sys.stdin)
    if request.get("handshake"):  # rig protocol 2: state the maximum force, do not move
        print(json.dumps({"protocol_version": 2, "max_force_n": args.max_force_n}))
        return
    needs_n = None
    if args.lift_force_from is not None:
        needs_n = lift_force_from(args.lift_force_from, request["object_id"])
    lifted, slip_m = grip_and_lift(request, args.extra_n, needs_n)
    print(
        f"object {request['object_id']} attempt {request['attempt_index']}: "
        f"{request['grip_force_n']:.4g} N -> {'lifted' if lifted else 'slipped'}",
        file=sys.stderr,
    )
    print(json.dumps({"lifted": lifted, "slip_m": slip_m, "message": "threshold stand-in"}))


if __name__ == "__main__":
    main()
