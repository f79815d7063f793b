"""Plain option values skip pydantic and come out as typer's pydantic coercion makes them.

``deformctl.cli._plain_values`` coerces the values a command line usually holds (text, decimal
numbers, defaults of the option's own type) itself and leaves everything else to typer: each
value it takes must be the one typer's adapter returns, type and all, and a short command
(``population``, ``inspect``) then runs without importing pydantic, nor jsonschema (a valid
artifact passes the fast checks).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from typer._adapters import try_build_adapter
from typer._click import Context
from typer._coercion import build_runtime_param
from typer.main import get_command
from typer.models import OptionInfo

from deformctl.cli import COMMAND_NAMES, build_app
from deformctl.cli._plain_values import NOT_PLAIN, PlainFirst, install, plain_value

TEXTS = ("1", "0", "-0", "7", "-12", "007", "1_000", " 1", "1 ", "+1", "0x10", "1.5", "-0.25",
         "1e3", "1E-3", "2.5e+2", "1.", ".5", "1e400", "-1e400", "1e-400", "nan", "inf", "-inf",
         "123456789012345678", "1234567890123456789012", "0.1000000000000000055511151231257827",
         "", "abc", "1,5", "true", "1.0")  # fmt: skip
OTHERS: tuple[Any, ...] = (0, 3, -2, True, False, 0.5, -0.0, 2.0, math.inf, None, b"1")


def _same(a: Any, b: Any) -> bool:
    """Equal, of the same type, and for floats the same bits (the sign of zero, NaN)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float):
        return a.hex() == b.hex() if not math.isnan(a) else math.isnan(b)
    return bool(a == b)


@pytest.mark.parametrize("annotation", [str, int, float, bool])
def test_a_plain_value_is_the_one_typers_adapter_gives(annotation: type) -> None:
    adapter = try_build_adapter(annotation, OptionInfo())
    assert adapter is not None
    taken = 0
    for value in (*TEXTS, *OTHERS):
        plain = plain_value(annotation, value, multiple=False)
        if plain is NOT_PLAIN:
            continue
        taken += 1
        assert _same(plain, adapter.validate_python(value)), (annotation, value, plain)
    # the check can fail: most decimal texts (and values of the type itself) are taken
    assert taken >= {str: 32, int: 9, float: 17, bool: 2}[annotation]


def test_a_repeated_text_option_is_a_list_of_its_texts() -> None:
    adapter = try_build_adapter(list[str], OptionInfo())
    assert adapter is not None
    for value in [("a", "b"), ["x"], ()]:
        plain = plain_value(list[str], value, multiple=True)
        assert plain == adapter.validate_python(value) == list(value)
        assert type(plain) is list
    assert plain_value(list[str], ("a", 1), multiple=True) is NOT_PLAIN
    assert plain_value(list[int], ("1",), multiple=True) is NOT_PLAIN


@pytest.mark.parametrize("annotation", [tuple[float, float, float], tuple[str, str]])
def test_a_fixed_tuple_of_plain_values_is_a_tuple_of_them(annotation: Any) -> None:
    adapter = try_build_adapter(annotation, OptionInfo())
    assert adapter is not None
    taken = 0
    for value in [("1", "2.5", "-3"), ("6", "6"), ("a", "b"), ("1", "x", "2"), ("1", "2", "3", "4"),
                  (1.0, 2.0, 3.0), ["0.5", "1e2", "7"], ("1_0", "2", "3")]:  # fmt: skip
        plain = plain_value(annotation, value, multiple=False)
        if plain is NOT_PLAIN:
            continue
        taken += 1
        expected = adapter.validate_python(value)
        assert type(plain) is tuple, (value, plain)
        assert len(plain) == len(expected), (value, plain)
        assert all(_same(a, b) for a, b in zip(plain, expected, strict=True)), (value, plain)
    assert taken >= 2


def _all_commands() -> list[Any]:
    """Every command that runs (with its group's parameters too)."""
    found: list[Any] = []

    def walk(command: Any) -> None:
        found.append(command)
        for sub in getattr(command, "commands", {}).values():
            walk(sub)

    walk(get_command(build_app(COMMAND_NAMES)))
    return found


def test_every_parameters_default_coerces_as_typer_coerces_it() -> None:
    plain = 0
    for command in _all_commands():
        install(command)
        ctx = Context(command)
        for param in command.params:
            ours = param._runtime_param
            if not isinstance(ours, PlainFirst):
                continue
            plain += 1
            theirs = build_runtime_param(param.type_descriptor)
            for value in (param.default, "1", "2.5"):
                try:
                    expected = theirs.coerce(value, param=param, ctx=ctx)
                except Exception as err:  # typer refuses it: so does the plain coercion
                    with pytest.raises(type(err)):
                        ours.coerce(value, param=param, ctx=ctx)
                    continue
                got = ours.coerce(value, param=param, ctx=ctx)
                assert _same(got, expected), (command.name, param.name, value, got, expected)
    assert plain > 150  # nearly every parameter of the command line


def test_a_value_typer_refuses_gets_typers_message(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "deformctl", "population", "--seed", "-1", "-o", "x.csv"],
        cwd=tmp_path, capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert proc.returncode == 2
    assert proc.stderr == (
        "error: deformctl population: invalid value for '--seed': Input should be greater than "
        "or equal to 0 (see 'deformctl population --help')\n"
    )


#: runs ``deformctl population --paper -o FILE`` then ``deformctl inspect FILE`` in one
#: interpreter and prints which of the watched modules were loaded
RUN_BOTH = """
import contextlib, io, json, sys
from deformctl.cli import main
out = sys.argv[1]
for args in (["population", "--paper", "--seed", "3", "-o", out], ["inspect", out]):
    sys.argv = ["deformctl", *args]
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        try:
            main()
        except SystemExit as stop:
            assert stop.code in (0, None), (args, stop.code)
print(json.dumps({"printed": printed.getvalue(),
                  "loaded": sorted(m for m in ("pydantic", "jsonschema", "pandas")
                                   if m in sys.modules)}))
"""


def test_a_short_command_imports_neither_pydantic_nor_jsonschema(tmp_path: Path) -> None:
    out = tmp_path / "objects.csv"
    proc = subprocess.run(
        [sys.executable, "-c", RUN_BOTH, str(out)], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.splitlines()[-1])
    assert "catalog" in result["printed"]  # both ran: inspect read what population wrote
    assert result["loaded"] == ["pandas"]  # the watch sees what the commands run on
