"""The reproduction report's plots, and the points each one does not show.

A plot never drops a point silently: :func:`draw_plots` checks, after each figure is laid out,
which of its points are not finite or fall outside the axes (a negative ζ left of the
``symlog`` axis that starts at 0, an object that was not lifted so has no L_f), and returns one
note per plot naming them; the report prints the notes under the plots.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

#: Names listed in full in a note; more are counted.
MAX_NAMED = 12


@dataclass(frozen=True)
class Plot:
    """One figure written, and what it does not show."""

    path: Path
    hidden: tuple[str, ...] = ()  #: ``name (why)`` of each point not shown

    def note(self) -> str:
        """``name.png: every point shown`` or the points not shown, named."""
        if not self.hidden:
            return f"`{self.path.name}`: every point is shown."
        shown = ", ".join(self.hidden[:MAX_NAMED])
        more = f" and {len(self.hidden) - MAX_NAMED} more" if len(self.hidden) > MAX_NAMED else ""
        return f"`{self.path.name}`: {len(self.hidden)} point(s) not shown: {shown}{more}."


def hidden_points(
    ax: Any, names: Sequence[str], x: Sequence[float], y: Sequence[float], what: str
) -> list[str]:
    """The points of a series ``what`` that ``ax`` does not show: not finite, or outside its
    limits (read after the figure is laid out)."""
    xs, ys = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    out = []
    for name, xv, yv in zip(names, xs, ys, strict=True):
        if not (np.isfinite(xv) and np.isfinite(yv)):
            out.append(f"{name} ({what}: no value)")
        elif not (x0 <= xv <= x1 and y0 <= yv <= y1):
            out.append(f"{name} ({what}: x {xv:.3g}, y {yv:.3g} outside the axes)")
    return out


def draw_plots(
    out_dir: Path,
    predictions: pd.DataFrame,
    index: pd.DataFrame,
    zeta: pd.Series,
    squeezes_by_object: Mapping[str, list[Any]],
    names: Mapping[str, str],
    landscape: pd.DataFrame,
) -> tuple[Plot, ...]:
    """``predicted_vs_measured.png``, ``force_compression.png`` and ``lf_over_fw_vs_zeta.png``
    (see :mod:`deformctl.repro.report`), each with the points it does not show."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plots = []
    fig, ax = plt.subplots(figsize=(5, 5))
    for split, marker in (("train", "o"), ("test", "s")):
        part = predictions[predictions["split"] == split]
        ax.scatter(
            part["lift_force_n"], part["predicted_lift_force_n"], marker=marker, label=split, s=18
        )
    lo = float(min(predictions["lift_force_n"].min(), predictions["predicted_lift_force_n"].min()))
    hi = float(max(predictions["lift_force_n"].max(), predictions["predicted_lift_force_n"].max()))
    ax.plot([lo, hi], [lo, hi], "k--", lw=1, label="y = x")
    ax.set_xlabel("simulated L_f (N), simulated (ours)")
    ax.set_ylabel("network L_f (N), our network")
    ax.set_title("Predicted vs simulated lifting force")
    ax.legend()
    fig.tight_layout()
    hidden = hidden_points(
        ax,
        list(predictions["object_id"]),
        predictions["lift_force_n"],
        predictions["predicted_lift_force_n"],
        "L_f",
    )
    plots.append(Plot(out_dir / "predicted_vs_measured.png", tuple(hidden)))
    fig.savefig(plots[-1].path, dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 4.5))
    hidden = []
    order = sorted(squeezes_by_object)
    for oid in order:
        for k, s in enumerate(squeezes_by_object[oid]):
            ax.plot(
                s.compression_m * 100.0,
                s.force_n,
                lw=1,
                color=f"C{order.index(oid)}",
                label=f"{oid} ({names.get(oid, oid)})" if k == 0 else None,
            )
    ax.set_xlabel("compression d (cm), simulated (ours)")
    ax.set_ylabel("force felt f (N), simulated (ours)")
    ax.set_title("Squeezes of the Table I objects")
    ax.legend()
    fig.tight_layout()
    for oid in order:
        for k, s in enumerate(squeezes_by_object[oid]):
            samples = [f"{oid} squeeze {k} sample {i}" for i in range(len(s.force_n))]
            hidden += hidden_points(ax, samples, s.compression_m * 100.0, s.force_n, "f(d)")
    plots.append(Plot(out_dir / "force_compression.png", tuple(hidden)))
    fig.savefig(plots[-1].path, dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ratio = index["lift_force_n"] / index["f_w_n"]
    sc = ax.scatter(
        zeta,
        ratio,
        c=index["weight_n"],
        s=16,
        cmap="viridis",
        label="our population",
    )
    fig.colorbar(sc, ax=ax, label="weight W (N)")
    ax.scatter(
        landscape["zeta"],
        landscape["ratio_paper"],
        marker="*",
        s=90,
        color="C3",
        edgecolor="k",
        label="the paper's simulation (Tables II, III)",
        zorder=3,
    )
    ax.scatter(
        landscape["zeta"],
        landscape["ratio_ours"],
        marker="x",
        s=50,
        color="k",
        label="simulated (ours), same 13 objects",
        zorder=3,
    )
    ax.axhline(1.0, color="k", lw=1, ls="--")
    ax.set_xscale("symlog", linthresh=0.05)  # linear near zeta = 0 (the water bag), log above
    ax.set_xlim(left=0.0)
    ax.set_xlabel("damping ratio ζ = λ / (2 √(D m))")
    ax.set_ylabel("L_f / F_w")
    ax.set_title("Lifting force over the rigid-object force")
    ax.legend(fontsize=8)
    fig.tight_layout()
    points = list(landscape["point"])
    hidden = [
        *hidden_points(ax, list(index["object_id"]), zeta, ratio, "population"),
        *hidden_points(ax, points, landscape["zeta"], landscape["ratio_paper"], "paper"),
        *hidden_points(ax, points, landscape["zeta"], landscape["ratio_ours"], "ours"),
    ]
    plots.append(Plot(out_dir / "lf_over_fw_vs_zeta.png", tuple(hidden)))
    fig.savefig(plots[-1].path, dpi=120)
    plt.close(fig)
    return tuple(plots)
