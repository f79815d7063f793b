"""The scale-out flags shared by ``measure --sim``, ``characterize`` and ``lift --sim``.

A dataset directory output (``-o DIR/`` or an existing directory) runs the per-object work
through :func:`deformctl.parallel.run_sweep`; the flags below choose where it runs. Single-file
outputs run as before and refuse these flags.
"""

from __future__ import annotations

from typing import Any

import typer

from deformctl.parallel import SweepOptions, SweepSummary

__all__ = ["SweepOptions", "finish"]

WORKERS_HELP = "Dataset output: local worker processes [default: every core]."
SCHEDULER_HELP = "Dataset output: run on this running Dask scheduler, tcp://HOST:PORT."
CONNECT_TIMEOUT_HELP = "With --scheduler: seconds allowed to reach the scheduler [default: 10]."
PARTITION_HELP = "Dataset output: objects per part file [default: 100]."
RESUME_HELP = "Dataset output: keep the complete parts of an earlier run, compute the rest."


def workers_option() -> Any:
    """``--workers N``."""
    return typer.Option(None, "--workers", metavar="N", help=WORKERS_HELP)


def scheduler_option() -> Any:
    """``--scheduler tcp://HOST:PORT``."""
    return typer.Option(None, "--scheduler", metavar="tcp://HOST:PORT", help=SCHEDULER_HELP)


def connect_timeout_option() -> Any:
    """``--connect-timeout S``."""
    return typer.Option(None, "--connect-timeout", metavar="S", help=CONNECT_TIMEOUT_HELP)


def partition_size_option() -> Any:
    """``--partition-size N``."""
    return typer.Option(None, "--partition-size", metavar="N", help=PARTITION_HELP)


def resume_option() -> Any:
    """``--resume``."""
    return typer.Option(False, "--resume", help=RESUME_HELP)


def finish(summary: SweepSummary, what: str) -> None:
    """Print the sweep's one-line summary on stderr; exit 1 when any object failed."""
    failures = f"; failed objects: {summary.out_dir}/_failures/" if summary.failed_total else ""
    typer.echo(f"{summary.out_dir}: {what}: {summary.line()}{failures}", err=True)
    if summary.exit_code:
        raise typer.Exit(summary.exit_code)
