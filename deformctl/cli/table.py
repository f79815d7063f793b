"""``deformctl table``: build the index table (2 inputs, ``-o``) or look it up (1, ``--lookup``).

The command has two modes, told apart by the arguments:

* **build**: ``table COEFFICIENTS LIFT -o index.parquet`` joins the two tables on ``object_id``
  (:func:`deformctl.table.build_index_table`) and writes an ``index_table``.
* **lookup**: ``table index.parquet --lookup weight_n=..,deformability_n_per_cm=..,
  damping_ns_per_cm=..`` prints the nearest entry and its distance in standardized units
  (:func:`deformctl.table.lookup`), and with ``--interpolate K`` an inverse-distance weighted
  estimate from the K nearest (:func:`deformctl.table.interpolate`).

Any other combination (one input without ``--lookup``, two inputs with ``--lookup``, ``-o`` with a
lookup, ...) is a usage error (exit 2) that says which form was meant.
"""

from __future__ import annotations

import json
import math
from typing import Annotated, Any

import typer

from deformctl.cli._common import translate_errors, warn
from deformctl.errors import UsageError, error_context

BUILD_FORM = "deformctl table COEFFICIENTS LIFT -o INDEX"


def _lookup_form() -> str:
    """``deformctl table INDEX --lookup weight_n=..,...`` (the lookup keys of
    :mod:`deformctl.table`, which imports pandas: read when a usage error names the form)."""
    from deformctl.table import LOOKUP_KEYS

    return "deformctl table INDEX --lookup " + ",".join(f"{k}=.." for k in LOOKUP_KEYS)


def _check_mode(
    inputs: list[str],
    output: str | None,
    lookup_text: str | None,
    interpolate_k: int | None,
    allow_unconverged: bool,
    force: bool,
) -> str:
    """``"build"`` or ``"lookup"``; any other combination is a :class:`UsageError`."""
    if lookup_text is None:
        if interpolate_k is not None:
            raise UsageError(f"--interpolate needs --lookup; use: {_lookup_form()} --interpolate K")
        if len(inputs) != 2:
            raise UsageError(
                f"got {len(inputs)} input(s); to build the index table use: {BUILD_FORM}; "
                f"to look it up use: {_lookup_form()}"
            )
        if output is None:
            raise UsageError(f"building the index table needs -o/--output; use: {BUILD_FORM}")
        return "build"
    if len(inputs) != 1:
        raise UsageError(
            f"--lookup takes exactly one index table, got {len(inputs)}: {_lookup_form()}"
        )
    for flag, given in (
        ("-o/--output", output is not None),
        ("--allow-unconverged", allow_unconverged),
        ("--force", force),
    ):
        if given:
            raise UsageError(f"{flag} is for building the index table, not with --lookup")
    if interpolate_k is not None and interpolate_k < 1:
        raise UsageError(f"--interpolate must be >= 1, got {interpolate_k}")
    return "lookup"


def _fmt(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else "nan"
    return str(value)


def _lookup(path: str, text: str, interpolate_k: int | None, as_json: bool) -> None:
    from deformctl.artifacts import read_table
    from deformctl.table import (
        INDEX_COLUMNS,
        MIN_LOOKUP_ROWS,
        QUALITY_COLUMN,
        interpolate,
        keys_without_spread,
        lookup_mapping,
        parse_lookup,
        validate_index_table,
    )

    query = parse_lookup(text)  # before reading: a bad --lookup is a usage error (exit 2)
    index = read_table(
        path,
        "index_table",
        refuse_foreign="build one with `deformctl table COEFFICIENTS LIFT -o INDEX`",
    )
    validate_index_table(index, min_rows=MIN_LOOKUP_ROWS)  # refusals before any warning
    unspread = keys_without_spread(index)
    if unspread:
        warn(
            f"{', '.join(unspread)} {'has' if len(unspread) == 1 else 'have'} no spread over the "
            "index table: compared in raw units, not standard deviations"
        )
    nearest = lookup_mapping(index, query)
    out: dict[str, Any] = {
        "query": query,
        "nearest": {
            k: nearest.row[k] for k in (*INDEX_COLUMNS, QUALITY_COLUMN) if k in nearest.row
        },
        "distance_std": nearest.distance,
        "keys_in_raw_units": unspread,
    }
    if interpolate_k is not None:
        est = interpolate(index, **query, k=interpolate_k)
        out["interpolated"] = {
            "lift_force_n": est.lift_force_n,
            "k": len(est.object_ids),
            "neighbours": [
                {"object_id": i, "distance_std": d, "weight": w}
                for i, d, w in zip(est.object_ids, est.distances, est.weights, strict=True)
            ],
        }
    quality = out["nearest"].get(QUALITY_COLUMN)
    if quality not in (None, "ok") and not (isinstance(quality, float) and math.isnan(quality)):
        warn(f"the nearest entry {out['nearest']['object_id']} has flagged coefficients: {quality}")
    if as_json:
        typer.echo(json.dumps(out, indent=2, allow_nan=False))
        return
    lines = [f"nearest: {out['nearest']['object_id']} (distance {nearest.distance:.4g} std units)"]
    lines += [f"  {k:<24} {_fmt(v)}" for k, v in out["nearest"].items() if k != "object_id"]
    if "interpolated" in out:
        interp = out["interpolated"]
        lines.append(
            f"interpolated lift_force_n: {_fmt(interp['lift_force_n'])} "
            f"(inverse-distance weights over {interp['k']} nearest)"
        )
        lines += [
            f"  {n['object_id']:<12} distance {n['distance_std']:.4g}  weight {n['weight']:.4g}"
            for n in interp["neighbours"]
        ]
    typer.echo("\n".join(lines))


@translate_errors
def table(
    inputs: Annotated[
        list[str],
        typer.Argument(
            metavar="COEFFICIENTS LIFT | INDEX",
            help="Build: the coefficients and lift-results tables. Lookup: one index table.",
            show_default=False,
        ),
    ],
    output: str | None = typer.Option(
        None, "-o", "--output", help="Build: the index table to write (Parquet; - for stdout)."
    ),
    allow_unconverged: bool = typer.Option(
        False,
        "--allow-unconverged",
        help="Build: keep objects whose lift search did not converge (with a finite force).",
    ),
    allow_flagged: bool = typer.Option(
        False,
        "--allow-flagged",
        help="Build: keep objects with impossible coefficients (D <= 0, λ < 0), flagged in "
        "the quality column, instead of exit 65.",
    ),
    force: bool = typer.Option(False, "--force", help="Build: overwrite an existing output."),
    lookup_text: str | None = typer.Option(
        None,
        "--lookup",
        metavar="weight_n=..,deformability_n_per_cm=..,damping_ns_per_cm=..",
        help="Lookup: the attributes (N, N/cm, N·s/cm) to find the nearest entry for.",
    ),
    interpolate_k: int | None = typer.Option(
        None,
        "--interpolate",
        metavar="K",
        help="Lookup: also print an inverse-distance weighted L_f from the K nearest entries.",
    ),
    as_json: bool = typer.Option(False, "--json", help="Lookup: print one JSON document."),
) -> None:
    """Join coefficients and lift results into the index table, or look an entry up.

    Build mode joins by object_id and refuses (exit 65, naming them) objects missing on either
    side and objects whose lifting-force search did not converge (unless --allow-unconverged).
    Lookup mode prints the nearest entry and its distance in standardized units (each attribute
    divided by its standard deviation over the table).

    Example:

    \b
      deformctl table coefficients.parquet lift.parquet -o index.parquet
      deformctl table index.parquet --lookup \\
          weight_n=40,deformability_n_per_cm=40,damping_ns_per_cm=5 --interpolate 4
    """
    mode = _check_mode(inputs, output, lookup_text, interpolate_k, allow_unconverged, force)
    if mode == "lookup" and allow_flagged:
        raise UsageError("--allow-flagged is for building the index table, not with --lookup")
    if mode == "lookup":
        assert lookup_text is not None
        _lookup(inputs[0], lookup_text, interpolate_k, as_json)
        return
    assert output is not None
    _build(
        inputs,
        output,
        allow_unconverged=allow_unconverged,
        allow_flagged=allow_flagged,
        force=force,
    )


def _build(
    inputs: list[str], output: str, *, allow_unconverged: bool, allow_flagged: bool, force: bool
) -> None:
    """Build mode: join, write ``output`` and say what was kept."""
    from deformctl.artifacts import Provenance, check_output_path, write_table
    from deformctl.artifacts.dataset import read_table_any
    from deformctl.table import QUALITY_COLUMN, build_index_table, format_ids

    coefficients_path, lift_path = inputs
    if output in (coefficients_path, lift_path) and output != "-":
        raise UsageError(f"output {output} is also an input")
    check_output_path(output, force)  # fail before reading anything
    coefficients = read_table_any(coefficients_path, "coefficients")  # a file or a dataset dir
    lift = read_table_any(lift_path, "lift_results")
    with error_context(f"{coefficients_path} + {lift_path}"):
        index = build_index_table(
            coefficients, lift, allow_unconverged=allow_unconverged, allow_flagged=allow_flagged
        )
    settings = {"allow_unconverged": allow_unconverged, "allow_flagged": allow_flagged}
    provenance = Provenance.from_invocation([coefficients_path, lift_path], settings=settings)
    write_table(index, output, "index_table", provenance=provenance, force=force)
    if output != "-":
        unconverged = int((~index["converged"]).sum())
        note = f", {unconverged} unconverged kept" if unconverged else ""
        kept = index[QUALITY_COLUMN].str.contains("impossible_coefficients", regex=False)
        flagged = sorted(index["object_id"][kept.fillna(False).to_numpy(dtype=bool)])
        if flagged:
            warn(
                f"{len(flagged)} object(s) kept with impossible coefficients (flagged): "
                f"{format_ids(flagged)}"
            )
        typer.echo(f"wrote {output}: {len(index)} objects{note}", err=True)
