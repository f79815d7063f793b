"""Our simulated lifting forces next to the seed paper's Table II.

Table II of Howard & Bekey reports, for the four bags of Table I, the lifting force from the
physical experiment (``lift_force_calculated_n``) and from the paper's own simulator
(``lift_force_simulation_n``); ``datasets/paper/table2.csv`` holds them. :func:`compare_with_paper`
puts a lift_results table (e.g. from ``deformctl lift datasets/paper/objects.csv --sim``) next to
them with relative differences. The differences are a measurement of how our simulator and lift
protocol relate to the paper's, not a target: the paper gives neither its friction coefficient
(the catalog assumes mu = 0.5) nor its lift profile.

Command line (what ``make reproduce`` calls)::

    python -m deformctl.repro.paper lift.parquet [table2.csv]

prints the comparison; ``table2.csv`` defaults to the bundled ``datasets/paper/table2.csv``.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from deformctl.errors import DeformctlError, InputDataError, MissingInputError
from deformctl.resources import dataset_path

#: The bundled Table II (``datasets/paper/table2.csv``, the package data ``deformctl.datasets``).
TABLE2_CSV = dataset_path("paper", "table2.csv")

TABLE2_COLUMNS = ("object_id", "lift_force_calculated_n", "lift_force_simulation_n")
COMPARISON_COLUMNS = (
    "object_id",
    "weight_n",
    "f_w_n",
    "lift_force_n",
    "lift_force_simulation_n",
    "rel_diff_simulation",
    "lift_force_calculated_n",
    "rel_diff_calculated",
)


def compare_with_paper(lift_results: pd.DataFrame, table2: pd.DataFrame) -> pd.DataFrame:
    """Our L_f beside Table II's simulation and physical ("calculated") lifting forces.

    Args:
        lift_results: a lift_results table (``object_id``, ``weight_n``, ``f_w_n``,
            ``lift_force_n``).
        table2: Table II (``object_id``, ``lift_force_calculated_n``,
            ``lift_force_simulation_n``; ``interior`` is kept when present).

    Returns:
        One row per object in both tables, in Table II's order: :data:`COMPARISON_COLUMNS`
        (plus ``interior`` after ``object_id`` when Table II has it), where
        ``rel_diff_X = lift_force_n / lift_force_X_n - 1``.

    Raises:
        InputDataError: a table without the needed columns, or no object in common.
    """
    for name, df, needed in (
        ("lift results", lift_results, ("object_id", "weight_n", "f_w_n", "lift_force_n")),
        ("Table II", table2, TABLE2_COLUMNS),
    ):
        missing = [c for c in needed if c not in df.columns]
        if missing:
            raise InputDataError(f"{name}: missing column(s) {', '.join(missing)}")
    ours = lift_results[["object_id", "weight_n", "f_w_n", "lift_force_n"]].astype(
        {"object_id": str}
    )
    keep = [
        "object_id",
        *(["interior"] if "interior" in table2.columns else []),
        *TABLE2_COLUMNS[1:],
    ]
    theirs = table2[keep].astype({"object_id": str})
    merged = theirs.merge(ours, on="object_id", how="inner", sort=False)
    if merged.empty:
        raise InputDataError(
            "no object of the lift results is in Table II "
            f"(lift results: {', '.join(ours['object_id'])}; Table II: "
            f"{', '.join(theirs['object_id'])})"
        )
    for col in ("simulation", "calculated"):
        merged[f"rel_diff_{col}"] = merged["lift_force_n"] / merged[f"lift_force_{col}_n"] - 1.0
    columns = list(COMPARISON_COLUMNS)
    if "interior" in merged.columns:
        columns.insert(1, "interior")
    return merged[columns].reset_index(drop=True)


def render(comparison: pd.DataFrame) -> str:
    """The comparison as a plain-text table (forces in N, differences in %)."""
    header = ["object", "W (N)", "F_w (N)", "L_f ours (N)", "paper sim (N)", "diff",
              "paper physical (N)", "diff"]  # fmt: skip
    rows = [header]
    for rec in comparison.to_dict("records"):
        name = str(rec["object_id"])
        if "interior" in rec:
            name += f" ({rec['interior']})"
        rows.append(
            [
                name,
                f"{rec['weight_n']:.2f}",
                f"{rec['f_w_n']:.2f}",
                f"{rec['lift_force_n']:.2f}",
                f"{rec['lift_force_simulation_n']:.2f}",
                f"{100 * rec['rel_diff_simulation']:+.0f} %",
                f"{rec['lift_force_calculated_n']:.2f}",
                f"{100 * rec['rel_diff_calculated']:+.0f} %",
            ]
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(header))]

    def line(cells: list[str]) -> str:
        pairs = enumerate(zip(cells, widths, strict=True))
        padded = [c.rjust(w) if i else c.ljust(w) for i, (c, w) in pairs]
        return "  ".join(padded).rstrip()

    return "\n".join(line(r) for r in rows)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m deformctl.repro.paper LIFT.parquet [TABLE2.csv]``: print the comparison.

    Returns:
        The exit code: 0, 2 for bad arguments, or the error's code (one line on stderr).
    """
    from deformctl.artifacts import read_table

    args = list(sys.argv[1:] if argv is None else argv)
    if not 1 <= len(args) <= 2 or args[0] in ("-h", "--help"):
        print("usage: python -m deformctl.repro.paper LIFT.parquet [TABLE2.csv]", file=sys.stderr)
        return 0 if args and args[0] in ("-h", "--help") else 2
    table2_path = Path(args[1]) if len(args) == 2 else TABLE2_CSV
    try:
        lift_results = read_table(args[0], "lift_results")
        if not table2_path.is_file():
            raise MissingInputError("no such file", path=table2_path)
        try:
            table2 = pd.read_csv(table2_path)
        except (ValueError, OSError) as err:
            raise InputDataError(f"not a readable CSV ({err})", path=table2_path) from None
        comparison = compare_with_paper(lift_results, table2)
    except DeformctlError as err:
        print(f"error: {err}", file=sys.stderr)
        return err.exit_code
    print(render(comparison))
    return 0


if __name__ == "__main__":  # pragma: no cover - exercised through subprocess in the tests
    sys.exit(main())
