"""``--workers auto``: the chooser against known costs, the flag's one rule, the measuring.

The chooser is a pure function of the costs, so its answers are checked against wall times
worked out by hand. The measuring map (:func:`map_in_order` with ``"auto"``) is checked on
cheap tasks: a task of microseconds stays in the client, a task that sleeps long enough once
the start cost is known to be small goes to a pool, and the start cost it measured is kept.
About 7 s in all: one real pool start (the start cost it measures is the point) and one
simulated ``measure`` through the command line (numba's import, shared with other tests).
The 4- and 40-object timings are in ``make bench`` (bench/bench_workers.py).
"""

from __future__ import annotations

import json
import logging
import math
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.errors import UsageError
from deformctl.parallel import SweepOptions, map_in_order, single_file_workers
from deformctl.parallel import auto as auto_mod
from deformctl.parallel.auto import (
    GAIN_MARGIN,
    WorkerChoice,
    choose_workers,
    costs_path,
    measured_start_s,
    record_start_s,
    slowdown,
    task_kind,
)
from deformctl.parallel.options import parse_workers

runner = CliRunner()


@pytest.fixture(autouse=True)
def _own_cost_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Each test reads and writes its own measured costs, never the user's."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


# ---------------------------------------------------------------------------- the rule


def test_four_objects_stay_in_one_process_and_forty_use_both_cores() -> None:
    # 2 idle cores, 3 s to start the workers, 0.7 s per object (the paper preset's order)
    few = choose_workers(2, cores=2, start_s=3.0, per_object_s=0.7)
    assert few.workers == 1
    assert few.wall_1_s == pytest.approx(1.4)
    assert few.wall_n_s == pytest.approx(3.0 + 0.7)  # one object each on 2 processes
    assert few.best_n == 2
    assert "saves less than 15%" in few.reason
    many = choose_workers(38, cores=2, start_s=3.0, per_object_s=0.7)
    assert many.workers == 2
    assert many.wall_1_s == pytest.approx(26.6)
    assert many.wall_n_s == pytest.approx(3.0 + 19 * 0.7)


def test_more_processes_only_for_the_margin() -> None:
    # 10 objects of 1 s on 2 idle cores: wall(2) = start + 5 s against wall(1) = 10 s
    at_margin = (1 - GAIN_MARGIN) * 10.0 - 5.0  # the start cost that saves exactly the margin
    assert choose_workers(10, cores=2, start_s=at_margin - 1e-9, per_object_s=1.0).workers == 2
    assert choose_workers(10, cores=2, start_s=at_margin + 1e-6, per_object_s=1.0).workers == 1
    assert choose_workers(10, cores=2, start_s=0.0, per_object_s=1.0, margin=0.6).workers == 1


def test_the_count_of_least_wall_time_and_the_smaller_on_a_tie() -> None:
    # 5 objects of 1 s on 4 cores, 0.5 s start: 2 -> 3.5 s, 3 -> 2.5 s, 4 -> 2.5 s
    choice = choose_workers(5, cores=4, start_s=0.5, per_object_s=1.0)
    assert (choice.workers, choice.wall_n_s) == (3, pytest.approx(2.5))
    # never more processes than objects
    assert choose_workers(2, cores=8, start_s=0.0, per_object_s=5.0).workers == 2


def test_no_choice_with_one_object_or_one_core() -> None:
    one = choose_workers(1, cores=4, start_s=0.0, per_object_s=100.0)
    assert (one.workers, one.best_n, one.wall_n_s, one.reason) == (1, None, None, "one object left")
    core = choose_workers(50, cores=1, start_s=0.0, per_object_s=100.0)
    assert (core.workers, core.reason) == (1, "one core available")


def test_slowdown_of_a_fair_share_of_busy_cores() -> None:
    assert slowdown(2, 2, 0.0) == pytest.approx(1.0)  # idle: each process has its core
    # one other process on 2 cores: 1 process gets a core, 2 share 2 cores among 3 -> 2/3 each
    assert slowdown(2, 2, 1.0) == pytest.approx(1.5)
    # 3 others: 1 process gets 2/4 core, 2 get 4/5 core together -> 0.4 each
    assert slowdown(2, 2, 3.0) == pytest.approx(1.25)
    # the load makes a pool less worth it: 38 objects of 0.7 s, 3 s start
    idle = choose_workers(38, cores=2, start_s=3.0, per_object_s=0.7)
    busy = choose_workers(38, cores=2, start_s=3.0, per_object_s=0.7, busy=3.0)
    assert busy.wall_n_s == pytest.approx(3.0 + 19 * 0.7 * 1.25)
    assert busy.wall_n_s > idle.wall_n_s  # type: ignore[operator]


def test_a_chosen_pool_always_promises_the_margin() -> None:
    """Over a grid of costs and loads: more than one process only with wall(n) <= 85 % wall(1),
    and one process whenever the estimated pool time is not that much shorter."""
    for objects in (2, 3, 4, 8, 40, 400):
        for cores in (2, 4):
            for start_s in (0.0, 0.5, 3.0, 10.0):
                for per_object_s in (0.001, 0.1, 0.7, 5.0):
                    for busy in (0.0, 1.0, 4.0):
                        c = choose_workers(
                            objects, cores=cores, start_s=start_s,
                            per_object_s=per_object_s, busy=busy,
                        )  # fmt: skip
                        if c.workers > 1:
                            assert c.wall_n_s <= (1 - GAIN_MARGIN) * c.wall_1_s + 1e-12
                        elif c.wall_n_s is not None:
                            assert c.wall_n_s > (1 - GAIN_MARGIN) * c.wall_1_s


def test_the_choice_as_a_record_and_a_line() -> None:
    choice = choose_workers(38, cores=2, start_s=3.0, per_object_s=0.7, start_measured=False)
    record = choice.as_dict()
    assert record["requested"] == "auto"
    assert record["workers"] == 2
    assert record["objects"] == 38
    assert record["start_measured"] is False
    json.dumps(record)  # serialisable
    assert choice.line().startswith("workers: auto chose 2 processes: 38 objects at 0.70 s")
    assert "start 3.0 s assumed" in choice.line()
    assert choice.note() == "workers auto: 2 (est. 26.6 s on 1 vs 16.3 s on 2, start 3.0 s assumed)"


# ---------------------------------------------------------------------------- the flag


@pytest.mark.parametrize(
    ("value", "parsed"), [("auto", "auto"), ("AUTO", "auto"), (" 3 ", 3), (2, 2), ("1", 1)]
)
def test_workers_accepts_auto_or_a_count(value: int | str, parsed: int | str) -> None:
    assert parse_workers(value) == parsed
    assert SweepOptions(workers=value).workers == parsed


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("0", "--workers must be >= 1, got 0"),
        (-1, "--workers must be >= 1, got -1"),
        ("abc", "--workers must be auto or a whole number >= 1, got 'abc'"),
        ("1.5", "--workers must be auto or a whole number >= 1, got '1.5'"),
        (True, "--workers must be auto or a whole number >= 1, got True"),
    ],
)
def test_workers_refuses_anything_else(value: int | str, message: str) -> None:
    with pytest.raises(UsageError) as err:
        parse_workers(value)
    assert str(err.value) == message


def test_auto_is_not_a_flag_given() -> None:
    assert SweepOptions(workers="auto").given() == []
    assert SweepOptions(workers=2).given() == ["--workers"]
    # auto (the default) with a scheduler is no conflict; a count is
    auto_on_dask = SweepOptions(workers="auto", scheduler="tcp://h:1")
    assert auto_on_dask.run_kwargs()["workers"] == "auto"
    with pytest.raises(UsageError, match="not both"):
        SweepOptions(workers=2, scheduler="tcp://h:1").check("out/")
    assert single_file_workers("auto", 5) == "auto"
    assert single_file_workers(None, 5) == "auto"
    assert single_file_workers("auto", 1) == 1


# ---------------------------------------------------------------------------- the measuring


def test_a_cheap_task_stays_in_the_client(caplog: pytest.LogCaptureFixture) -> None:
    seen: list[int] = []
    with caplog.at_level(logging.INFO, logger="deformctl.parallel"):
        out = map_in_order(
            abs, [-3, 4, -5, 6], workers="auto", on_result=lambda i, _: seen.append(i)
        )
    assert out == [3, 4, 5, 6]
    assert seen == [0, 1, 2, 3]
    (record,) = [r for r in caplog.records if hasattr(r, "worker_choice")]
    choice: WorkerChoice = record.worker_choice  # type: ignore[attr-defined]
    assert choice.workers == 1
    assert choice.objects == 2  # two ran first, to be timed
    assert choice.start_measured is False  # nothing measured yet on this "machine"
    assert not costs_path().exists()  # no pool, nothing measured


def test_a_pool_is_chosen_from_a_measured_start_cost_and_the_cost_is_kept(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    kind = task_kind(time.sleep)
    record_start_s(kind, 0.0, 2)  # as if measured: workers start for free
    monkeypatch.setattr(auto_mod, "machine_load", lambda: 0.0)
    monkeypatch.setattr("deformctl.parallel.sweep.machine_load", lambda: 0.0)
    monkeypatch.setattr("deformctl.parallel.sweep._available_cores", lambda: 2)
    with caplog.at_level(logging.INFO, logger="deformctl.parallel"):
        out = map_in_order(time.sleep, [0.2] * 6, workers="auto")
    assert out == [None] * 6
    (record,) = [r for r in caplog.records if hasattr(r, "worker_choice")]
    assert record.worker_choice.workers == 2  # type: ignore[attr-defined]
    measured = measured_start_s(kind)
    assert measured is not None
    assert measured > 0.0  # the pool's real start, now kept
    assert json.loads(costs_path().read_text())[kind]["workers"] == 2


def test_the_cost_cache_survives_a_bad_file_and_a_read_only_home(tmp_path: Path) -> None:
    path = costs_path()
    path.parent.mkdir(parents=True)
    path.write_text("not json")
    assert measured_start_s("x") is None
    record_start_s("x", 1.25, 2)
    assert measured_start_s("x") == 1.25
    record_start_s("x", math.nan, 2)  # ignored
    assert measured_start_s("x") == 1.25
    record_start_s("x", 2.25, 2)  # averaged with the one kept
    assert measured_start_s("x") == 1.75
    path.write_text(json.dumps({"x": {"start_s": -1}}))
    assert measured_start_s("x") is None
    path.unlink()
    path.parent.chmod(0o500)
    try:
        record_start_s("y", 1.0, 2)  # no error: the cache is a hint
    finally:
        path.parent.chmod(0o700)


# ---------------------------------------------------------------------------- the commands

_HEADER = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\n"
)
_FAST = ["--alpha-cm", "5", "--dt-s", "0.002", "--squeezes", "1", "--ramp-s", "0.05",
         "--hold-s", "0.05"]  # fmt: skip


def _catalog(tmp_path: Path, n: int) -> Path:
    path = tmp_path / "cat.csv"
    rows = [f"o{i},10,10,10,{2 + i},0.5,{10 + 5 * i},0.2" for i in range(n)]
    path.write_text(_HEADER + "\n".join(rows) + "\n")
    return path


def test_measure_sim_takes_workers_auto_and_says_what_it_chose(tmp_path: Path) -> None:
    cat = _catalog(tmp_path, 3)
    out = tmp_path / "s.mcap"
    result = runner.invoke(
        app, ["measure", "sim", str(cat), "-o", str(out), "--workers", "auto", *_FAST]
    )
    assert result.exit_code == 0, result.stderr
    line = result.stderr.strip().splitlines()[-1]
    assert line.startswith("measure: 3 object(s) done")
    # 3 objects: 2 timed in the client, then one left: nothing to choose
    assert line.endswith("; workers auto: 1 (one object left))")
    assert out.exists()


@pytest.mark.parametrize("value", ["0", "-1", "abc"])
def test_a_bad_workers_value_is_one_line_and_exit_2(tmp_path: Path, value: str) -> None:
    cat = _catalog(tmp_path, 2)
    for argv in (
        ["measure", "sim", str(cat), "-o", str(tmp_path / "s.mcap"), *_FAST],
        ["lift", "sim", str(cat), "-o", str(tmp_path / "l.parquet")],
        ["characterize", str(cat), "-o", str(tmp_path / "c/")],
    ):
        result = runner.invoke(app, [*argv, "--workers", value])
        assert result.exit_code == 2, (argv, result.stderr)
        err = result.stderr.strip()
        assert err.startswith("error: --workers must be"), err
        assert "\n" not in err
    assert sorted(p.name for p in tmp_path.iterdir() if p.name != "cache") == ["cat.csv"]


class _Called(Exception):
    pass


@pytest.mark.parametrize(
    ("library", "argv"),
    [
        ("deformctl.measure.stage.simulate_catalog_file", ["measure", "sim", "-o", "s.mcap"]),
        ("deformctl.lift.stage.lift_catalog_files", ["lift", "sim", "-o", "l.parquet"]),
        ("deformctl.measure.csv.batch.measure_csv_files",
         ["measure", "csv", "--columns", "time=t,force=f,compression=c", "--weight-n", "1",
          "-o", "s.mcap"]),
    ],
)  # fmt: skip
def test_the_commands_default_is_the_librarys(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, library: str, argv: list[str]
) -> None:
    import importlib
    import inspect

    module, name = library.rsplit(".", 1)
    default = (
        inspect.signature(getattr(importlib.import_module(module), name))
        .parameters["workers"]
        .default
    )
    seen: dict[str, object] = {}

    def recorder(*args: object, **kwargs: object) -> None:
        seen.update(kwargs)
        raise _Called

    monkeypatch.setattr(library, recorder)
    monkeypatch.chdir(tmp_path)
    for name in ("a.csv", "b.csv"):  # two recordings: a single one is read in the client
        (tmp_path / name).write_text("t,f,c\n0,0,0\n")
    command, source, *rest = argv
    inputs = ["a.csv", "b.csv"] if source == "csv" else [str(_catalog(tmp_path, 2))]
    result = runner.invoke(app, [command, source, *inputs, *rest])
    assert isinstance(result.exception, _Called), result.stderr
    assert default == "auto"
    assert seen["workers"] == default


def _cheap_probes_then_dear(seconds: float) -> float:
    """A task whose first objects are cheap and the rest dear (the probe underestimates)."""
    time.sleep(seconds)
    return seconds


def test_a_cheap_probe_does_not_keep_a_dear_catalog_in_one_process(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    # known truth, worked by hand: start 0.5 s (as if measured), 2 idle cores; after the two
    # probes of 0.01 s, 20 objects left: one process 0.2 s, two 0.6 s: one process. After the
    # first dear object (0.25 s) the mean of the timed objects is 0.13 s: 19 left, one process
    # 2.47 s, two 0.5 + 10 x 0.13 = 1.8 s, more than 15 % less: the pool, with 19 objects left.
    kind = task_kind(_cheap_probes_then_dear)
    record_start_s(kind, 0.5, 2)
    monkeypatch.setattr(auto_mod, "machine_load", lambda: 0.0)
    monkeypatch.setattr("deformctl.parallel.sweep.machine_load", lambda: 0.0)
    monkeypatch.setattr("deformctl.parallel.sweep._available_cores", lambda: 2)
    items = [0.01, 0.01] + [0.25] * 20
    first = choose_workers(20, cores=2, start_s=0.5, per_object_s=0.01)
    assert first.workers == 1  # the rule on the probes alone
    seen: list[int] = []
    with caplog.at_level(logging.INFO, logger="deformctl.parallel"):
        out = map_in_order(
            _cheap_probes_then_dear, items, workers="auto", on_result=lambda i, _: seen.append(i)
        )
    assert out == items
    assert seen == list(range(len(items)))  # every object once, in order
    (record,) = [r for r in caplog.records if hasattr(r, "worker_choice")]
    choice: WorkerChoice = record.worker_choice  # type: ignore[attr-defined]
    assert choice.workers == 2
    assert choice.objects == 19


def test_the_load_is_the_runnable_count_now_less_the_reader(tmp_path: Path) -> None:
    # known truth: the kernel's fourth field counts the reader itself; a lagging average is
    # not read where the count exists
    fake = tmp_path / "loadavg"
    fake.write_text("7.50 6.00 5.00 3/120 4242\n")
    assert auto_mod.machine_load(str(fake)) == 2.0
    fake.write_text("7.50 6.00 5.00 1/120 4242\n")
    assert auto_mod.machine_load(str(fake)) == 0.0  # alone: no other load
    # no such file (not Linux): the 1-minute load average, a number >= 0
    assert auto_mod.machine_load(str(tmp_path / "absent")) >= 0.0
