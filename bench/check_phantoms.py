"""Every silicone phantom recording through ``measure --csv FILE --weight-n 0.62`` and
``characterize`` with no other option (``make phantom-check``; about a minute for 38 files).

The recordings: ``/work/shared/data/phantom`` when present (38 files), else the three shipped in
``datasets/examples/phantom`` (CC BY 4.0; credit in their README); or the folder given as the
first argument. For each file it prints the law chosen, its stiffening parameter, D and the
force it is stated at, the file's own secant at that force (from its rows: the first loading row
at or above the force, interpolated, over its compression from the first row, which is the
contact point of a testing machine's export), their relative difference, and the quality flags.
It exits 1 unless every file is fitted (none refused), D is within 5 % of the file's secant, and
no file is flagged ``at_bound``.

``--aic`` adds, per file, the AIC of Hunt–Crossley with its exponent allowed up to 6 (instead
of 3) and of Hunt–Crossley within its bounds, each minus the exponential law's (positive: the
exponential law is the better by AIC), and that exponent: the evidence for the law that widens
the family (docs/explanation/materials.md).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.cli import app

SHARED = Path("/work/shared/data/phantom")
SHIPPED = Path(__file__).resolve().parents[1] / "datasets" / "examples" / "phantom"
PREAMBLE_ROWS = 7
REL_TOL = 0.05


def file_secant_n_per_cm(csv: Path, force_n: float) -> float:
    """The recording's own secant at ``force_n``, N/cm: the force over the compression (from the
    first row) at which its loading rows first reach the force (linear between two rows)."""
    rows = pd.read_csv(csv, skiprows=PREAMBLE_ROWS)
    d = rows["Compression (mm)"].to_numpy() / 10.0  # cm
    f = rows["Load (N)"].to_numpy()
    d, f = d - d[0], f[: int(np.argmax(f)) + 1]
    j = int(np.argmax(f >= force_n))
    if j == 0:
        return float("nan")
    d_at = float(np.interp(force_n, [f[j - 1], f[j]], [d[j - 1], d[j]]))
    return force_n / d_at


def wide_hunt_crossley(log: Path, n_max: float) -> tuple[float, float]:
    """AIC and exponent of Hunt–Crossley fitted to a squeeze log with ``n`` in ``[1, n_max]``."""
    from deformctl.characterize import materials
    from deformctl.characterize.material_options import MaterialOptions
    from deformctl.characterize.options import FitOptions
    from deformctl.characterize.stage import read_and_characterize

    saved = materials.HC_EXPONENT_BOUNDS
    materials.HC_EXPONENT_BOUNDS = (1.0, n_max)
    try:
        options = FitOptions(materials=MaterialOptions(model="hc"))
        row = read_and_characterize(str(log), options).table.iloc[0]
    finally:
        materials.HC_EXPONENT_BOUNDS = saved
    return float(row["hc_aic"]), float(row["hc_exponent"])


def check(csv: Path, work: Path, runner: CliRunner, aic: bool = False) -> dict[str, object]:
    """One file through both commands; its row of the report."""
    log, out = work / f"{csv.stem}.mcap", work / f"{csv.stem}.parquet"
    res = runner.invoke(app, ["measure", "csv", str(csv), "--weight-n", "0.62", "-o", str(log)])
    if res.exit_code != 0:
        return {"file": csv.stem, "refused": f"measure exit {res.exit_code}: {res.stderr.strip()}"}
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out)])
    if res.exit_code != 0:
        return {"file": csv.stem, "refused": f"characterize exit {res.exit_code}: {res.stderr}"}
    (row,) = read_table(out, "coefficients").to_dict("records")
    force = float(row["operating_force_n"])
    secant = file_secant_n_per_cm(csv, force)
    shape = {"hc": "hc_exponent", "exp": "exp_stiffening_per_cm"}.get(str(row["model"]))
    extra: dict[str, object] = {}
    if aic:
        wide_aic, wide_n = wide_hunt_crossley(log, 6.0)
        extra = {
            "aic_hc6_minus_exp": wide_aic - row["exp_aic"],
            "hc6_exponent": wide_n,
            "aic_hc3_minus_exp": row["hc_aic"] - row["exp_aic"],
        }
    return {
        "file": csv.stem,
        "refused": "",
        "model": row["model"],
        "shape": row[shape] if shape else float("nan"),
        "force_n": force,
        "d_n_per_cm": row["deformability_n_per_cm"],
        "file_secant_n_per_cm": secant,
        "rel_diff": row["deformability_n_per_cm"] / secant - 1.0,
        "at_bound": "at_bound" in str(row["quality"]).split(","),
        "quality": row["quality"],
        **extra,
    }


def main(argv: list[str]) -> int:
    aic = "--aic" in argv
    args = [a for a in argv if a != "--aic"]
    folder = Path(args[0]) if args else (SHARED if SHARED.is_dir() else SHIPPED)
    files = sorted(folder.glob("*.csv"))
    runner = CliRunner()
    with tempfile.TemporaryDirectory() as tmp:
        table = pd.DataFrame([check(f, Path(tmp), runner, aic) for f in files])
    with pd.option_context("display.width", 200, "display.max_rows", None):
        print(table.drop(columns=["quality"], errors="ignore").to_string(index=False))
    refused = int((table["refused"] != "").sum())
    fitted = table[table["refused"] == ""]
    off = int((fitted["rel_diff"].abs() > REL_TOL).sum()) if len(fitted) else 0
    bound = int(fitted["at_bound"].sum()) if len(fitted) else 0
    worst = float(fitted["rel_diff"].abs().max()) if len(fitted) else float("nan")
    models = ", ".join(f"{m} {n}" for m, n in fitted["model"].value_counts().items())
    print(
        f"{len(files)} files from {folder}: {refused} refused, {off} with D off the file's secant "
        f"by more than {100 * REL_TOL:g} % (largest {100 * worst:.2f} %), {bound} at_bound; "
        f"laws: {models}"
    )
    if aic and len(fitted):
        for col in ("aic_hc6_minus_exp", "aic_hc3_minus_exp", "hc6_exponent"):
            print(f"{col}: {fitted[col].min():.4g} to {fitted[col].max():.4g}")
    return 0 if len(files) and refused == 0 and off == 0 and bound == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
