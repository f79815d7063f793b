"""One rule per quantity (``deformctl.quantities``): its bounds, and the same words everywhere.

The rule itself is checked at its edges; then the same bad value is sent through every command
that takes the quantity (and through the library calls behind them): each refuses it with exit 2
and the one line the quantity writes, so no command accepts what another refuses.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from deformctl.catalog import CatalogObject, MeasuredObject
from deformctl.characterize import FitOptions, fit_lsq
from deformctl.cli import app
from deformctl.errors import EXIT_USAGE, InputDataError, UsageError
from deformctl.lift.options import SearchOptions
from deformctl.lift.search import find_min_lift_force
from deformctl.measure import CsvOptions, csv_objects
from deformctl.measure.options import SqueezeProtocol
from deformctl.population import make_population
from deformctl.quantities import (
    DAMPING_NS_PER_CM,
    FRICTION_MU,
    GROWTH,
    LIFT_ACCEL_M_S2,
    LIFT_HEIGHT_M,
    MAX_ATTEMPTS,
    PARTICLES_PER_SIDE,
    RAMP_S,
    SHEAR_DAMPING_RATIO,
    SIM_SLIP_TOLERANCE_M,
    SIZE_CM,
    STIFFNESS_N_PER_CM,
    TOLERANCE_REL,
    WEIGHT_N,
    WINDOW_S,
    Quantity,
)
from deformctl.series import SqueezeSeries, TrialOutcome

runner = CliRunner()


# ---------------------------------------------------------------------------- the rule


@pytest.mark.parametrize(
    ("quantity", "good", "bad"),
    [
        (
            FRICTION_MU,
            [0.01, 0.5, 3],
            [0.0, 1e-9, 0.0099, 1e-308, 3.0001, 10, -1, math.nan, math.inf, "0.5", None],
        ),
        (WEIGHT_N, [0.001, 5000], [0.0, -1, 5000.5, math.nan]),
        (SIZE_CM, [0.1, 200], [0.09, 201, math.inf]),
        (STIFFNESS_N_PER_CM, [0.01, 1e5], [0.0, 1e5 * 1.01]),
        (DAMPING_NS_PER_CM, [0.0, 1e4], [-1e-9, 1e4 + 1]),
        (WINDOW_S, [1e-9, 0.2, 10], [0.0, -0.2, math.nan, math.inf]),
        (RAMP_S, [1e-9, 0.25], [0.0, -1]),
        (GROWTH, [1.0001, 2], [1.0, 0.5, math.nan]),
        (TOLERANCE_REL, [1e-6, 0.5], [0.0, 1.0, -0.01]),
        (MAX_ATTEMPTS, [1, 50], [0, -1, 2.5, True, math.nan]),
        (PARTICLES_PER_SIDE, [2, 13], [1, 0, 4.5, math.inf]),
        (SHEAR_DAMPING_RATIO, [1e-9, 1.0], [0.0, 1.0001, -0.5, math.nan]),
        (LIFT_ACCEL_M_S2, [1e-9, 9.81], [0.0, -1, math.inf]),
        (LIFT_HEIGHT_M, [1e-9, 0.05], [0.0, -0.01, math.nan]),
        (SIM_SLIP_TOLERANCE_M, [0.0, 5e-4], [-1e-9, math.inf, math.nan]),
    ],
)
def test_each_rule_holds_at_its_edges(quantity: Quantity, good: list[Any], bad: list[Any]) -> None:
    for value in good:
        assert quantity.ok(value), (quantity.name, value)
        assert quantity.check(value) == value
    for value in bad:
        assert not quantity.ok(value), (quantity.name, value)
        with pytest.raises(UsageError) as info:
            quantity.check(value)
        assert str(info.value).startswith(f"{quantity.flag} must be {quantity.rule}"), value


def test_a_file_value_gets_the_same_rule_as_a_data_error() -> None:
    with pytest.raises(InputDataError) as info:
        FRICTION_MU.check_data(0.0, where="object 'A'", path="cat.csv")
    assert str(info.value) == (
        "cat.csv: object 'A': friction_mu = 0 is outside its physical bounds [0.01, 3]"
    )
    assert info.value.exit_code == 65
    assert FRICTION_MU.check_data(0.5, where="object 'A'") == 0.5


def test_the_catalog_bounds_are_the_quantities() -> None:
    from deformctl.catalog import BOUNDS, COLUMN_QUANTITIES

    assert BOUNDS["friction_mu"] == (FRICTION_MU.low, FRICTION_MU.high)
    assert COLUMN_QUANTITIES["size_z_cm"] is SIZE_CM
    assert COLUMN_QUANTITIES["material_damping_ns_per_cm"] is DAMPING_NS_PER_CM


# ---------------------------------------------------------------------------- every command


def _error(argv: list[str]) -> str:
    result = runner.invoke(app, argv)
    assert result.exit_code == EXIT_USAGE, (argv, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0]


def _csv(tmp: Path, *flags: str) -> list[str]:
    recording = ["--columns", "time=t,force=f,compression=c", "--object-id", "a"]
    return ["measure", "csv", str(tmp / "r.csv"), *recording, *flags, "-o", str(tmp / "o.mcap")]


def _bag(tmp: Path, *flags: str) -> list[str]:
    topics = ["--wrench-topic", "/w", "--position-topic", "/p", "--object-id", "a"]
    return ["measure", "bag", str(tmp / "b.mcap"), *topics, *flags, "-o", str(tmp / "o.mcap")]


def _images(tmp: Path, *flags: str) -> list[str]:
    photos = [str(tmp / "top.png"), str(tmp / "side.png"), "--marker-size-cm", "5"]
    return ["measure", "images", *photos, "--object-id", "a", *flags, "-o", str(tmp / "c.csv")]


def _population(tmp: Path, *flags: str) -> list[str]:
    return ["population", *flags, "-o", str(tmp / "c.csv")]


def _predict(tmp: Path, *flags: str) -> list[str]:
    given = dict(zip(flags[::2], flags[1::2], strict=True))
    features = {
        "--weight-n": "40",
        "--deformability-n-per-cm": "40",
        "--damping-ns-per-cm": "5",
        **given,
    }
    return ["predict", str(tmp / "model.skops"), *(x for kv in features.items() for x in kv)]


def _lib(call: Callable[[], object]) -> str:
    with pytest.raises(UsageError) as info:
        call()
    assert info.value.exit_code == EXIT_USAGE
    return f"error: {info.value}"


def _lifted(grip_force_n: float, attempt_index: int) -> TrialOutcome:
    return TrialOutcome(grip_force_n, grip_force_n >= 7.0, 0.0)


def test_friction_is_refused_alike_by_every_command(tmp_path: Path) -> None:
    """μ = 0: ``measure --csv`` used to accept what ``lift`` refused."""
    want = "error: --friction-mu must be a number in [0.01, 3], got 0"
    mu = ("--weight-n", "1", "--friction-mu", "0")
    assert _error(_csv(tmp_path, *mu)) == want
    assert _error(_bag(tmp_path, *mu)) == want
    assert _error(_images(tmp_path, *mu)) == want
    assert _error(_population(tmp_path, "--friction-mu", "0")) == want
    assert _error(_population(tmp_path, "--friction-mu", "0,0.5")) == want
    assert _error(_predict(tmp_path, "--friction-mu", "0")) == want
    assert _lib(lambda: MeasuredObject("a", 1.0, friction_mu=0.0)) == want
    assert _lib(lambda: make_population(3, seed=0, friction_mu=0.0)) == want
    assert _lib(lambda: csv_objects(["r.csv"], weight_n=1.0, friction_mu=0.0)) == want
    # read from a file: the same rule, as a data error naming where it was read (exit 65)
    rule = "friction_mu = 0 is outside its physical bounds [0.01, 3]"
    assert _mapped(tmp_path, "friction_mu", "0") == f"line 2: {rule}"
    assert _predicted(friction_mu=0.0) == f"friction_mu must be {FRICTION_MU.rule}; it is 0 for A"


def test_friction_above_3_is_refused_alike_by_every_command(
    tmp_path: Path, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    """Μ > 3 is bad input, from a flag (exit 2) or a file (exit 65); μ = 3 is not."""
    want = "error: --friction-mu must be a number in [0.01, 3], got 3.5"
    assert _error(_csv(tmp_path, "--weight-n", "1", "--friction-mu", "3.5")) == want
    assert _error(_population(tmp_path, "--friction-mu", "0.5,3.5")) == want
    assert _error(_predict(tmp_path, "--friction-mu", "3.5")) == want
    assert _lib(lambda: MeasuredObject("a", 1.0, friction_mu=3.5)) == want
    assert _mapped(tmp_path, "friction_mu", "3.5") == (
        "line 2: friction_mu = 3.5 is outside its physical bounds [0.01, 3]"
    )
    want = "friction_mu must be a number in [0.01, 3]; it is 3.5 for A"
    assert _predicted(friction_mu=3.5) == want
    catalog = write_catalog(tmp_path / "cat.csv", [{**catalog_row, "friction_mu": 3.5}])
    result = runner.invoke(app, ["inspect", str(catalog)])  # the catalog spec states the bound
    assert result.exit_code == 65
    assert "'friction_mu'" in result.stderr
    assert "<= 3, got 3.5" in result.stderr
    with pytest.raises(
        InputDataError, match=r"friction_mu = 3.5 is outside its physical bounds \[0.01, 3\]"
    ):
        CatalogObject.from_row({**catalog_row, "friction_mu": 3.5})
    assert MeasuredObject("a", 1.0, friction_mu=3.0).friction_mu == 3.0


def test_the_operating_force_has_one_rule(tmp_path: Path) -> None:
    """``characterize --at-force-n`` and ``MaterialOptions(at_force_n=...)``: AT_FORCE_N's words."""
    from deformctl.characterize import MaterialOptions

    want = "error: --at-force-n must be a finite number > 0 N, got 0"
    log, out = str(tmp_path / "s.mcap"), str(tmp_path / "c.parquet")
    assert _error(["characterize", log, "-o", out, "--at-force-n", "0"]) == want
    assert _lib(lambda: MaterialOptions(at_force_n=0.0)) == want
    assert _lib(lambda: MaterialOptions(at_force_n=math.nan)).endswith("got nan")
    assert MaterialOptions(at_force_n=5).at_force_n == 5.0


def test_weight_is_refused_alike_by_every_command(tmp_path: Path) -> None:
    want = "error: --weight-n must be a number in [0.001, 5000] N, got 0"
    assert _error(_csv(tmp_path, "--weight-n", "0")) == want
    assert _error(_bag(tmp_path, "--weight-n", "0")) == want
    assert _error(_images(tmp_path, "--weight-n", "0", "--friction-mu", "0.5")) == want
    assert _error(_population(tmp_path, "--weight-n", "0")) == want
    assert _error(_predict(tmp_path, "--weight-n", "0")) == want
    assert _lib(lambda: MeasuredObject("a", 0.0)) == want
    assert _mapped(tmp_path, "weight_n", "0") == (
        "line 2: weight_n = 0 is outside its physical bounds [0.001, 5000]"
    )
    assert _predicted(weight_n=0.0) == f"weight_n must be {WEIGHT_N.rule}; it is 0 for A"


def test_size_is_refused_alike_by_every_command(tmp_path: Path) -> None:
    want = "error: --size-cm must be a number in [0.1, 200] cm, got 0"
    size = ("--weight-n", "1", "--size-cm", "0", "5", "5")
    assert _error(_csv(tmp_path, *size)) == want
    assert _error(_bag(tmp_path, *size)) == want
    assert _lib(lambda: MeasuredObject("a", 1.0, (0.0, 5.0, 5.0))) == want


def test_deformability_and_damping_are_refused_alike(tmp_path: Path) -> None:
    want_d = "error: --deformability-n-per-cm must be a number in [0.01, 100000] N/cm, got 0"
    assert _error(_population(tmp_path, "--deformability-n-per-cm", "0,40")) == want_d
    assert _error(_predict(tmp_path, "--deformability-n-per-cm", "0")) == want_d
    want_l = "error: --damping-ns-per-cm must be a number in [0, 10000] N·s/cm, got -1"
    assert _error(_population(tmp_path, "--damping-ns-per-cm", "-1,5")) == want_l
    assert _error(_predict(tmp_path, "--damping-ns-per-cm", "-1")) == want_l
    line = _predicted(deformability_n_per_cm=0.0)
    assert line == f"deformability_n_per_cm must be {STIFFNESS_N_PER_CM.rule}; it is 0 for A"
    # a fitted λ within 0.05 N·s/cm of 0 is noise and counts as 0; below it, the same rule
    assert _predicted(damping_ns_per_cm=-1.0).startswith(
        f"damping_ns_per_cm must be {DAMPING_NS_PER_CM.rule} (a fitted -0.05 counts as 0)"
    )


def test_the_window_has_one_text(tmp_path: Path, kv_squeeze: SqueezeSeries) -> None:
    """``--window-s`` had three texts: the file path, the sweep path and the estimators'."""
    want = "error: --window-s must be a finite number > 0 s, got 0"
    log, table = str(tmp_path / "s.mcap"), str(tmp_path / "c.parquet")
    assert _error(["characterize", log, "--window-s", "0", "-o", table]) == want
    sweep = ["characterize", str(tmp_path), "--window-s", "0", "-o", str(tmp_path / "out") + "/"]
    assert _error(sweep) == want
    assert _lib(lambda: FitOptions(window_s=0.0)) == want
    assert _lib(lambda: fit_lsq([kv_squeeze], window_s=0.0)) == want


def test_the_ramp_is_refused_by_the_library_too(tmp_path: Path) -> None:
    """``--ramp-s 0`` was refused by the command and accepted by the library."""
    want = (
        "error: --ramp-s must be a finite number > 0 s (a force step does not excite the "
        "damping), got 0"
    )
    catalog = str(tmp_path / "cat.csv")
    assert _error(["measure", "sim", catalog, "--ramp-s", "0", "-o", str(tmp_path / "s")]) == want
    assert _lib(lambda: SqueezeProtocol(ramp_s=0.0)) == want


def test_the_search_options_have_one_text(tmp_path: Path) -> None:
    catalog = str(tmp_path / "cat.csv")
    for flag, value, kwargs in (
        ("--growth", "1", {"growth": 1.0}),
        ("--tolerance", "0", {"tolerance_rel": 0.0}),
        ("--max-attempts", "0", {"max_attempts": 0}),
    ):
        argv = [
            "lift",
            "rig",
            catalog,
            "--command",
            "true",
            flag,
            value,
            "-o",
            str(tmp_path / "l.parquet"),
        ]
        line = _error(argv)
        assert line.startswith(f"error: {flag} must be "), line
        assert _lib(lambda kw=kwargs: SearchOptions(**kw)) == line  # type: ignore[misc]
        lib = _lib(
            lambda kw=kwargs: find_min_lift_force(  # type: ignore[misc]
                _lifted, weight_n=5.0, friction_mu=0.5, **kw
            )
        )
        assert lib == line


@pytest.mark.parametrize(
    ("flag", "want"),
    [
        ("--alpha-cm", "error: --alpha-cm must be a finite number > 0 cm, got -1"),
        ("--dt-s", "error: --dt-s must be a number in [1e-05, 0.05] s, got -1"),
        (
            "--memory-budget-gib",
            "error: --memory-budget-gib must be a finite number > 0 GiB, got -1",
        ),
    ],
)
def test_the_simulator_settings_have_one_text(tmp_path: Path, flag: str, want: str) -> None:
    from deformctl.presets import SimOptions
    from deformctl.sim import SimSettings

    catalog = str(tmp_path / "cat.csv")
    measure = ["measure", "sim", catalog, flag, "-1", "-o", str(tmp_path / "s.mcap")]
    lift = ["lift", "sim", catalog, flag, "-1", "-o", str(tmp_path / "l.parquet")]
    assert _error(measure) == _error(lift) == want
    name = flag[2:].replace("-", "_")
    assert _lib(lambda: SimSettings(**{name: -1.0})) == want
    assert _lib(lambda: SimOptions(**{name: -1.0})) == want
    if flag == "--memory-budget-gib":  # the CSV reader's budget is the same quantity
        want = "error: --memory-budget-gib must be a finite number > 0 GiB, got -1"
        assert _error(_csv(tmp_path, "--weight-n", "1", flag, "-1")) == _error(lift) == want
        assert _lib(lambda: CsvOptions(memory_budget_gib=-1)) == want


@pytest.mark.parametrize(
    ("flag", "field", "want"),
    [
        ("--lift-accel-m-s2", "accel_m_s2", "--lift-accel-m-s2 must be a finite number > 0 m/s²"),
        ("--lift-speed-m-s", "speed_m_s", "--lift-speed-m-s must be a finite number > 0 m/s"),
        ("--lift-height-m", "height_m", "--lift-height-m must be a finite number > 0 m"),
        ("--lift-hold-s", "hold_s", "--lift-hold-s must be a finite number >= 0 s"),
        ("--slip-tolerance-m", "tolerance_m", "--slip-tolerance-m must be a finite number >= 0 m"),
    ],
)
def test_the_lift_profile_and_slip_have_one_text(
    tmp_path: Path, flag: str, field: str, want: str
) -> None:
    """``lift sim``'s profile and slip flags, the options type behind them and the simulator's
    own types refuse a bad value with the one line of its rule."""
    from deformctl.presets import SimOptions
    from deformctl.sim import LiftProfile, SlipCriterion

    want = f"error: {want}, got -1"
    catalog = str(tmp_path / "cat.csv")
    assert _error(["lift", "sim", catalog, flag, "-1", "-o", str(tmp_path / "l.parquet")]) == want
    option = flag[2:].replace("-", "_")
    assert _lib(lambda: SimOptions(**{option: -1.0})) == want
    kind = SlipCriterion if field == "tolerance_m" else LiftProfile
    assert _lib(lambda: kind(**{field: -1.0})) == want


def test_the_coverage_and_the_lag_have_one_text(tmp_path: Path) -> None:
    from deformctl.predict import load_predictor

    want = "error: --coverage must be a number in (0, 1), got 1"
    assert _error([*_predict(tmp_path, "--friction-mu", "0.5"), "--coverage", "1"]) == want
    assert _lib(lambda: load_predictor("grip").margin(1.0)) == want
    want = "error: --lag-s must be auto or a number in [-10, 10] s, got 11"
    assert _error(_csv(tmp_path, "--weight-n", "1", "--lag-s", "11")) == want
    assert _lib(lambda: CsvOptions(lag_s=11.0)) == want


def _mapped(tmp: Path, column: str, value: str) -> str:
    """The error line of ``measure --csv --objects-from`` with ``column`` = ``value``."""
    mapping = tmp / "map.csv"
    mapping.write_text(f"file,{column}\nr.csv,{value}\n")
    argv = [*_csv(tmp, "--weight-n", "1"), "--objects-from", str(mapping)]
    argv.remove("--object-id")
    argv.remove("a")
    result = runner.invoke(app, argv)
    assert result.exit_code == 65, result.stderr
    prefix = f"error: {mapping}: "
    (line,) = result.stderr.splitlines()
    assert line.startswith(prefix), line
    return line.removeprefix(prefix)


def _predicted(**bad: float) -> str:
    """The bundled model's refusal of one object with ``bad`` values (a data error)."""
    from deformctl.predict import load_predictor

    values = {"weight_n": 10.0, "deformability_n_per_cm": 20.0, "damping_ns_per_cm": 1.0}
    values |= {"friction_mu": 0.5, **bad}
    with pytest.raises(InputDataError) as info:
        load_predictor("grip").predict(**values, name="A")
    return info.value.message


@pytest.mark.parametrize(
    ("flag", "value", "want"),
    [
        ("--train-size", "1", "error: --train-size must be an integer >= 2, got 1"),
        ("--calibration-size", "-1", "error: --calibration-size must be an integer >= 0, got -1"),
        ("--hidden", "4,0", "error: --hidden must be an integer >= 1, got 0"),
        ("--seed", "-1", "error: --seed must be an integer >= 0, got -1"),
    ],
)
def test_the_training_options_have_one_text(
    tmp_path: Path, flag: str, value: str, want: str
) -> None:
    """Refused where :class:`TrainOptions` is built, before the index table is read (there is
    none here); the library's options type refuses the same value with the same words."""
    from deformctl.model import TrainOptions

    argv = ["train", str(tmp_path / "none.parquet"), flag, value, "-o", str(tmp_path / "m.skops")]
    assert _error(argv) == want
    name = flag[2:].replace("-", "_")
    given = tuple(int(v) for v in value.split(",")) if name == "hidden" else int(value)
    assert _lib(lambda: TrainOptions(**{name: given})) == want
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("options", "want"),
    [
        ({"restarts": 0}, "error: restarts must be an integer >= 1, got 0"),
        ({"max_iter": 0}, "error: max_iter must be an integer >= 1, got 0"),
        ({"alpha": -1e-4}, "error: alpha must be a finite number >= 0, got -0.0001"),
        ({"tol": 0.0}, "error: tol must be a finite number > 0, got 0"),
        ({"train_size": 2.5}, "error: --train-size must be an integer >= 2, got 2.5"),
        ({"hidden": ()}, "error: --hidden needs at least one layer size"),
        ({"target": "log"}, "error: target must be 'ratio' or 'direct', got 'log'"),
    ],
)
def test_the_library_only_training_options_are_refused_when_built(
    options: dict[str, Any], want: str
) -> None:
    from deformctl.model import TrainOptions

    assert _lib(lambda: TrainOptions(**options)) == want
