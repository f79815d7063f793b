"""The ``make fuzz`` driver (tests/fuzz/hostile_cli.py): a small seeded set is clean, and the
judge is not blind: it fails a traceback, two error lines, an output left on failure, a printed
force that is not one, an implausible prediction without its flag, and a unit slip accepted
without a warning."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from .hostile_cli import Case, _lift_force_ok, _prediction_ok, judge, run


def test_a_small_seeded_set_is_clean() -> None:
    clean, unclean = run(20, seed=1)  # the first 20 artifact kinds, one case each
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


def test_the_judge_holds_each_case_to_its_right_verdict() -> None:
    refused = Case("x", [], None, expect=(65,))
    assert judge(refused, _result(0)) is not None  # a tampered file accepted
    assert judge(refused, _result(2, "error: a\n")).startswith("exit 2, expected 65")
    assert judge(refused, _result(65, "error: a\n")) is None
    flagged = Case("x", [], None, stderr_needs="energy_returned")
    assert judge(flagged, _result(0, "")) == "exit 0 without 'energy_returned' on stderr"
    assert judge(flagged, _result(0, "warning: ... (flagged energy_returned)\n")) is None
    over = Case("x", [], None, after=lambda: "request of 600 N above min(50, 500)")
    assert judge(over, _result(0)) == "request of 600 N above min(50, 500)"


def test_every_class_of_the_second_run_is_in_the_harness() -> None:
    from .hostile_cases import CLASSES, ELSEWHERE
    from .hostile_cli import KINDS

    assert set(CLASSES) <= set(KINDS)
    assert set(ELSEWHERE) <= set(CLASSES)
    assert len(CLASSES) == 17
