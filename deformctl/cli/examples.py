"""``deformctl examples DIR``: the bundled sample recordings and guide inputs, for a wheel user."""

from __future__ import annotations

import typer

from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force


@translate_errors
def examples(
    directory: str = typer.Argument(
        ..., metavar="DIR", help="The folder to copy them into (created; must be empty)."
    ),
    force: Force = False,
) -> None:
    """Copy the bundled sample recordings and the guides' inputs into DIR, to run the guides.

    DIR gets datasets/ (the sample recordings: a testing-machine export, a gripper's ROS 2 bag,
    three real phantom recordings with their licence; the paper's object tables) and examples/
    (the stand-in rigs and scripts the guides run), laid out as in a checkout, so the guides'
    commands run unchanged from DIR. An existing DIR that holds anything is refused unless
    --force, which writes the bundled files over their copies and keeps the rest.

    Example: deformctl examples samples && cd samples && deformctl measure csv
    datasets/examples/utm_export.csv --object-id foam --weight-n 2.9 -o foam.mcap
    """
    from deformctl.samples import copy_examples

    written = copy_examples(directory, force=force)
    folders = sorted({str(p.parent) for p in written})
    typer.echo(
        f"wrote {directory}: {len(written)} files in {', '.join(folders)}; run the guides' "
        f"commands from {directory}",
        err=True,
    )
