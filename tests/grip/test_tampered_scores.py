"""Bounds that cannot lie: a model file whose calibration scores were changed is refused.

A copy of the bundled grip model with only its ``conformal_scores`` changed made ``predict
--coverage 0.9`` print upper bounds of -4.37 N, 2.19 N (below F_w = 2.9 N), 3.5e298 N and inf,
each with ``bound_guaranteed = true``. Each such tampering (and the subtler ones: a changed
count, a score moved inside the physical range, a rescaled list) is now refused by every command
that loads the file with one line and exit 65, and every bound printed by an untouched file
satisfies F_w <= prediction <= bound. A coverage below the smallest meaningful value 1/(n + 1)
exits 2.
"""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.artifacts.model import load_model
from deformctl.cli import app
from deformctl.errors import InputDataError, UsageError
from deformctl.grip.conformal import conformal_rank, min_coverage, scores_digest
from deformctl.grip.fast import Predictor, resolve_model_path
from deformctl.grip.sanity import SCORE_HIGH, SCORE_LOW

cli = CliRunner()
BUNDLED = resolve_model_path("grip")
#: the object of the hostile run (F_w = 2.9 N)
OBJECT = {"weight_n": 2.9, "deformability_n_per_cm": 20.0, "damping_ns_per_cm": 2.0,
          "friction_mu": 0.5}  # fmt: skip


def _meta(path: Path) -> dict[str, object]:
    with zipfile.ZipFile(path) as z:
        schema = json.loads(z.read("schema.json"))
    return json.loads(json.loads(schema["content"]["metadata_json"]["content"]))


def _rewrite(src: Path, dst: Path, change: dict[str, object]) -> Path:
    with zipfile.ZipFile(src) as z_in, zipfile.ZipFile(dst, "w") as z_out:
        for info in z_in.infolist():
            data = z_in.read(info)
            if info.filename == "schema.json":
                schema = json.loads(data)
                node = schema["content"]["metadata_json"]
                meta = json.loads(json.loads(node["content"]))
                meta.update(change)
                node["content"] = json.dumps(json.dumps(meta, allow_nan=True))
                data = json.dumps(schema).encode()
            z_out.writestr(info, data)
    return dst


def _scores() -> list[float]:
    return list(_meta(BUNDLED)["conformal_scores"])  # type: ignore[arg-type]


def _at_rank(coverage: float, value: float) -> list[float]:
    """The bundled scores with the one that is the margin at ``coverage`` set to ``value``."""
    scores = sorted(_scores())
    k = conformal_rank(len(scores), coverage)
    scores[k - 1 :] = [max(value, s) if value > 0 else value for s in scores[k - 1 :]]
    if value < 0:
        scores[: k - 1] = [value] * (k - 1)
    return scores


def _tamperings() -> dict[str, dict[str, object]]:
    scores = _scores()
    fewer = scores[:-1]
    return {
        # the four the hostile run printed
        "bound -4.37 N": {"conformal_scores": _at_rank(0.9, -2.5)},
        "bound below F_w": {"conformal_scores": _at_rank(0.9, -0.5)},
        "bound 3.5e298 N": {"conformal_scores": _at_rank(0.9, 1e298)},
        "bound inf": {"conformal_scores": _at_rank(0.9, math.inf)},
        "nan score": {"conformal_scores": [math.nan, *scores[1:]]},
        # the subtler ones
        "inside the range, margin raised": {"conformal_scores": _at_rank(0.9, 5.0)},
        "one score moved a little": {"conformal_scores": [scores[0] + 1e-3, *scores[1:]]},
        "count changed": {"conformal_scores": fewer},
        "count and n_calibration changed": {"conformal_scores": fewer, "n_calibration": 149},
        "scores and stored margins rescaled": {
            "conformal_scores": [2 * s for s in scores],
            "conformal": None,
        },
        "empty": {"conformal_scores": []},
        "not numbers": {"conformal_scores": ["a", "b"]},
    }


TAMPERINGS = _tamperings()
#: Changes a file without a digest (the bundled model, written before ``train`` stored one)
#: cannot show: they leave the stored margins at P = 0.9 and 0.95 as they were. A file that
#: ``train`` or ``adapt`` writes now carries the digest, which refuses them too.
LEGACY_MISSES = {"one score moved a little", "count and n_calibration changed"}


@pytest.mark.parametrize(
    ("kind", "digest"),
    [(k, d) for k in TAMPERINGS for d in (False, True) if d or k not in LEGACY_MISSES],
)
def test_every_kind_of_score_tampering_is_refused_by_every_loader(
    kind: str, digest: bool, tmp_path: Path
) -> None:
    src = BUNDLED
    if digest:  # a file as train writes it now: the scores' digest stored
        stored = {"conformal_digest": scores_digest(_scores())}
        src = _rewrite(BUNDLED, tmp_path / "digest.skops", stored)
    bad = _rewrite(src, tmp_path / "grip.skops", TAMPERINGS[kind])
    with pytest.raises(InputDataError):
        Predictor.load(bad)
    with pytest.raises(InputDataError):
        load_model(bad)  # the estimator's loader (inspect) refuses it too
    args = ["--weight-n", "2.9", "--deformability-n-per-cm", "20", "--damping-ns-per-cm", "2",
            "--friction-mu", "0.5", "--coverage", "0.9"]  # fmt: skip
    res = cli.invoke(app, ["predict", str(bad), *args])
    assert res.exit_code == 65, (kind, res.stdout, res.stderr)
    assert res.stderr.count("\n") == 1
    assert res.stderr.startswith("error: ")
    assert res.stdout == ""
    res = cli.invoke(app, ["inspect", str(bad)])
    assert res.exit_code == 65, (kind, res.stdout, res.stderr)


def test_a_digest_covers_a_new_file(tmp_path: Path) -> None:
    scores = _scores()
    good = _rewrite(BUNDLED, tmp_path / "g.skops", {"conformal_digest": scores_digest(scores)})
    assert Predictor.load(good).scores is not None
    moved = [*scores[:-1], scores[-1] * 0.999]  # the margins at 0.9 / 0.95 are unchanged
    bad = _rewrite(good, tmp_path / "b.skops", {"conformal_scores": moved})
    with pytest.raises(InputDataError, match="do not match their stored digest"):
        Predictor.load(bad)


def test_every_printed_bound_is_between_the_prediction_and_the_limit() -> None:
    model = Predictor.load("grip")
    rng = np.random.default_rng(0)
    n = 2000
    W, D = rng.uniform(0.1, 100, n), rng.uniform(0.5, 200, n)
    lam, mu = rng.uniform(0, 20, n), rng.uniform(0.1, 1.5, n)
    for coverage in (min_coverage(150), 0.1, 0.5, 0.9, 0.95):
        est = model.predict_many(W, D, lam, mu, coverage=coverage)
        plausible = ~est.prediction_implausible
        up, lift, f_w = est.lift_force_upper_n, est.lift_force_n, est.f_w_n
        assert np.all(np.isfinite(up))
        assert np.all(up >= lift)
        assert np.all(up >= f_w)
        assert np.all(up[plausible] <= (1 + SCORE_HIGH) * lift[plausible])
    assert SCORE_LOW < -0.9 < SCORE_HIGH > 9


def test_coverage_below_the_smallest_meaningful_value_exits_2() -> None:
    model = Predictor.load("grip")
    assert min_coverage(150) == pytest.approx(1 / 151)
    for p in (3e-15, 1e-300, 0.006):
        with pytest.raises(UsageError, match=r"--coverage must be at least 1/\(n \+ 1\) = 0.00662"):
            model.predict(**OBJECT, coverage=p)
    args = ["--weight-n", "2.9", "--deformability-n-per-cm", "20", "--damping-ns-per-cm", "2",
            "--friction-mu", "0.5", "--coverage", "3e-15"]  # fmt: skip
    res = cli.invoke(app, ["predict", "grip", *args])
    assert res.exit_code == 2
    assert res.stderr.count("\n") == 1
    # at the smallest meaningful value: the smallest score's bound, clipped at the prediction
    est = model.predict(**OBJECT, coverage=min_coverage(150))
    assert est.lift_force_upper_n == pytest.approx(est.lift_force_n)


def test_an_untouched_table_prediction_has_sane_bounds(tmp_path: Path) -> None:
    table = pd.DataFrame([{"object_id": "A", **OBJECT}])
    src, out = tmp_path / "in.parquet", tmp_path / "out.parquet"
    table.to_parquet(src, index=False)
    res = cli.invoke(app, ["predict", "grip", str(src), "--coverage", "0.9", "-o", str(out)])
    assert res.exit_code == 0, res.stderr
    row = read_table(out, "predictions").iloc[0]
    assert row["f_w_n"] <= row["predicted_lift_force_n"] <= row["lift_force_upper_n"]
