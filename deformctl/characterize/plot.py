"""``characterize --plot DIR``: one PNG per object, to look at a fit.

Each figure (:data:`FIGURE_SIZE_IN` at :data:`DPI`, so :data:`PIXELS`) has four panels:

* force against compression: the samples, and every law's fitted mean force over the windows
  (the law chosen drawn thick), with the operating force marked;
* force and compression against time, the squeezes one after another;
* every law's window residuals against time;
* the chosen law's rate-free force–compression curve with the loading's small-strain and
  large-strain slopes.

The title names the object, the law chosen and the quality flags. Matplotlib draws on its Agg
canvas (no display needed, no global state touched); each file is written atomically.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from deformctl.characterize.laws import elastic_force
from deformctl.errors import UsageError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from deformctl.characterize.objectfit import ObjectFit

#: Figure size, inches, and resolution: the PNG is 1200 × 900 pixels.
FIGURE_SIZE_IN = (12.0, 9.0)
DPI = 100
PIXELS = (1200, 900)
#: Colour of each law.
COLOURS = {"kv": "tab:blue", "hc": "tab:orange", "sls": "tab:green", "exp": "tab:red"}


def plot_path(plot_dir: str | Path, object_id: str) -> Path:
    """``plot_dir/<object_id>.png``, with characters a file name cannot hold replaced by ``_``."""
    safe = re.sub(r"[^A-Za-z0-9._-]", "_", object_id) or "_"
    return Path(plot_dir) / f"{safe}.png"


def check_plot_dir(plot_dir: str | Path) -> Path:
    """Create ``plot_dir`` (and its parents) when missing.

    Raises:
        UsageError: it exists and is not a directory, or cannot be created (exit 2).
    """
    d = Path(plot_dir)
    if d.exists() and not d.is_dir():
        raise UsageError(f"--plot {plot_dir}: not a directory")
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"--plot {plot_dir}: cannot create it: {err.strerror or err}") from None
    return d


def plot_object(obj: ObjectFit, object_id: str, quality: str, path: str | Path) -> Path:
    """Draw one object's fit into ``path`` (PNG, replaced atomically)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from deformctl.artifacts.io import atomic_output

    fig = Figure(figsize=FIGURE_SIZE_IN, dpi=DPI)
    FigureCanvasAgg(fig)
    ax_fd, ax_t, ax_r, ax_el = fig.subplots(2, 2).ravel()
    chosen = obj.chosen
    offset = 0.0
    ax_f2 = ax_t.twinx()
    for k, (g, s) in enumerate(zip(obj.grids, obj.data.squeezes, strict=True)):
        t = offset + g.dt_s * np.arange(g.force_n.shape[0])
        ax_fd.plot(
            1e3 * g.compression_m,
            g.force_n,
            ".",
            ms=1.5,
            color="0.65",
            label="samples" if k == 0 else None,
        )
        ax_t.plot(t, g.force_n, color="tab:red", lw=1, label="force" if k == 0 else None)
        ax_f2.plot(t, 1e3 * g.compression_m, color="tab:purple", lw=1)
        centre = offset + s.mean_time()
        for fit in obj.fits:
            pred = fit.window_prediction(s)
            bold = fit is chosen
            label = f"{fit.model} (BIC {fit.bic:.1f})" if k == 0 else None
            ax_fd.plot(
                1e3 * s.mean_compression(),
                pred,
                "-",
                color=COLOURS[fit.model],
                lw=2.5 if bold else 1.0,
                label=label,
            )
            resid = s.mean_force(fit.params.get("lag_s", 0.0)) - pred
            ax_r.plot(
                centre,
                resid,
                "-",
                color=COLOURS[fit.model],
                lw=1.5 if bold else 0.8,
                label=fit.model if k == 0 else None,
            )
        offset = float(t[-1]) + 10.0 * g.dt_s
    ax_fd.axhline(obj.operating_force_n, color="k", ls=":", lw=1, label="operating force")
    ax_fd.set(xlabel="compression (mm)", ylabel="force (N)", title="force against compression")
    ax_fd.legend(fontsize=8, loc="upper left")
    ax_t.set(xlabel="time (s), squeezes one after another", ylabel="force (N)")
    ax_t.set_title("force and compression against time")
    ax_f2.set_ylabel("compression (mm)", color="tab:purple")
    ax_r.axhline(0.0, color="k", lw=0.5)
    ax_r.set(xlabel="time (s)", ylabel="window residual (N)", title="residuals of each law")
    ax_r.legend(fontsize=8)
    top = max(float(np.max(g.compression_m)) for g in obj.grids)
    d = np.linspace(0.0, top, 200)
    ax_el.plot(
        1e3 * d,
        elastic_force(chosen.model, chosen.params, d),
        color=COLOURS[chosen.model],
        lw=2,
        label=f"{chosen.model}: rate-free curve",
    )
    for slope, frac, name in (
        (obj.loading.small_strain_n_per_m, 0.1, "small-strain slope"),
        (obj.loading.large_strain_n_per_m, 0.95, "large-strain slope"),
    ):
        if np.isfinite(slope):
            x0 = frac * top
            y0 = float(elastic_force(chosen.model, chosen.params, np.array([x0]))[0])
            xs = np.array([x0 - 0.05 * top, x0 + 0.05 * top])
            ax_el.plot(1e3 * xs, y0 + slope * (xs - x0), "k--", lw=1, label=name)
    ax_el.set(
        xlabel="compression (mm)",
        ylabel="force above the preload (N)",
        title=f"D = {obj.deformability_n_per_m / 100:.4g} N/cm at {obj.operating_force_n:.4g} N; "
        f"stiffening ×{obj.loading.stiffening_ratio:.3g}",
    )
    ax_el.legend(fontsize=8)
    fig.suptitle(f"{object_id}: {chosen.model} — {quality}", fontsize=13)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.96))
    dest = Path(path)
    with atomic_output(dest, force=True) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)
    return dest


def plot_fits(
    fits: Mapping[str, ObjectFit], quality: Mapping[str, str], plot_dir: str | Path
) -> list[str]:
    """One PNG per object (object id → its fit; its ``quality`` for the title); the paths."""
    d = check_plot_dir(plot_dir)
    return [
        str(plot_object(obj, oid, str(quality.get(oid, "")), plot_path(d, oid)))
        for oid, obj in fits.items()
    ]
