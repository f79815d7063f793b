"""The bundled grip model's evaluation on objects it has never seen (``make model``).

``make model`` trains ``datasets/models/grip.skops`` on a seeded grip population (``population
--grip``, seed 1) through the whole pipeline (``lift --sim`` for the truth L_f, ``measure --sim``
+ ``characterize`` for D and λ, ``table``, ``train``), then runs a *fresh* population (seed 2)
and two special sets through the same pipeline and calls this module:

``python -m deformctl.repro.grip_model mu-catalog POPULATION.csv -o MU.csv``
    The friction pairs: the first :data:`N_MU_PAIRS` objects of a population that can be gripped
    at μ = 0.25, each twice, at μ = 0.25 (``<id>-mu0.25``) and at μ = 1.0 (``<id>-mu1``).

``python -m deformctl.repro.grip_model population --seed S --kv-n N --laws L --laws-n M ...``
    The model's population of every law: ``population --grip -n N --seed S`` (the Kelvin–Voigt
    population the model was trained on before the law mix, bit for bit, so that its Kelvin–Voigt
    network and figures stay today's), then ``population --grip --laws L -n M --seed T
    --id-prefix L`` (``--laws-seed T``: the other laws' objects from their own seed, so that they
    are not the Kelvin–Voigt objects' draws with another law). The Kelvin–Voigt rows take the
    law columns' Kelvin–Voigt values (exponent 1, no arm).

``python -m deformctl.repro.grip_model report RUN_DIR --model MODEL``
    Reads the run directory's index tables (:data:`RUN_FILES`) and prints, on the fresh
    population: the model's median and max relative error beside the constant-ratio, F_w and
    nearest-entry baselines (the last two fitted on the *training* index), the coverage and mean
    margin of the P = 0.9 and 0.95 bounds and the share of objects flagged outside the training
    range; the friction pairs' predicted against simulated L_f(0.25) / L_f(1.0); the paper's Table
    I objects A-D, predicted against simulated. Each line ends with its target and
    ``ok`` or ``MISSED``; the report is also written to ``RUN_DIR/report.md``. Exit 1 when a target
    is missed (``--no-gate`` reports only).

Nothing is tuned here: the model is the file ``train`` wrote and the truth is the simulator's.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from deformctl.catalog import KELVIN_VOIGT_LAW_VALUES, MATERIAL_COLUMNS
from deformctl.errors import DeformctlError
from deformctl.grip.fast import Estimates, Predictor
from deformctl.population import GRIP_MAX_STRAIN_AT_F_W, grip_strain_at_f_w

#: The index tables ``report`` reads from the run directory.
RUN_FILES = {
    "train": "train/index.parquet",
    "test": "test/index.parquet",
    "mu": "mu/index.parquet",
    "paper": "paper/index.parquet",
}
#: The id prefix of the other laws' objects in :func:`model_population`.
LAW_ID_PREFIX = "L"
#: How many objects the friction pairs take, and their two μ.
N_MU_PAIRS = 8
MU_PAIR = (0.25, 1.0)
#: The grip model's targets.
TARGET_MEDIAN = 0.03
TARGET_MAX = 0.10
TARGET_BASELINE_SHARE = 1.0 / 3.0
TARGET_MU_RATIO = 0.05
TARGET_COVERAGE = {0.9: 0.85, 0.95: 0.9}
TARGET_MARGIN_90 = 0.12
TARGET_TABLE_I = 0.10
#: The targets per material law: P = 0.9 coverage and mean margin as above, the first-lift
#: rate (the P = 0.95 bound is >= L_f and <= 1.10 L_f) and the change of the 13 published
#: points' predictions from the reference model (today's bundled one).
TARGET_FIRST_LIFT = 0.90
FIRST_LIFT_EXTRA = 0.10
TARGET_PUBLISHED_CHANGE = 0.01


def mu_catalog(population: pd.DataFrame, n: int = N_MU_PAIRS) -> pd.DataFrame:
    """The friction pairs: the first ``n`` objects grippable at μ = 0.25, at μ 0.25 and 1.0."""
    strain = grip_strain_at_f_w(population.assign(friction_mu=MU_PAIR[0]))
    chosen = population[strain <= GRIP_MAX_STRAIN_AT_F_W].head(n)
    rows = []
    for mu in MU_PAIR:
        part = chosen.copy()
        part["object_id"] = [f"{oid}-mu{mu:g}" for oid in part["object_id"]]
        part["friction_mu"] = mu
        rows.append(part)
    return pd.concat(rows, ignore_index=True)


def model_population(seed: int, kv_n: int, laws: str, laws_n: int, laws_seed: int) -> pd.DataFrame:
    """The model's population of every law (module doc): ``kv_n`` Kelvin–Voigt objects as
    ``population --grip`` draws them alone (seed ``seed``), then ``laws_n`` objects of the mix
    ``laws`` (seed ``laws_seed``)."""
    from deformctl.population import grip_population

    kv = grip_population(kv_n, seed=seed)
    if laws_n == 0:
        return kv
    others = grip_population(laws_n, seed=laws_seed, laws=laws, id_prefix=LAW_ID_PREFIX)
    kv = kv.assign(**KELVIN_VOIGT_LAW_VALUES)
    return pd.concat([kv, others[list(kv.columns)]], ignore_index=True)


def _predict(predictor: Predictor, index: pd.DataFrame, coverage: float | None) -> Estimates:
    return predictor.predict_many(
        index["weight_n"].to_numpy(),
        index["deformability_n_per_cm"].to_numpy(),
        index["damping_ns_per_cm"].to_numpy(),
        index["friction_mu"].to_numpy(),
        coverage=coverage,
        names=index["object_id"].astype(str).tolist(),
    )


def _rel(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    return np.asarray(np.abs(pred - true) / true)


def _nearest_ratio(train: pd.DataFrame, test: pd.DataFrame) -> np.ndarray:
    """The nearest training entry's L_f / F_w (standardized W, D, λ) times the row's F_w."""
    from deformctl.table import standardized_distances

    q = test[["weight_n", "deformability_n_per_cm", "damping_ns_per_cm"]].to_numpy(np.float64)
    nearest = np.argmin(standardized_distances(train, q), axis=1)
    ratio = (train["lift_force_n"] / train["f_w_n"]).to_numpy()
    return np.asarray(ratio[nearest] * test["f_w_n"].to_numpy())


class _Lines:
    def __init__(self) -> None:
        self.lines: list[str] = []
        self.missed: list[str] = []

    def add(self, text: str) -> None:
        self.lines.append(text)

    def check(
        self, text: str, value: float, limit: float, *, at_least: bool = False, pct: bool = True
    ) -> None:
        ok = value >= limit if at_least else value <= limit
        target = f"{'>=' if at_least else '<='} {f'{limit:.0%}' if pct else f'{limit:.3g}'}"
        self.lines.append(f"{text} (target {target}: {'ok' if ok else 'MISSED'})")
        if not ok:
            self.missed.append(text)


def report(
    run_dir: str | Path, model: str | Path, reference: str | Path | None = "grip"
) -> tuple[str, list[str]]:
    """The evaluation report's text and the targets missed (see the module docstring)."""
    from deformctl.artifacts import read_table

    run = Path(run_dir)
    tables = {k: read_table(run / v, "index_table") for k, v in RUN_FILES.items()}
    predictor = Predictor.load(model)
    out = _Lines()
    meta = predictor.metadata
    out.add(f"# The bundled grip model on objects it has not seen ({model})")
    out.add("")
    notes = meta.get("notes") or {}
    out.add(
        f"model: {meta.get('form')} form, hidden {meta['hyperparameters']['hidden']}, seed "
        f"{meta.get('seed')}, {meta.get('n_train')} train / {meta.get('n_calibration')} "
        f"calibration / {meta.get('n_test')} test rows; notes: "
        + ", ".join(f"{k}={v}" for k, v in sorted(notes.items()))
    )

    train, test = tables["train"], _kv_rows(tables["test"], run)
    y = test["lift_force_n"].to_numpy()
    est = _predict(predictor, test, None)
    rel = _rel(est.lift_force_n, y)
    ratio = float(np.median(train["lift_force_n"] / train["f_w_n"]))
    base = {
        "constant ratio (training median L_f/F_w x F_w)": ratio * test["f_w_n"].to_numpy(),
        "F_w alone": test["f_w_n"].to_numpy(),
        "nearest training entry (its L_f/F_w x F_w)": _nearest_ratio(train, test),
    }
    out.add("")
    out.add(
        f"## Fresh population: {len(test)} Kelvin–Voigt objects (truth: lift --sim; D, λ: "
        "characterize)"
    )
    out.add("")
    out.check(
        f"model median relative error {np.median(rel):.2%}", float(np.median(rel)), TARGET_MEDIAN
    )
    out.check(f"model max relative error {rel.max():.2%}", float(rel.max()), TARGET_MAX)
    medians = {}
    for name, pred in base.items():
        r = _rel(pred, y)
        medians[name] = float(np.median(r))
        out.add(f"baseline {name}: median {np.median(r):.2%}, max {r.max():.2%}")
    cr = medians["constant ratio (training median L_f/F_w x F_w)"]
    out.check(
        f"model median / constant-ratio median {np.median(rel) / cr:.3f}",
        float(np.median(rel) / cr),
        TARGET_BASELINE_SHARE,
        pct=False,
    )
    flagged = float(np.mean(est.outside_training_range))
    out.add(f"objects flagged outside the training range: {flagged:.1%}")
    for p, need in TARGET_COVERAGE.items():
        bound = _predict(predictor, test, p)
        upper = bound.lift_force_upper_n
        covered = float(np.mean(y <= upper))
        margin = float(np.mean(upper / y - 1.0))
        out.check(
            f"P = {p:g}: coverage {covered:.3f} (margin q = {predictor.margin(p):+.2%}), mean "
            f"margin (upper / L_f - 1) {margin:.2%}",
            covered,
            need,
            at_least=True,
            pct=False,
        )
        if p == 0.9:
            out.check(f"P = 0.9 mean margin {margin:.2%}", margin, TARGET_MARGIN_90)
        inside = ~bound.outside_training_range
        if inside.any() and not inside.all():
            out.add(
                f"  inside the training range only ({inside.sum()} objects): coverage "
                f"{np.mean(y[inside] <= upper[inside]):.3f}"
            )

    out.add("")
    out.add("## The same object at μ 0.25 and 1.0")
    out.add("")
    mu = tables["mu"]
    mu_est = _predict(predictor, mu, None)
    by_id = dict(zip(mu["object_id"].astype(str), range(len(mu)), strict=True))
    worst = 0.0
    out.add("| object | sim L_f(0.25)/L_f(1) | predicted | difference |")
    out.add("|---|---|---|---|")
    low, high = (f"-mu{m:g}" for m in MU_PAIR)
    for oid in sorted(i[: -len(low)] for i in by_id if i.endswith(low)):
        a, b = by_id[oid + low], by_id[oid + high]
        sim = mu["lift_force_n"].iloc[a] / mu["lift_force_n"].iloc[b]
        pred = mu_est.lift_force_n[a] / mu_est.lift_force_n[b]
        worst = max(worst, abs(pred / sim - 1))
        out.add(f"| {oid} | {sim:.4f} | {pred:.4f} | {pred / sim - 1:+.2%} |")
    out.check(f"worst ratio difference {worst:.2%}", worst, TARGET_MU_RATIO)

    out.add("")
    out.add("## The paper's Table I objects A-D (μ = 0.5)")
    out.add("")
    paper = tables["paper"]
    p_est = _predict(predictor, paper, 0.9)
    out.add(
        "| object | W N | D N/cm | λ N·s/cm | simulated L_f N | predicted | error | upper P=0.9 |"
    )
    out.add("|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for i, row in enumerate(paper.itertuples()):
        pred = float(p_est.lift_force_n[i])
        err = pred / row.lift_force_n - 1
        worst = max(worst, abs(err))
        out.add(
            f"| {row.object_id} | {row.weight_n:g} | {row.deformability_n_per_cm:.3f} | "
            f"{row.damping_ns_per_cm:.3f} | {row.lift_force_n:.3f} | {pred:.3f} | {err:+.2%} | "
            f"{p_est.lift_force_upper_n[i]:.3f} |"
        )
    out.check(f"Table I worst error {worst:.2%}", worst, TARGET_TABLE_I)
    for line in p_est.warnings:
        out.add(f"warning: {line}")

    _law_section(out, predictor, run)
    _published_section(out, predictor, reference)

    out.add("")
    out.add("## Why this form: the same network on the raw inputs")
    out.add("")
    out.add(
        "The grip model's network (same hidden layers, restarts and training rows) fitted to "
        "L_f / W from the raw (W, D, λ, μ) instead of log(L_f / F_w) from (ω_n, ζ):"
    )
    for line in _raw_form_lines(meta, train, test, mu):
        out.add(line)
    return "\n".join(out.lines) + "\n", out.missed


def _raw_form_lines(
    meta: Any, train: pd.DataFrame, test: pd.DataFrame, mu: pd.DataFrame
) -> list[str]:
    """The raw-input alternative on the fresh population and the friction pairs."""
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from threadpoolctl import threadpool_limits

    from deformctl.model import TrainOptions, make_model

    cols = ["weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu"]
    ids = set(meta["split"]["train"])
    rows = train[train["object_id"].astype(str).isin(ids)]
    X, y = rows[cols].astype(float), rows["lift_force_n"].to_numpy()
    hp = meta["hyperparameters"]
    fit = ("activation", "solver", "alpha", "max_iter", "tol")
    options = TrainOptions(hidden=tuple(hp["hidden"]), **{k: hp[k] for k in fit})
    best, best_loss = None, np.inf
    for rs in meta["restart_seeds"]:
        model = make_model(options, random_state=rs)
        with warnings.catch_warnings(), threadpool_limits(limits=1):
            warnings.simplefilter("ignore", ConvergenceWarning)
            model.fit(X, y)
            loss = float(np.sqrt(np.mean((model.predict(X) / y - 1) ** 2)))
        if loss < best_loss:
            best, best_loss = model, loss
    assert best is not None
    with threadpool_limits(limits=1):
        rel = _rel(best.predict(test[cols].astype(float)), test["lift_force_n"].to_numpy())
        pred_mu = best.predict(mu[cols].astype(float))
    by_id = dict(zip(mu["object_id"].astype(str), range(len(mu)), strict=True))
    low, high = (f"-mu{m:g}" for m in MU_PAIR)
    worst = 0.0
    for oid in (i[: -len(low)] for i in by_id if i.endswith(low)):
        a, b = by_id[oid + low], by_id[oid + high]
        sim = mu["lift_force_n"].iloc[a] / mu["lift_force_n"].iloc[b]
        worst = max(worst, abs(pred_mu[a] / pred_mu[b] / sim - 1))
    return [
        f"raw inputs: median relative error {np.median(rel):.2%}, max {rel.max():.2%} on the "
        f"fresh population; friction pairs' worst ratio difference {worst:.2%}",
    ]


def _with_laws(index: pd.DataFrame, run: Path) -> pd.DataFrame | None:
    """The test index with each object's law columns from ``test/coefficients.parquet`` (None
    when the run has no coefficients table or it states no law)."""
    from deformctl.artifacts import read_table
    from deformctl.grip.lawtrain import join_laws

    path = run / "test" / "coefficients.parquet"
    if not path.exists():
        return None
    coef = read_table(path, "coefficients")
    if "model" not in coef.columns:
        return None
    return join_laws(index, coef)


def _kv_rows(index: pd.DataFrame, run: Path) -> pd.DataFrame:
    """The Kelvin–Voigt rows of the test index (all of them when it states no law)."""
    joined = _with_laws(index, run)
    if joined is None:
        return index
    return index[(joined["model"] == "kv").to_numpy()].reset_index(drop=True)


def _law_section(out: _Lines, predictor: Predictor, run: Path) -> None:
    """Per law, on the fresh population: error, P = 0.9 coverage and margin, first-lift rate."""
    from deformctl.artifacts import read_table
    from deformctl.grip.laws import KNOWN_LAWS
    from deformctl.predict import predict_objects_with_laws

    joined = _with_laws(read_table(run / RUN_FILES["test"], "index_table"), run)
    if joined is None:
        return
    out.add("")
    out.add("## Per material law (the row's law as characterize states it)")
    out.add("")
    from deformctl.grip.laws import LAW_COLUMN, LAW_PARAMETER_COLUMNS

    keep = [LAW_COLUMN, *dict.fromkeys(c for cs in LAW_PARAMETER_COLUMNS.values() for c in cs)]
    keep += ["weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu"]
    inputs = {
        c: joined[c].to_numpy(dtype=object if c == "model" else float)
        for c in keep
        if c in joined.columns
    }
    names = joined["object_id"].astype(str).tolist()
    y = joined["lift_force_n"].to_numpy()
    res = {
        p: predict_objects_with_laws(predictor, inputs, coverage=p, names=names)
        for p in (0.9, 0.95)
    }
    for law in KNOWN_LAWS:
        sel = (joined["model"] == law).to_numpy()
        if not sel.any():
            continue
        est9, est95 = res[0.9].estimates, res[0.95].estimates
        rel = _rel(est9.lift_force_n[sel], y[sel])
        up9, up95 = est9.lift_force_upper_n[sel], est95.lift_force_upper_n[sel]
        out.add(
            f"### {law}: {int(sel.sum())} objects, "
            f"{int(np.sum(est9.bound_guaranteed[sel]))} with bound_guaranteed"
        )
        out.check(
            f"{law} median relative error {np.median(rel):.2%}",
            float(np.median(rel)),
            TARGET_MEDIAN,
        )
        out.check(f"{law} max relative error {rel.max():.2%}", float(rel.max()), TARGET_MAX)
        cov = float(np.mean(y[sel] <= up9))
        out.check(
            f"{law} P = 0.9 coverage {cov:.3f}", cov, TARGET_COVERAGE[0.9], at_least=True, pct=False
        )
        margin = float(np.mean(up9 / y[sel] - 1.0))
        out.check(f"{law} P = 0.9 mean margin {margin:.2%}", margin, TARGET_MARGIN_90)
        first = float(np.mean((up95 >= y[sel]) & (up95 <= (1 + FIRST_LIFT_EXTRA) * y[sel])))
        out.check(
            f"{law} first-lift rate (P = 0.95 bound in [L_f, 1.10 L_f]) {first:.3f}",
            first,
            TARGET_FIRST_LIFT,
            at_least=True,
            pct=False,
        )


def published_points() -> pd.DataFrame:
    """The 13 published points (Table II's four bags, Table III's nine cubes) at μ = 0.5."""
    from importlib.resources import files

    root = files("deformctl.datasets").joinpath("paper")
    t2 = pd.read_csv(str(root.joinpath("table2.csv")))
    t3 = pd.read_csv(str(root.joinpath("table3_cubes.csv")))
    objects = pd.read_csv(str(root.joinpath("objects.csv")))
    w = dict(zip(objects["object_id"], objects["weight_n"], strict=True))
    return pd.DataFrame(
        {
            "object_id": [*t2["object_id"], *t3["object_id"]],
            "weight_n": [*(w[i] for i in t2["object_id"]), *t3["weight_n"]],
            "deformability_n_per_cm": [
                *t2["deformability_calculated_n_per_cm"],
                *t3[MATERIAL_COLUMNS[0]],
            ],
            "damping_ns_per_cm": [*t2["damping_calculated_ns_per_cm"], *t3[MATERIAL_COLUMNS[1]]],
            "friction_mu": 0.5,
        }
    )


def _published_section(out: _Lines, predictor: Predictor, reference: str | Path | None) -> None:
    """The 13 published points' predictions against the reference model's (today's)."""
    if reference is None:
        return
    ref = Predictor.load(reference)
    points = published_points()
    new = _predict(predictor, points, None).lift_force_n
    old = _predict(ref, points, None).lift_force_n
    change = np.abs(new / old - 1)
    out.add("")
    out.add(f"## The 13 published points against {reference} (today's predictions)")
    out.add("")
    out.add("| point | W N | D N/cm | λ N·s/cm | today N | this model N | change |")
    out.add("|---|---|---|---|---|---|---|")
    for i, row in enumerate(points.itertuples()):
        out.add(
            f"| {row.object_id} | {row.weight_n:g} | {row.deformability_n_per_cm:g} | "
            f"{row.damping_ns_per_cm:g} | {old[i]:.4g} | {new[i]:.4g} | "
            f"{new[i] / old[i] - 1:+.2%} |"
        )
    out.check(
        f"13 published points: largest change {change.max():.2%}",
        float(change.max()),
        TARGET_PUBLISHED_CHANGE,
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m deformctl.repro.grip_model")
    sub = parser.add_subparsers(dest="command", required=True)
    cat = sub.add_parser("mu-catalog", help="the friction pairs' catalog")
    cat.add_argument("population")
    cat.add_argument("-o", "--output", required=True)
    pop = sub.add_parser("population", help="the model's population of every law")
    pop.add_argument("--seed", type=int, required=True)
    pop.add_argument("--kv-n", type=int, required=True)
    pop.add_argument("--laws", required=True)
    pop.add_argument("--laws-n", type=int, required=True)
    pop.add_argument("--laws-seed", type=int, required=True)
    pop.add_argument("-o", "--output", required=True)
    rep = sub.add_parser("report", help="evaluate the model on the run directory")
    rep.add_argument("run_dir")
    rep.add_argument("--model", default="grip")
    rep.add_argument(
        "--reference",
        default="grip",
        help="the model whose predictions of the 13 published points are today's ('none': skip)",
    )
    rep.add_argument("--no-gate", action="store_true", help="exit 0 even when a target is missed")
    try:
        args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return 2 if exc.code else 0
    try:
        if args.command == "mu-catalog":
            from deformctl.artifacts import read_catalog, write_catalog

            write_catalog(mu_catalog(read_catalog(args.population)), args.output, force=True)
            return 0
        if args.command == "population":
            from deformctl.artifacts import write_catalog

            both = model_population(args.seed, args.kv_n, args.laws, args.laws_n, args.laws_seed)
            write_catalog(both, args.output, force=True)
            return 0
        ref = None if args.reference == "none" else args.reference
        text, missed = report(args.run_dir, args.model, ref)
    except DeformctlError as err:
        print(f"error: {err}", file=sys.stderr)
        return err.exit_code
    print(text, end="")
    (Path(args.run_dir) / "report.md").write_text(text, encoding="utf-8")
    if missed and not args.no_gate:
        print(f"error: {len(missed)} target(s) missed", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
