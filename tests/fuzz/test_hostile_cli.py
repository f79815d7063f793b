"""The ``make fuzz`` driver (tests/fuzz/hostile_cli.py): a small seeded set is clean, and the
judge is not blind: it fails a traceback, two error lines, an output left on failure, a printed
force that is not one, an implausible prediction without its flag, and a unit slip accepted
without a warning."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from .hostile_cli import Case, _lift_force_ok, _prediction_ok, judge, run


def test_a_small_seeded_set_is_clean() -> None:
    clean, unclean = run(20, seed=1)  # two cases of each artifact kind
    assert unclean == []
    assert clean == 20


def _result(
    code: int, stderr: str = "", stdout: str = "", exc: BaseException | None = None
) -> object:
    return SimpleNamespace(exit_code=code, stderr=stderr, stdout=stdout, exception=exc)


def test_the_judge_fails_what_is_not_clean(tmp_path: Path) -> None:
    left = tmp_path / "out.parquet"
    left.write_bytes(b"half")
    case = Case("x", [], left)
    assert judge(case, _result(1, exc=ZeroDivisionError("boom"))) == "ZeroDivisionError: boom"
    assert judge(case, _result(65, "Traceback (most recent call last):\n")) == "traceback"
    assert judge(case, _result(65, "error: a\nerror: b\n")).startswith("not one error line")
    assert judge(case, _result(65, "error: a\n")) == "output written on failure"
    assert judge(Case("x", [], None), _result(65, "warning: w\nerror: a\n")) is None
    assert judge(case, _result(3, "error: a\n")) == "exit 3"
    slip = Case("recording N values under [kN]: measure", [], None, needs_warning=True)
    assert judge(slip, _result(0, "")) == "a unit slip passed without a warning naming the unit"
    warned = "warning: column 'Load [kN]': peak force 5e+03 N is above 3 kN for a soft object; "
    assert judge(slip, _result(0, warned + "plausible in N: is the unit right?\n")) is None
    lookup = _lift_force_ok(1.0, 100.0)
    assert lookup("interpolated lift_force_n: 3.4e+307 (inverse-distance ...)") is not None
    assert lookup("interpolated lift_force_n: 42 (inverse-distance ...)") is None
    csv = "f_w_n,predicted_lift_force_n\n2,500\n"
    assert _prediction_ok(csv) == "implausible L_f without prediction_implausible"
    assert (
        _prediction_ok("f_w_n,predicted_lift_force_n,prediction_implausible\n2,500,True\n") is None
    )
