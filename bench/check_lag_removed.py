"""What ``characterize`` should do after ``measure --lag-s`` took a lag out of the force
(``python -m bench.check_lag_removed [--draws N] [--seed S]``, about a minute per 100 draws).

Each draw is a Kelvin–Voigt ramp-and-hold (``deformctl.testing.shapes``' protocol: D 2–50 N/cm,
a 0.5–3 s ramp, a 0.8–2 s hold) whose force lags its position by a latency τ in 0.03–0.2 s, λ = 0
on 30 % of the draws, else λ/D in 0.005–0.5 s. It is written as a CSV export, read as
``measure --csv --lag-s τ`` (given: the rig's latency) and ``--lag-s auto`` (estimated) read it,
and fitted as ``characterize`` fits each log, and also as it would were the log's
``force_lag_source`` read differently:

* ``given/none fitted``: the rule (a given lag leaves no lag to fit);
* ``given/residual fitted``: a lag fitted after the given one, judged as an unknown lag;
* ``auto/withheld``: the rule (λ withheld after an estimate);
* ``auto/none fitted``: the estimate trusted as the latency;
* ``auto/residual fitted``: a lag fitted after the estimate, judged as an unknown lag.

Per line: the draws, those whose λ was reported, and those of them confidently wrong (λ off by
more than 20 %, or by more than 0.15 N·s/cm where λ = 0), then the rows whose D is off by more
than 5 %. ``auto`` counts only the draws whose estimate was shifted out (a lag estimated at or
below 0 is not).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from deformctl.artifacts import write_squeeze_log
from deformctl.characterize.stage import read_and_characterize
from deformctl.measure.csv.options import CsvOptions
from deformctl.measure.stage import read_recording
from deformctl.testing.shapes import _law_squeeze, _u

#: λ off by more than this is wrong ...
LAMBDA_TOL = 0.20
#: ... or by more than this where λ = 0, N·s/cm.
LAMBDA_FLOOR_NS_PER_CM = 0.15
D_TOL = 0.05
#: (label, the lag's option, the ``force_lag_source`` the log is given; None: as measure wrote)
VARIANTS = (
    ("given/none fitted", "given", None),
    ("given/residual fitted", "given", ""),
    ("auto/withheld", "auto", None),
    ("auto/none fitted", "auto", "given"),
    ("auto/residual fitted", "auto", ""),
)


def _csv(t: np.ndarray, f: np.ndarray, d: np.ndarray) -> bytes:
    lines = ["Time (s),Load (N),Compression (mm)"]
    lines += [f"{a:.6f},{b:.6f},{c * 1000.0:.6f}" for a, b, c in zip(t, f, d, strict=True)]
    return ("\n".join(lines) + "\n").encode()


def check(draws: int, seed: int) -> dict[str, Counter[str]]:
    """Run ``draws`` draws and count, per variant (module docstring)."""
    counts: dict[str, Counter[str]] = {label: Counter() for label, _, _ in VARIANTS}
    with tempfile.TemporaryDirectory(prefix="deformctl-lag-") as tmp:
        src, log = Path(tmp) / "export.csv", Path(tmp) / "log.mcap"
        for i in range(draws):
            rng = np.random.default_rng([seed, i])
            k = _u(rng, 200.0, 5000.0)
            lam = 0.0 if rng.uniform() < 0.3 else k * _u(rng, 0.005, 0.5)
            tau = _u(rng, 0.03, 0.2)
            s = _law_squeeze(
                rng, "kv", {"stiffness_n_per_m": k, "damping_ns_per_m": lam}, lag_s=tau
            )
            src.write_bytes(_csv(s.t, s.f, s.d))
            recs = {
                opt: read_recording(src, CsvOptions(lag_s=value), "obj")
                for opt, value in (("given", tau), ("auto", "auto"))
            }
            for label, opt, source in VARIANTS:
                rec = recs[opt]
                if rec.force_lag_s is None:
                    continue
                obj: dict[str, object] = {"object_id": "obj", "weight_n": 1.0, **rec.log_fields()}
                if source == "":
                    del obj["force_lag_s"], obj["force_lag_source"]
                elif source is not None:
                    obj["force_lag_source"] = source
                write_squeeze_log(log, [obj], rec.squeezes, provenance=None, force=True)
                (row,) = read_and_characterize(log).table.to_dict("records")
                c = counts[label]
                c["draws"] += 1
                lam_cm, got = lam / 100.0, float(row["damping_ns_per_cm"])
                if math.isfinite(got) and row["quality"] == "ok":
                    c["reported"] += 1
                    off = abs(got - lam_cm)
                    c["wrong"] += off > max(LAMBDA_TOL * lam_cm, LAMBDA_FLOOR_NS_PER_CM)
                c["d_wrong"] += not abs(row["deformability_n_per_cm"] / (k / 100.0) - 1) <= D_TOL
    return counts


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.check_lag_removed")
    parser.add_argument("--draws", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    counts = check(args.draws, args.seed)
    print("variant                 draws  λ reported (ok)  λ wrong  D off > 5 %")
    for label, c in counts.items():
        print(f"{label:22s} {c['draws']:6d} {c['reported']:16d} {c['wrong']:8d} {c['d_wrong']:12d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
