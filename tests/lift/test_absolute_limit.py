"""The absolute force limit of a rig: no request above min(object's ceiling, rig's limit).

The rig states its maximum force in a handshake (docs/rig-protocol.md); a rig that states none
(a version-1 rig) gets :data:`DEFAULT_ABSOLUTE_MAX_FORCE_N`. ``--max-force-n`` and a catalog's
``max_force_n`` can lower the limit, never raise it. The property test draws catalogs the
catalog schema accepts (every column anywhere in its bounds, μ down to its floor) and objects
that need any force up to a million times F_w, and finds no request above the limit.
"""

from __future__ import annotations

import json
import math
import shlex
import sys
from pathlib import Path
from typing import Any
from unittest import mock

import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.artifacts.schema import validate_frame
from deformctl.catalog import BOUNDS
from deformctl.cli import app
from deformctl.errors import RigError, UsageError
from deformctl.lift.ceiling import (
    DEFAULT_ABSOLUTE_MAX_FORCE_N,
    DEFAULT_CEILING_RATIO,
    absolute_limit,
    force_ceiling,
)
from deformctl.lift.options import SearchOptions
from deformctl.lift.runners import rig as rig_module
from deformctl.lift.runners.rig import RigRunner, rig_handshake, rig_runner_factory
from deformctl.lift.stage import lift_catalog
from deformctl.quantities import FRICTION_MU

cli = CliRunner()
RIGS = Path(__file__).resolve().parents[1] / "rigs"
HEADER = "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu"


def _rig(threshold_n: float, log: Path | None = None, stated: float | None = None) -> str:
    args = [sys.executable, str(RIGS / "threshold_rig.py"), str(threshold_n), str(log or "-")]
    return shlex.join(args + ([] if stated is None else [repr(stated)]))


# ---------------------------------------------------------------------------- the rule


def test_mu_has_a_physical_floor() -> None:
    assert FRICTION_MU.low == 0.01
    assert not FRICTION_MU.low_open
    for tiny in (1e-9, 1e-100, 1e-300, 1e-308, 0.0099):
        assert not FRICTION_MU.ok(tiny)
    assert BOUNDS["friction_mu"] == (0.01, 3.0)


def test_the_limit_lowers_every_ceiling_and_the_flag_cannot_raise_it() -> None:
    default = absolute_limit(None)
    assert (default.max_force_n, default.source) == (500.0, "absolute default")
    # 10 x F_w = 50,000 N for W = 5000 N, μ = 0.5: the absolute default wins
    assert force_ceiling("A", 5000.0, absolute=default).max_force_n == 500.0
    # --max-force-n above the limit: the limit
    assert force_ceiling("A", 1.0, max_force_n=1e6, absolute=default).max_force_n == 500.0
    # the catalog's max_force_n above it: the limit; below it: the catalog's
    row = {"max_force_n": 1e9}
    assert force_ceiling("A", 1.0, row=row, absolute=default).source == "absolute default"
    assert force_ceiling("A", 1.0, row={"max_force_n": 7.0}, absolute=default).max_force_n == 7.0
    stated = absolute_limit(2000.0)
    assert force_ceiling("A", 5000.0, absolute=stated).max_force_n == 2000.0
    assert force_ceiling("A", 1.0, absolute=stated).max_force_n == DEFAULT_CEILING_RATIO
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(UsageError):
            absolute_limit(bad)


def test_a_rig_runner_alone_never_sends_more_than_the_default_limit() -> None:
    runner = RigRunner("rig", timeout_s=1, object={"object_id": "A", "weight_n": 1.0,
                                                   "friction_mu": 0.5})  # fmt: skip
    assert runner.request(1.0, 0)["max_force_n"] == DEFAULT_ABSOLUTE_MAX_FORCE_N
    with pytest.raises(RigError, match="above the force ceiling 500 N"):
        runner(501.0, 0)  # refused before the command runs


# ---------------------------------------------------------------------------- the handshake


def test_the_handshake_reads_the_stated_maximum_and_a_version_1_rig_gets_the_default() -> None:
    assert rig_handshake(_rig(1.0, stated=120.0), timeout_s=30).max_force_n == 120.0
    assert rig_handshake(_rig(1.0), timeout_s=30) == absolute_limit(None)  # exits 1
    echo = [sys.executable, str(RIGS / "echo_rig.py")]
    assert rig_handshake([*echo, '{"lifted": true, "slip_m": 0}'], timeout_s=30).source == (
        "absolute default"
    )
    assert rig_handshake([*echo, "not json"], timeout_s=30).source == "absolute default"
    assert rig_handshake(["/no/such/rig"], timeout_s=30).source == "absolute default"
    for bad in ('{"max_force_n": -5}', '{"max_force_n": "a lot"}', '{"max_force_n": 0}'):
        with pytest.raises(RigError, match="rig handshake: max_force_n must be a finite number"):
            rig_handshake([*echo, bad], timeout_s=30)


def test_cli_a_stated_maximum_caps_the_requests(tmp_path: Path) -> None:
    catalog = tmp_path / "objects.csv"
    # F_w = 1000 N: above the 500 N default, below the 2000 N the rig states
    catalog.write_text(f"{HEADER}\nheavy,8,5,4,1000,0.5\n", encoding="utf-8")
    log, out = tmp_path / "req.jsonl", tmp_path / "lift.parquet"
    args = [
        "lift",
        "rig",
        str(catalog),
        "--command",
        _rig(1900.0, log, stated=2000.0),
        "-o",
        str(out),
    ]
    res = cli.invoke(app, args)
    assert res.exit_code == 0, res.stderr
    sent = [json.loads(line) for line in log.read_text().splitlines()]
    assert sent
    assert max(r["grip_force_n"] for r in sent) <= 2000.0
    assert {r["max_force_n"] for r in sent} == {2000.0}
    assert read_table(out, "lift_results")["max_force_n"].tolist() == [2000.0]


def test_cli_a_version_1_rig_never_gets_more_than_the_default(tmp_path: Path) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(f"{HEADER}\nheavy,8,5,4,1000,0.5\nlight,8,5,4,10,0.5\n", encoding="utf-8")
    log, out = tmp_path / "req.jsonl", tmp_path / "lift.parquet"
    args = ["lift", "rig", str(catalog), "--command", _rig(12.0, log), "--max-force-n", "1e6"]
    res = cli.invoke(app, [*args, "-o", str(out)])
    assert res.exit_code == 1  # heavy: no safe grip
    assert res.stderr.splitlines()[0] == (
        "warning: object 'heavy': F_w = 1000 N is above its force ceiling 500 N (the absolute "
        "limit of a rig that states none): no safe grip, not lifted"
    )
    sent = [json.loads(line) for line in log.read_text().splitlines()]
    assert {r["object_id"] for r in sent} == {"light"}  # nothing was asked of heavy
    assert all(r["grip_force_n"] <= r["max_force_n"] == 500.0 for r in sent)
    table = read_table(out, "lift_results").set_index("object_id")
    assert table.loc["light", "converged"]


def test_cli_a_tiny_mu_is_refused_before_any_request(tmp_path: Path) -> None:
    log = tmp_path / "req.jsonl"
    for mu in ("1e-9", "1e-100", "1e-300", "1e-308"):
        catalog = tmp_path / "objects.csv"
        catalog.write_text(f"{HEADER}\nA,8,5,4,2.1,{mu}\n", encoding="utf-8")
        res = cli.invoke(app, ["lift", "rig", str(catalog), "--command", _rig(1.0, log), "-o",
                               str(tmp_path / "x.parquet")])  # fmt: skip
        assert res.exit_code == 65, (mu, res.stderr)
        assert res.stderr.count("\n") == 1
        assert "friction_mu" in res.stderr
        assert "0.01" in res.stderr
    assert not log.exists()


# ---------------------------------------------------------------------------- the property


def _bounded(column: str) -> st.SearchStrategy[float]:
    low, high = BOUNDS[column]
    return st.floats(low, high, allow_nan=False, allow_infinity=False)


_ROW = st.fixed_dictionaries(
    {
        "size_x_cm": _bounded("size_x_cm"),
        "size_y_cm": _bounded("size_y_cm"),
        "size_z_cm": _bounded("size_z_cm"),
        "weight_n": _bounded("weight_n"),
        "friction_mu": _bounded("friction_mu"),
        # how many times F_w the object needs: 1 to a million (far beyond any ceiling)
        "needs_ratio": st.floats(1.0, 1e6),
        "max_force_n": st.none() | st.floats(1e-6, 1e308),
    }
)


@settings(max_examples=80, deadline=None)
@given(
    rows=st.lists(_ROW, min_size=1, max_size=4),
    flag=st.none() | st.floats(1e-6, 1e308),
    stated=st.none() | st.floats(1e-3, 1e6),
)
def test_no_request_ever_exceeds_the_limit(
    rows: list[dict[str, Any]], flag: float | None, stated: float | None
) -> None:
    catalog = pd.DataFrame(
        [
            {"object_id": f"O{i}", **{k: v for k, v in r.items() if k != "needs_ratio"}}
            for i, r in enumerate(rows)
        ]
    )
    if catalog["max_force_n"].isna().all():
        catalog = catalog.drop(columns="max_force_n")
    validate_frame(catalog, "catalog")  # a catalog the schema accepts
    needs = {f"O{i}": r["needs_ratio"] * r["weight_n"] / (2 * r["friction_mu"])
             for i, r in enumerate(rows)}  # fmt: skip
    sent: list[dict[str, Any]] = []

    def answer(self: RigRunner, payload: str, where: tuple[int, float]) -> str:
        request = json.loads(payload)
        sent.append(request)
        lifted = request["grip_force_n"] >= needs[request["object_id"]]
        return json.dumps({"lifted": lifted, "slip_m": 0.0 if lifted else 0.05})

    limit = absolute_limit(stated).max_force_n
    with (
        mock.patch.object(RigRunner, "_run", answer),
        mock.patch.object(rig_module, "rig_handshake", return_value=absolute_limit(stated)),
    ):
        factory = rig_runner_factory("rig", timeout_s=1)
        lift_catalog(catalog, factory, search=SearchOptions(max_force_n=flag))
    for request in sent:
        row = rows[int(request["object_id"][1:])]
        f_w_n = row["weight_n"] / (2 * row["friction_mu"])
        own = row["max_force_n"] if row["max_force_n"] is not None else flag
        relative = DEFAULT_CEILING_RATIO * f_w_n if own is None else own
        assert request["grip_force_n"] <= min(relative, limit)
        assert request["max_force_n"] <= limit
        assert request["grip_force_n"] <= request["max_force_n"]


def test_cli_a_bad_stated_maximum_stops_the_run_before_any_attempt(tmp_path: Path) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(f"{HEADER}\nA,8,5,4,2,0.5\n", encoding="utf-8")
    echo = shlex.join([sys.executable, str(RIGS / "echo_rig.py"), '{"max_force_n": -5}'])
    out, log = tmp_path / "lift.parquet", tmp_path / "lift.mcap"
    res = cli.invoke(
        app, ["lift", "rig", str(catalog), "--command", echo, "-o", str(out), "--log", str(log)]
    )
    assert res.exit_code == 1
    assert res.stderr == (
        "error: rig handshake: max_force_n must be a finite number > 0 (N), got -5\n"
    )
    assert not out.exists()
    assert not log.exists()
