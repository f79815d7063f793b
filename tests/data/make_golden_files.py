"""Write the tiny golden artifacts of ``tests/data/`` and their human-readable expectations.

Run from the repository root after an intended format change, and commit the files with it::

    .venv/bin/python tests/data/make_golden_files.py

Each artifact (a squeeze log, a lift log, one table of every kind) sits next to
``<name>.expected.json``: what every reader must return for it (``tests/artifacts/
test_golden_files.py``). The files are written with the public writers from fixed inputs, so
they change only when a writer or a format changes.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))  # the checkout, for tests._helpers

from deformctl.artifacts import (  # noqa: E402
    Provenance,
    read_lift_log,
    read_squeeze_log,
    read_table,
    write_lift_log,
    write_squeeze_log,
    write_table,
)
from tests._helpers.builders import make_attempts, make_squeezes, make_tables  # noqa: E402

OBJECTS = [
    {"object_id": "A", "weight_n": 0.7, "size_x_cm": 17.8, "friction_mu": 0.5},
    {"object_id": "B", "weight_n": 1.4, "position_rate_hz": 1000.0},
]


def plain(value: Any) -> Any:
    """JSON-friendly: numpy arrays as lists, NaN as None."""
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, list):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    return value


def squeeze_expectation(path: Path) -> dict[str, Any]:
    """What the squeeze-log reader returns for ``path``."""
    objects, squeezes = read_squeeze_log(path)
    fields = ("time_s", "force_n", "compression_m", "commanded_force_n")
    return {
        "kind": "squeeze_log",
        "objects": objects,
        "squeezes": [
            {
                "object_id": s.object_id,
                "squeeze_index": s.squeeze_index,
                **{f: plain(getattr(s, f)) for f in (*fields, "palm_left_x_m", "palm_right_x_m")},
            }
            for s in squeezes
        ],
    }


def lift_expectation(path: Path) -> dict[str, Any]:
    """What the lift-log reader returns for ``path``."""
    objects, attempts = read_lift_log(path)
    out = []
    for a in attempts:
        series = a.outcome.series
        out.append(
            {
                "object_id": a.object_id,
                "attempt_index": a.attempt_index,
                "grip_force_n": a.outcome.grip_force_n,
                "lifted": a.outcome.lifted,
                "slip_m": plain(a.outcome.slip_m),
                "details": a.outcome.details,
                "series": None if series is None else plain(vars(series)),
            }
        )
    return {"kind": "lift_log", "objects": objects, "attempts": out}


def table_expectation(path: Path, kind: str) -> dict[str, Any]:
    """What the table reader returns for ``path``: kind, version, units, rows, provenance."""
    df = read_table(path, kind)
    return {
        "kind": df.attrs["kind"],
        "schema_version": df.attrs["schema_version"],
        "columns": list(df.columns),
        "units": df.attrs["units"],
        "rows": plain(df.to_dict("records")),
        "provenance": df.attrs["provenance"].to_dict(),
    }


def main() -> None:
    """Write every golden file and its expectation into ``tests/data/`` (run from the repo root)."""
    # The same provenance in every file: a relative input path and a fixed command line.
    provenance = Provenance.from_invocation(
        ["datasets/paper/objects.csv"],
        seed=7,
        settings={"dt_s": 1e-4, "note": "tests/data golden file"},
        argv=["deformctl", "measure", "--sim", "datasets/paper/objects.csv"],
    )
    written = []
    log = HERE / "squeeze_2x2.mcap"
    write_squeeze_log(log, OBJECTS, make_squeezes(), provenance=provenance, force=True)
    written.append((log, {**squeeze_expectation(log), "provenance": provenance.to_dict()}))
    log = HERE / "lift_2.mcap"
    write_lift_log(log, OBJECTS[:1], make_attempts(), provenance=provenance, force=True)
    written.append((log, {**lift_expectation(log), "provenance": provenance.to_dict()}))
    for kind, frame in make_tables().items():
        path = HERE / f"{kind}.parquet"
        write_table(frame, path, kind, provenance=provenance, force=True)
        written.append((path, table_expectation(path, kind)))
    for path, expected in written:
        text = json.dumps(expected, indent=1, sort_keys=True, allow_nan=False) + "\n"
        path.with_name(path.stem + ".expected.json").write_text(text, encoding="utf-8")
        print(f"wrote {path.relative_to(HERE.parent.parent)} and its .expected.json")


if __name__ == "__main__":
    main()
