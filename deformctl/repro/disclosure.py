"""What the reproduction report says about itself, so that a reader can weigh every number.

* :data:`LABELS`: where each column's numbers come from. Every number with a unit in a table of
  ``report.md`` carries one of them in its header: ``simulated (ours)``, ``measured (the paper's
  rig)``, ``the paper's simulation``, ``the paper's network`` or ``our network``.
* :func:`calibration_section`: which parameters of the simulator preset the run used were
  fitted (by ``make calibrate``), to which of the paper's points, with the in-sample and the
  leave-one-out error: the comparison with those points is not independent of the fit.
* :func:`provenance_section`: the deformctl version, the git commit of the source (with a note
  when the tree has uncommitted changes), the date and the command lines (the report's own and
  the one that wrote each artifact it reads).
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pandas as pd

#: Where a column's numbers come from (the header names one).
LABELS: dict[str, str] = {
    "ours": "simulated (ours)",
    "rig": "measured (the paper's rig)",
    "paper_sim": "the paper's simulation",
    "paper_nn": "the paper's network",
    "our_nn": "our network",
}
#: The paper's Table II objects by id (the calibration names them by interior).
_TABLE2 = {"A": "sponge", "B": "cotton", "C": "sand", "D": "water"}


def column(name: str, unit: str | None, source: str) -> str:
    """A table header: ``D (N/cm), measured (the paper's rig)``."""
    return f"{name}{f' ({unit})' if unit else ''}, {LABELS[source]}"


def run_preset(*tables: pd.DataFrame) -> str | None:
    """The simulator preset the artifacts' provenance names (None when none names one)."""
    for table in tables:
        provenance = table.attrs.get("provenance")
        preset = getattr(provenance, "settings", {}).get("sim_preset")
        if isinstance(preset, str):
            return preset.split("+", 1)[0]
    return None


def calibration_section(preset: str | None, calibration: Mapping[str, Any]) -> str:
    """The calibration paragraph and table (``calibration``: ``datasets/calibration/paper.json``).

    When the run used another preset than ``paper`` (or none is recorded) the paragraph says so:
    the fit below then does not describe the run's simulator.
    """
    fitted = calibration.get("fitted", {})
    bounds = calibration.get("bounds", {})
    points = [str(p.get("point")) for p in calibration.get("points", [])]
    loo = calibration.get("leave_one_out", {})
    loo_by_point = {str(p.get("point")): p for p in loo.get("points", [])}
    params = ", ".join(
        f"`{k}` = {v:g} (searched in [{bounds.get(k, ['?', '?'])[0]}, "
        f"{bounds.get(k, ['?', '?'])[1]}])"
        for k, v in fitted.items()
    )
    used = (
        f"The simulator ran with the `{preset}` preset."
        if preset
        else "The artifacts do not record the simulator preset (the default is `paper`)."
    )
    if preset not in (None, "paper"):
        used += " The calibration below is the `paper` preset's and does not describe this run."
    lines = [
        f"{used} Its {len(fitted)} fitted parameters: {params}, fitted by `make calibrate` "
        f"(deformctl {calibration.get('deformctl_version', '?')}) to the paper's "
        f"{len(points)} simulated lifting forces: Table II's {', '.join(_TABLE2.values())} "
        f"(the paper's simulation column) and Table III's nine inputs simulated as cubes "
        f"(`datasets/paper/table3_cubes.csv`). Objective: {calibration.get('objective', '?')}.",
        f"In-sample worst error over the {len(points)} points: "
        f"{100 * float(calibration.get('worst_error', float('nan'))):.1f} %; leave-one-out "
        f"(each point predicted with the parameters fitted to the other "
        f"{max(len(points) - 1, 0)}): worst {100 * float(loo.get('worst', float('nan'))):.1f} %. "
        "The comparisons with these points below are therefore not independent of the fit: "
        "the leave-one-out column is the honest error.",
        f"Fixed, not fitted: {_fixed(calibration.get('fixed', {}))}; μ = "
        f"{calibration.get('friction_mu', '?')} for every object (the paper gives none).",
    ]
    table = [
        "| point (fitted to it) | L_f (N), the paper's simulation | in-sample error | "
        "leave-one-out error |",
        "|---|---|---|---|",
        *(
            f"| {p['point']} | {float(p.get('lift_force_paper_n', float('nan'))):.2f} | "
            f"{_pct(p.get('error'))} | {_pct(loo_by_point.get(str(p['point']), {}).get('error'))} |"
            for p in calibration.get("points", [])
        ),
    ]
    return "\n\n".join([*lines, "\n".join(table)])


def _fixed(fixed: Mapping[str, Any]) -> str:
    return ", ".join(f"{k} {v}" for k, v in fixed.items()) or "nothing recorded"


def _pct(value: Any) -> str:
    try:
        return f"{100 * float(value):+.1f} %"
    except (TypeError, ValueError):
        return "–"


def git_commit(source: Path | None = None) -> str:
    """The source tree's commit (``abc1234``, ``+ uncommitted changes`` when dirty), or
    ``unknown (not a git checkout)``."""
    where = source or Path(__file__).resolve().parents[2]
    try:
        head = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True, timeout=10
        )
        if head.returncode != 0:
            return "unknown (not a git checkout)"
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=where,
            capture_output=True,
            text=True,
            timeout=10,
        )
    except (OSError, subprocess.SubprocessError):
        return "unknown (git not available)"
    commit = head.stdout.strip()
    return commit + (" + uncommitted changes" if dirty.stdout.strip() else "")


def provenance_section(
    version: str,
    artifacts: Mapping[str, pd.DataFrame],
    argv: Sequence[str] | None = None,
    *,
    now: datetime | None = None,
    commit: str | None = None,
) -> str:
    """Version, commit, date and command lines (the report's and each artifact's)."""
    args = list(sys.argv if argv is None else argv)
    stamp = (now or datetime.now(UTC)).strftime("%Y-%m-%d %H:%M:%S UTC")
    rows = ["| artifact | written by |", "|---|---|"]
    for name, table in artifacts.items():
        provenance = table.attrs.get("provenance")
        command = " ".join(getattr(provenance, "command_line", ()) or ()) or "not recorded"
        rows.append(f"| {name} | `{command}` |")
    lines = [
        f"deformctl {version}, commit {commit or git_commit()}, written {stamp}.",
        f"This report: `{' '.join(args) or 'python -m deformctl.repro.report'}`; the artifacts "
        "it reads:",
        "\n".join(rows),
    ]
    return "\n\n".join(lines)
