"""The reproduction report: our pipeline's numbers beside the paper's Tables II and III.

``make reproduce`` runs the whole pipeline with the ``deformctl`` command into one run
directory and then calls :func:`write_report` (``python -m deformctl.repro.report RUN_DIR``), which
reads the artifacts back through the validating readers and writes:

* ``report.md``: Table II (deformability, damping, lifting force of the four Table I objects)
  with the paper's calculated and simulated values beside ours and the relative differences;
  Table III (network inputs, expected and predicted lifting force) for the paper's rows and a
  sample of our test rows; Table III's nine inputs run through our simulator (cubes of
  1 g/cm³, ``datasets/paper/table3_cubes.csv``) beside the paper's expected and NN columns; the
  model's metrics on train and test beside three baselines (nearest entry, F_w alone, and the
  constant ratio: the training rows' median L_f / F_w times F_w); the landscape: the span of
  L_f / F_w over the population and its rank correlation with ζ.
* ``predicted_vs_measured.png``: our network's L_f against the simulated L_f, train and test.
* ``force_compression.png``: force felt against compression for the four Table I objects.
* ``lf_over_fw_vs_zeta.png``: L_f / F_w against the damping ratio ζ = λ / (2 √(D m)) over the
  population, with the paper's 13 simulated points (Table II and III, F_w at μ = 0.5) and ours
  for the same 13 objects overlaid.

Before the tables, the report says how it was made and what the simulator was fitted to
(:mod:`deformctl.repro.disclosure`: version, commit, date, command lines; the calibrated
parameters, the paper's points they were fitted to, the in-sample and leave-one-out errors); every
column with a unit names its source (:data:`deformctl.repro.disclosure.LABELS`), and under the
plots each one's points not shown are named (:mod:`deformctl.repro.plots`).

The run directory holds the files the Makefile names (see :data:`RUN_FILES`). Nothing here is
tuned to the paper: differences are reported as they are.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from deformctl.artifacts import read_squeeze_log, read_table
from deformctl.catalog import catalog_objects
from deformctl.errors import DeformctlError, MissingInputError
from deformctl.physics import damping_ratio, rigid_grip_force_n
from deformctl.presets import paper_calibration
from deformctl.repro.disclosure import (
    LABELS,
    calibration_section,
    column,
    provenance_section,
    run_preset,
)
from deformctl.repro.paper import compare_with_paper
from deformctl.repro.plots import draw_plots
from deformctl.resources import dataset_path
from deformctl.version import __version__ as version

#: The artifacts :func:`write_report` reads from the run directory.
RUN_FILES = {
    "paper_squeeze": "paper_squeeze.mcap",
    "paper_coefficients": "paper_coefficients.parquet",
    "paper_lift": "paper_lift.parquet",
    "lift": "lift.parquet",
    "index": "index.parquet",
    "metrics": "metrics.json",
    "predictions": "predictions.parquet",
    "table3_lift": "table3_lift.parquet",
}

DATASETS = dataset_path("paper")  #: the bundled paper tables (table2.csv, table3.csv)


@dataclass(frozen=True)
class ReportSummary:
    """What :func:`write_report` wrote and the headline numbers it printed."""

    report_path: Path
    plots: tuple[Path, ...]
    table2: pd.DataFrame
    model_test_max_rel_error: float
    model_test_median_rel_error: float
    text: str
    constant_ratio_test_max_rel_error: float = float("nan")
    constant_ratio_test_median_rel_error: float = float("nan")
    ratio_min: float = float("nan")  #: the population's smallest L_f / F_w
    ratio_max: float = float("nan")  #: the population's largest L_f / F_w
    ratio_zeta_spearman: float = float("nan")  #: rank correlation of L_f / F_w with ζ
    plot_notes: tuple[str, ...] = ()  #: per plot: every point shown, or the points not shown


def _rel(ours: pd.Series, theirs: pd.Series) -> pd.Series:
    return (ours - theirs) / theirs


def compare_table2(
    coefficients: pd.DataFrame, lift: pd.DataFrame, table2: pd.DataFrame
) -> pd.DataFrame:
    """Our D, λ and L_f for the Table I objects beside the paper's Table II.

    The lifting-force half is :func:`deformctl.repro.paper.compare_with_paper`; this adds the
    deformability and damping columns.

    Returns:
        One row per paper object that was lifted, with the paper's calculated D and λ, ours, the
        paper's calculated (physical) and simulated lifting force, ours, and relative
        differences (ours − paper) / paper; NaN where the paper's value is 0.
    """
    lf = compare_with_paper(lift, table2)
    merged = lf.merge(
        table2[["object_id", "deformability_calculated_n_per_cm", "damping_calculated_ns_per_cm"]],
        on="object_id",
    ).merge(
        coefficients[["object_id", "deformability_n_per_cm", "damping_ns_per_cm"]],
        on="object_id",
        how="left",
    )
    out = pd.DataFrame(
        {
            "object_id": merged["object_id"],
            "interior": merged["interior"],
            "d_paper_n_per_cm": merged["deformability_calculated_n_per_cm"],
            "d_ours_n_per_cm": merged["deformability_n_per_cm"],
            "lambda_paper_ns_per_cm": merged["damping_calculated_ns_per_cm"],
            "lambda_ours_ns_per_cm": merged["damping_ns_per_cm"],
            "lf_paper_physical_n": merged["lift_force_calculated_n"],
            "lf_paper_simulation_n": merged["lift_force_simulation_n"],
            "lf_ours_n": merged["lift_force_n"],
            "f_w_ours_n": merged["f_w_n"],
            "lf_rel_diff_vs_simulation": merged["rel_diff_simulation"],
            "lf_rel_diff_vs_physical": merged["rel_diff_calculated"],
        }
    )
    out["d_rel_diff"] = _rel(out["d_ours_n_per_cm"], out["d_paper_n_per_cm"])
    lam_paper = out["lambda_paper_ns_per_cm"].where(out["lambda_paper_ns_per_cm"] != 0)
    out["lambda_rel_diff"] = _rel(out["lambda_ours_ns_per_cm"], lam_paper)
    return out


def _fmt(value: Any, digits: int = 2) -> str:
    if isinstance(value, float | np.floating):
        return "–" if not np.isfinite(value) else f"{value:.{digits}f}"
    return str(value)


def _pct(value: Any) -> str:
    return "–" if not np.isfinite(value) else f"{100 * float(value):+.1f} %"


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A GitHub Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _metrics_rows(metrics: dict[str, Any]) -> list[list[str]]:
    rows = []
    for key, label in (
        ("model", "network 3-2-1"),
        ("baseline_nearest", "nearest index entry"),
        ("baseline_f_w", "F_w = W/(2μ)"),
        ("baseline_constant_ratio", "median L_f/F_w × F_w"),
    ):
        block = metrics.get(key)
        if not block:
            continue
        for split in ("train", "test"):
            m = block[split]
            rows.append(
                [
                    label,
                    split,
                    _pct(m["max_rel_error"]).lstrip("+"),
                    _pct(m["median_rel_error"]).lstrip("+"),
                    _fmt(m["mae_n"]),
                    _fmt(m["r2"], 3),
                ]
            )
    return rows


def _split_of(predictions: pd.DataFrame, metrics: dict[str, Any]) -> pd.Series:
    split = metrics.get("split") or {}
    test_ids = set(split.get("test", []))
    return predictions["object_id"].map(lambda i: "test" if i in test_ids else "train")


def population_zeta(index: pd.DataFrame) -> pd.Series:
    """ζ of each index-table row, from its measured D and λ (see ``damping_ratio``)."""
    return pd.Series(
        damping_ratio(
            index["weight_n"].to_numpy(dtype=np.float64),
            index["deformability_n_per_cm"].to_numpy(dtype=np.float64),
            index["damping_ns_per_cm"].to_numpy(dtype=np.float64),
        ),
        index=index.index,
    )


def compare_landscape(
    table2: pd.DataFrame,
    paper_lift: pd.DataFrame,
    table3: pd.DataFrame,
    table3_lift: pd.DataFrame,
    friction_mu: float = 0.5,
) -> pd.DataFrame:
    """The paper's 13 simulated points beside our L_f for the same objects.

    Table II's four bags (ours from ``paper_lift``) and Table III's nine inputs (ours from
    ``table3_lift``, object ids ``T3-1`` … ``T3-9`` as in ``datasets/paper/table3_cubes.csv``).
    The paper's F_w is taken at ``friction_mu`` (the catalog's assumption; the paper gives none).

    Returns:
        One row per point: ``point``, ``weight_n``, D, λ, ``zeta``, ``lift_force_paper_n``, the
        paper's NN output (Table III only), ``lift_force_ours_n`` (NaN when that object was not
        lifted), ``ratio_paper``, ``ratio_ours`` and ``error`` (ours / paper − 1).
    """
    catalog = pd.read_csv(dataset_path("paper", "objects.csv"))
    names = dict(zip(catalog["object_id"], catalog["name"], strict=True))
    specs = {o.object_id: o.to_sim_spec() for o in catalog_objects(catalog)}
    ours2 = paper_lift.set_index("object_id")["lift_force_n"]
    ours3 = table3_lift.set_index("object_id")["lift_force_n"]
    rows = []
    for r in table2.itertuples():
        o = specs[str(r.object_id)]
        rows.append(
            (str(names[r.object_id]), o.weight_n, o.stiffness_n_per_cm, o.damping_ns_per_cm,
             float(r.lift_force_simulation_n), np.nan, float(ours2.get(r.object_id, np.nan)))
        )  # fmt: skip
    for i, r in enumerate(table3.itertuples(), start=1):
        rows.append(
            (f"T3-{i}", float(r.weight_n), float(r.deformability_n_per_cm),
             float(r.damping_ns_per_cm), float(r.lift_force_expected_n),
             float(r.lift_force_nn_output_n), float(ours3.get(f"T3-{i}", np.nan)))
        )  # fmt: skip
    out = pd.DataFrame(
        rows,
        columns=[
            "point",
            "weight_n",
            "deformability_n_per_cm",
            "damping_ns_per_cm",
            "lift_force_paper_n",
            "lift_force_paper_nn_n",
            "lift_force_ours_n",
        ],
    )
    out["zeta"] = damping_ratio(
        out["weight_n"], out["deformability_n_per_cm"], out["damping_ns_per_cm"]
    )
    f_w = rigid_grip_force_n(out["weight_n"].to_numpy(dtype=np.float64), friction_mu)
    out["ratio_paper"] = out["lift_force_paper_n"] / f_w
    out["ratio_ours"] = out["lift_force_ours_n"] / f_w
    out["error"] = out["lift_force_ours_n"] / out["lift_force_paper_n"] - 1.0
    return out


def write_report(
    run_dir: str | Path,
    *,
    datasets_dir: str | Path = DATASETS,
    argv: Sequence[str] | None = None,
) -> ReportSummary:
    """Read a reproduce run directory and write ``report.md`` and the plots into it.

    ``argv``: the report's command line as the report states it (default :data:`sys.argv`).

    Raises:
        MissingInputError: a file of :data:`RUN_FILES` is missing.
        DeformctlError: an artifact does not validate.
    """
    run = Path(run_dir)
    files = {key: run / name for key, name in RUN_FILES.items()}
    for path in files.values():
        if not path.exists():
            raise MissingInputError("no such file (run `make reproduce` first)", path=path)
    datasets = Path(datasets_dir)
    table2 = pd.read_csv(datasets / "table2.csv")
    table3 = pd.read_csv(datasets / "table3.csv")
    paper_coeffs = read_table(files["paper_coefficients"], "coefficients")
    paper_lift = read_table(files["paper_lift"], "lift_results")
    lift = read_table(files["lift"], "lift_results")
    index = read_table(files["index"], "index_table")
    predictions = read_table(files["predictions"], "predictions")
    metrics = json.loads(files["metrics"].read_text())
    objects, squeezes = read_squeeze_log(files["paper_squeeze"])
    table3_lift = read_table(files["table3_lift"], "lift_results")
    artifacts = {  # their provenance, before anything is merged into them
        "lift.parquet": lift,
        "index.parquet": index,
        "predictions.parquet": predictions,
        "paper_lift.parquet": paper_lift,
        "paper_coefficients.parquet": paper_coeffs,
        "table3_lift.parquet": table3_lift,
    }
    landscape = compare_landscape(table2, paper_lift, table3, table3_lift)

    t2 = compare_table2(paper_coeffs, paper_lift, table2)
    predictions = predictions.merge(index[["object_id", "lift_force_n", "f_w_n"]], on="object_id")
    predictions["split"] = _split_of(predictions, metrics)
    predictions["rel_error"] = (
        predictions["predicted_lift_force_n"] - predictions["lift_force_n"]
    ).abs() / predictions["lift_force_n"]
    test = predictions[predictions["split"] == "test"]

    by_object: dict[str, list[Any]] = {}
    for s in squeezes:
        by_object.setdefault(s.object_id, []).append(s)
    names = {str(o.get("object_id")): str(o.get("interior", o.get("name", ""))) for o in objects}
    drawn = draw_plots(run, predictions, index, population_zeta(index), by_object, names, landscape)
    plots = tuple(p.path for p in drawn)

    t2_rows = [
        [
            f"{r.object_id} {r.interior}",
            _fmt(r.d_paper_n_per_cm),
            _fmt(r.d_ours_n_per_cm),
            _pct(r.d_rel_diff),
            _fmt(r.lambda_paper_ns_per_cm),
            _fmt(r.lambda_ours_ns_per_cm),
            _pct(r.lambda_rel_diff),
            _fmt(r.lf_paper_physical_n),
            _fmt(r.lf_paper_simulation_n),
            _fmt(r.lf_ours_n),
            _pct(r.lf_rel_diff_vs_simulation),
            _pct(r.lf_rel_diff_vs_physical),
        ]
        for r in t2.itertuples()
    ]
    t2_md = markdown_table(
        [
            "object",
            column("D", "N/cm", "rig"),
            column("D", "N/cm", "ours"),
            "Δ D",
            column("λ", "N·s/cm", "rig"),
            column("λ", "N·s/cm", "ours"),
            "Δ λ",
            column("L_f", "N", "rig"),
            column("L_f", "N", "paper_sim"),
            column("L_f", "N", "ours"),
            "Δ vs the paper's simulation",
            "Δ vs the rig",
        ],
        t2_rows,
    )
    t3_paper = markdown_table(
        [
            column("W", "N", "paper_sim"),
            column("D", "N/cm", "paper_sim"),
            column("λ", "N·s/cm", "paper_sim"),
            column("expected L_f", "N", "paper_sim"),
            column("NN L_f", "N", "paper_nn"),
            "error",
        ],
        [
            [
                _fmt(r.weight_n),
                _fmt(r.deformability_n_per_cm),
                _fmt(r.damping_ns_per_cm),
                _fmt(r.lift_force_expected_n),
                _fmt(r.lift_force_nn_output_n),
                _pct(
                    (r.lift_force_nn_output_n - r.lift_force_expected_n) / r.lift_force_expected_n
                ),
            ]
            for r in table3.itertuples()
        ],
    )
    sample = test.sort_values("object_id").head(len(table3))
    t3_ours = markdown_table(
        [
            "object",
            column("W", "N", "ours"),
            column("D", "N/cm", "ours"),
            column("λ", "N·s/cm", "ours"),
            column("L_f", "N", "ours"),
            column("NN L_f", "N", "our_nn"),
            "error",
        ],
        [
            [
                str(r.object_id),
                _fmt(r.weight_n),
                _fmt(r.deformability_n_per_cm),
                _fmt(r.damping_ns_per_cm),
                _fmt(r.lift_force_n),
                _fmt(r.predicted_lift_force_n),
                _pct((r.predicted_lift_force_n - r.lift_force_n) / r.lift_force_n),
            ]
            for r in sample.itertuples()
        ],
    )
    t3_sim = markdown_table(
        ["input", column("W", "N", "paper_sim"), column("D", "N/cm", "paper_sim"),
         column("λ", "N·s/cm", "paper_sim"), "ζ", column("expected L_f", "N", "paper_sim"),
         column("NN L_f", "N", "paper_nn"), column("L_f", "N", "ours"), "ours vs expected"],
        [
            [r.point, _fmt(r.weight_n), _fmt(r.deformability_n_per_cm),
             _fmt(r.damping_ns_per_cm), _fmt(r.zeta, 3), _fmt(r.lift_force_paper_n),
             _fmt(r.lift_force_paper_nn_n), _fmt(r.lift_force_ours_n), _pct(r.error)]
            for r in landscape[landscape["point"].str.startswith("T3-")].itertuples()
        ],
    )  # fmt: skip
    ratio = index["lift_force_n"] / index["f_w_n"]
    zeta = population_zeta(index)
    ratio_min, ratio_max = float(ratio.min()), float(ratio.max())
    spearman = float(ratio.rank().corr(zeta.rank())) if len(index) > 2 else float("nan")
    worst = landscape["error"].abs().max()
    landscape_md = markdown_table(
        ["point", "ζ", column("L_f", "N", "paper_sim"), column("L_f", "N", "ours"),
         f"L_f/F_w, {LABELS['paper_sim']}", f"L_f/F_w, {LABELS['ours']}", "Δ"],
        [
            [r.point, _fmt(r.zeta, 3), _fmt(r.lift_force_paper_n), _fmt(r.lift_force_ours_n),
             _fmt(r.ratio_paper, 3), _fmt(r.ratio_ours, 3), _pct(r.error)]
            for r in landscape.itertuples()
        ],
    )  # fmt: skip
    metrics_md = markdown_table(
        [
            "predictor",
            "split",
            "max rel. error",
            "median rel. error",
            column("MAE", "N", "ours"),
            "R²",
        ],
        _metrics_rows(metrics),
    )
    test_max = float(test["rel_error"].max()) if len(test) else float("nan")
    test_median = float(test["rel_error"].median()) if len(test) else float("nan")
    converged = int(lift["converged"].sum())
    text = "\n\n".join(
        [
            "# deformctl reproduction of Howard & Bekey",
            "Produced by `make reproduce`. μ = 0.5 is assumed for every object (the paper gives "
            "no friction coefficient), so lifting forces compare in shape, not to the newton. "
            "Each column's header says where its numbers come from: "
            + ", ".join(f"*{label}*" for label in LABELS.values())
            + " (our network: trained on simulated (ours) rows).",
            "## How this report was made",
            provenance_section(version, artifacts, argv),
            "## Calibration",
            calibration_section(run_preset(paper_lift, table3_lift, lift), paper_calibration()),
            "## Table II: the four Table I objects",
            t2_md,
            "## Table III: network inputs and outputs",
            "The paper's rows:",
            t3_paper,
            f"Ours (the first {len(sample)} of {len(test)} test objects):",
            t3_ours,
            "Table III's nine inputs through our simulator (cubes of 1 g/cm³, μ = 0.5; "
            "`datasets/paper/table3_cubes.csv`):",
            t3_sim,
            "## The landscape: L_f / F_w against the damping ratio ζ",
            f"Over the population L_f / F_w spans {ratio_min:.3f} to {ratio_max:.3f}; its rank "
            f"correlation with ζ is {spearman:+.2f} (negative: it falls as damping grows). The "
            f"paper's 13 simulated points beside ours (worst {_pct(worst)}):",
            landscape_md,
            "## Model metrics (same split for every predictor)",
            f"Population: {len(lift)} objects, {converged} converged lifting-force searches; "
            f"{metrics.get('n_train')} train / {metrics.get('n_test')} test, "
            f"seed {metrics.get('seed')}.",
            metrics_md,
            "## Plots",
            "\n".join(f"![{p.stem}]({p.name})" for p in plots),
            "Points not shown (a plot never drops a point without saying so):\n\n"
            + "\n".join(f"- {p.note()}" for p in drawn),
        ]
    )
    report_path = run / "report.md"
    report_path.write_text(text + "\n", encoding="utf-8")
    summary_lines = [
        "Table I objects (ours vs the paper's Table II):",
        *[
            f"  {r.object_id} {r.interior:<7}"
            f" D {r.d_ours_n_per_cm:6.2f} N/cm ({_pct(r.d_rel_diff)})"
            f"  λ {r.lambda_ours_ns_per_cm:5.2f} N·s/cm ({_pct(r.lambda_rel_diff)})"
            f"  L_f {r.lf_ours_n:6.2f} N vs sim {r.lf_paper_simulation_n:5.2f}"
            f" ({_pct(r.lf_rel_diff_vs_simulation)}), physical {r.lf_paper_physical_n:5.2f}"
            f" ({_pct(r.lf_rel_diff_vs_physical)})"
            for r in t2.itertuples()
        ],
        f"Network 3-2-1 on {len(test)} test objects: max relative error "
        f"{100 * test_max:.2f} %, median {100 * test_median:.2f} % (paper: max < 14.8 %)",
    ]
    summary_lines.append(
        f"Landscape: L_f/F_w spans {ratio_min:.3f} to {ratio_max:.3f} over {len(index)} objects "
        f"(rank correlation with zeta {spearman:+.2f}); the 13 paper points: worst "
        f"{_pct(worst)}"
    )
    for key, label in (
        ("baseline_nearest", "nearest entry"),
        ("baseline_f_w", "F_w alone"),
        ("baseline_constant_ratio", "constant ratio (median L_f/F_w x F_w)"),
    ):
        block = metrics.get(key)
        if block:
            m = block["test"]
            summary_lines.append(
                f"Baseline {label}: max {100 * m['max_rel_error']:.2f} %, "
                f"median {100 * m['median_rel_error']:.2f} %"
            )
    summary_lines.append(f"Report: {report_path}")
    return ReportSummary(
        report_path=report_path,
        plots=plots,
        plot_notes=tuple(p.note() for p in drawn),
        table2=t2,
        model_test_max_rel_error=test_max,
        model_test_median_rel_error=test_median,
        text="\n".join(summary_lines),
        constant_ratio_test_max_rel_error=_test_metric(metrics, "max_rel_error"),
        constant_ratio_test_median_rel_error=_test_metric(metrics, "median_rel_error"),
        ratio_min=ratio_min,
        ratio_max=ratio_max,
        ratio_zeta_spearman=spearman,
    )


def _test_metric(metrics: dict[str, Any], name: str) -> float:
    block = metrics.get("baseline_constant_ratio")
    return float(block["test"][name]) if block else float("nan")


def gate_failures(
    summary: ReportSummary,
    *,
    max_test_error: float | None = None,
    beat_constant_ratio: bool = False,
    ratio_span: tuple[float, float] | None = None,
) -> list[str]:
    """The acceptance checks ``make reproduce`` asks for that the run fails, one message each.

    Args:
        max_test_error: the network's max relative test error must be at most this fraction.
        beat_constant_ratio: the network's max test error must be at most half the
            constant-ratio baseline's, and its median at most a third of the baseline's median.
        ratio_span: ``(low, high)``: the population's L_f / F_w must reach down to ``low`` and up
            to ``high``, and fall with ζ (negative rank correlation).
    """
    failures = []
    s = summary
    if max_test_error is not None and not s.model_test_max_rel_error <= max_test_error:
        failures.append(
            f"the network's max relative test error {100 * s.model_test_max_rel_error:.2f} % "
            f"exceeds {100 * max_test_error:.2f} %"
        )
    if beat_constant_ratio:
        if not s.model_test_max_rel_error <= 0.5 * s.constant_ratio_test_max_rel_error:
            failures.append(
                f"the network's max test error {100 * s.model_test_max_rel_error:.2f} % is more "
                f"than half the constant-ratio baseline's "
                f"{100 * s.constant_ratio_test_max_rel_error:.2f} %"
            )
        if not s.model_test_median_rel_error <= s.constant_ratio_test_median_rel_error / 3.0:
            failures.append(
                f"the network's median test error {100 * s.model_test_median_rel_error:.2f} % is "
                f"more than a third of the constant-ratio baseline's "
                f"{100 * s.constant_ratio_test_median_rel_error:.2f} %"
            )
    if ratio_span is not None:
        low, high = ratio_span
        if not (s.ratio_min <= low and s.ratio_max >= high):
            failures.append(
                f"L_f/F_w spans {s.ratio_min:.3f} to {s.ratio_max:.3f}, not {low} to {high}"
            )
        if not s.ratio_zeta_spearman < 0:
            failures.append(
                f"L_f/F_w does not fall with zeta (rank correlation {s.ratio_zeta_spearman:+.2f})"
            )
    return failures


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m deformctl.repro.report RUN_DIR [gates]``: write the report, print its summary.

    Gates (each failing one prints an ``error:`` line and the exit code is 1, so a regression of a
    headline number fails ``make reproduce``): ``--require-max-test-error FRACTION``,
    ``--require-beat-constant-ratio`` and ``--require-ratio-span LOW HIGH`` (see
    :func:`gate_failures`).
    """
    import argparse

    parser = argparse.ArgumentParser(prog="python -m deformctl.repro.report")
    parser.add_argument("run_dir", metavar="RUN_DIR")
    parser.add_argument("--require-max-test-error", type=float, metavar="FRACTION")
    parser.add_argument("--require-beat-constant-ratio", action="store_true")
    parser.add_argument("--require-ratio-span", type=float, nargs=2, metavar=("LOW", "HIGH"))
    try:
        args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:  # argparse printed its usage line
        return 2 if exc.code else 0
    limit = args.require_max_test_error
    if limit is not None and not 0 < limit < 1:
        print(f"error: --require-max-test-error takes a fraction, got {limit!r}", file=sys.stderr)
        return 2
    given = list(sys.argv[1:] if argv is None else argv)
    try:
        summary = write_report(
            args.run_dir, argv=["python", "-m", "deformctl.repro.report", *given]
        )
    except DeformctlError as err:
        print(f"error: {err}", file=sys.stderr)
        return err.exit_code
    print(summary.text)
    failures = gate_failures(
        summary,
        max_test_error=limit,
        beat_constant_ratio=args.require_beat_constant_ratio,
        ratio_span=tuple(args.require_ratio_span) if args.require_ratio_span else None,
    )
    for message in failures:
        print(f"error: {message}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
