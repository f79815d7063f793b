"""``deformctl inspect``: what an artifact is and what it holds."""

from __future__ import annotations

import json
import os

import typer

from deformctl.artifacts.io import display_name, read_input_bytes, stale_temporaries
from deformctl.artifacts.row_options import DEFAULT_ROWS, parse_column_list, parse_row_count
from deformctl.cli._common import translate_errors
from deformctl.cli._inspect_text import render_dataset, render_text
from deformctl.errors import UsageError


@translate_errors
def inspect(
    file: str = typer.Argument(
        ...,
        help="Any deformctl artifact (MCAP, Parquet, catalog CSV, model file); - for stdin; "
        "grip: the bundled model.",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON document instead of text."),
    rows: str | None = typer.Option(
        None,
        "--rows",
        metavar="N|all",
        help=f"Show only the first N (>= 1) rows of a table (or of --attempts) [default: the "
        f"summary and the first {DEFAULT_ROWS}; --json and --csv: every row]; all: every row.",
    ),
    columns: str | None = typer.Option(
        None, "--columns", metavar="a,b,c", help="Show only these columns, in this order."
    ),
    as_csv: bool = typer.Option(
        False, "--csv", help="Print the rows as CSV on stdout (every digit), nothing else."
    ),
    attempts: bool = typer.Option(
        False,
        "--attempts",
        help="A lift log's attempts: per object every attempt (force, lifted, outcome, slip) "
        "and the L_f found.",
    ),
) -> None:
    """Show an artifact's kind, schema, counts, time range, units and provenance, and its rows.

    A table (catalog, coefficients, lift results, index table, predictions, a dataset
    directory) shows its first 20 rows under the summary, units in the headers; --rows N (or
    all), --columns and --attempts show the rows alone; --json adds every row as "records" and
    --csv prints every row as CSV, unless --rows N is given. Numbers show 6 significant digits
    in the text table and every digit in --json and --csv; long text is cut to the terminal
    width.

    FILE `grip` is the model bundled with deformctl (the one `predict grip` uses); a file of
    that name in the working directory is ./grip.

    The file is fully validated first; a damaged or invalid file exits with 65. Temporary files
    a killed run left next to it (``.NAME.deformctl-PID-RANDOM.tmp``) are listed on stderr (and
    as ``stale_temporary_files`` in --json); the next run writing the file removes them.

    Example: deformctl inspect datasets/paper/objects.csv --rows all --columns object_id,weight_n
    """
    if as_json and as_csv:
        raise UsageError("give --json or --csv, not both")
    from deformctl.artifacts.dataset import describe_dataset
    from deformctl.artifacts.describe import describe
    from deformctl.artifacts.rows import artifact_rows, rows_csv, rows_records, select_rows
    from deformctl.cli._rows import rows_footer, rows_text
    from deformctl.grip.fast import BUNDLED_MODELS, resolve_model_path

    if file in BUNDLED_MODELS:  # a bundled model's name, as predict resolves it
        file = str(resolve_model_path(file))
    limit = parse_row_count(rows, default=None if as_json or as_csv else DEFAULT_ROWS)
    chosen = parse_column_list(columns)
    explicit = rows is not None or chosen is not None or as_csv or attempts
    if os.path.isdir(file):  # a sweep dataset directory
        info = describe_dataset(file)
        table = artifact_rows(file, None, attempts=attempts)
        text = render_dataset(info)
    else:
        data = read_input_bytes(file)
        info = describe(file, data=data)  # validates, with the errors every reader gives
        table = artifact_rows(file, data, attempts=attempts)
        text = ""
        if file != "-":
            stale = [str(p) for p in stale_temporaries(file)]
            if stale:  # a killed writer's leftovers; the next run writing this file removes them
                info["stale_temporary_files"] = stale
    if table is None and explicit:
        raise UsageError(
            f"{display_name(file)} is a {info['kind']}: it has no rows (rows: tables and dataset "
            "directories; a lift log's attempts: --attempts)"
        )
    shown = None if table is None else select_rows(table, chosen, limit, display_name(file))
    if as_csv:
        assert shown is not None
        typer.echo(rows_csv(shown), nl=False)
    elif as_json:
        if shown is not None:
            info["records"] = rows_records(shown)
            info["records_total"] = shown.total
        typer.echo(json.dumps(info, indent=2, allow_nan=False))
    else:
        typer.echo(rows_text(shown, text or render_text(info), summary=not explicit))
    if shown is not None and (note := rows_footer(shown)):
        typer.echo(note, err=True)
    for path in info.get("stale_temporary_files", []):
        typer.echo(
            f"stale temporary file of a killed run: {path} (the next run writing "
            f"{file} removes it)",
            err=True,
        )
