"""A command line that answers at once: ``import deformctl.cli``, ``deformctl
--help`` and every ``deformctl <command> --help`` import none of the heavy libraries; the
commands import them when they run. The timings are ``make bench``'s (bench/bench_startup.py):
wall times vary with the machine's load, the imports do not.

Each check runs in a fresh interpreter (a subprocess), because this test session has imported
everything already.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

from deformctl.cli import COMMAND_NAMES, app, build_app, listed_command

#: Imported only by the commands that run on them: data frames and Parquet (pandas, pyarrow),
#: the model (scikit-learn, skops), the simulator (numba, scipy), images (OpenCV), sweeps (Dask),
#: plots (matplotlib), logs and their validation (mcap, jsonschema).
HEAVY = ("pandas", "pyarrow", "sklearn", "skops", "numba", "scipy", "cv2", "dask",
         "distributed", "matplotlib", "mcap", "jsonschema")  # fmt: skip
#: Nor these, which a help does not need either: numpy (the options' defaults live in modules
#: without it), pydantic (typer imports it to coerce option values, which a help does not) and
#: rich (the progress bars).
HELP_TOO = ("numpy", "pydantic", "rich")

#: Runs ``deformctl ARGS --help`` for the top level, then for each command, in one interpreter,
#: and prints which watched modules were loaded after each (a module, once loaded, stays).
HELPS = """
import contextlib, io, json, sys
from deformctl.cli import COMMAND_NAMES, main
watch = sys.argv[1].split(",")
loaded = {}
subcommands = [["measure", s] for s in ("sim", "csv", "bag", "images")] + [["lift", "sim"],
               ["lift", "rig"]]
for args in [[], *[[name] for name in COMMAND_NAMES], *subcommands]:
    sys.argv = ["deformctl", *args, "--help"]
    with contextlib.redirect_stdout(io.StringIO()) as out:
        try:
            main()
        except SystemExit as stop:
            assert stop.code in (0, None), (args, stop.code)
    assert "Usage: deformctl" in out.getvalue(), args
    loaded[" ".join(args) or "--help"] = sorted(m for m in watch if m in sys.modules)
print(json.dumps(loaded))
"""


def _loaded_after(code: str, *args: str) -> object:
    proc = subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


def test_importing_the_cli_imports_no_heavy_library() -> None:
    code = (
        "import json, sys, deformctl.cli; "
        "print(json.dumps(sorted(m for m in sys.argv[1].split(',') if m in sys.modules)))"
    )
    assert _loaded_after(code, ",".join(HEAVY + HELP_TOO)) == []


def test_no_help_imports_a_heavy_library() -> None:
    loaded = _loaded_after(HELPS, ",".join(HEAVY + HELP_TOO))
    subcommands = ["measure sim", "measure csv", "measure bag", "measure images", "lift sim"]
    helps = ["--help", *COMMAND_NAMES, *subcommands, "lift rig"]
    assert loaded == {name: [] for name in helps}


def test_the_watch_sees_a_command_that_runs(tmp_path: Path) -> None:
    # the check above can fail: running a command (not its help) loads what it runs on
    out = tmp_path / "paper.csv"
    code = (
        "import json, sys\n"
        "from deformctl.cli import main\n"
        f"sys.argv = ['deformctl', 'population', '--paper', '-o', {str(out)!r}]\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "print(json.dumps(sorted(m for m in ('pandas', 'numpy', 'pydantic') "
        "if m in sys.modules)))"
    )
    assert _loaded_after(code) == ["numpy", "pandas"]  # not pydantic (test_plain_values.py)
    assert out.is_file()


def test_the_listing_is_the_whole_apps_help() -> None:
    # deformctl --help lists stand-ins read from the command modules' source: same text
    runner = CliRunner()
    listing = build_app(COMMAND_NAMES, listed_command)
    for args in (["--help"], [], ["predic"], ["--version"]):
        whole, listed = runner.invoke(app, args), runner.invoke(listing, args)
        assert (listed.exit_code, listed.stdout, listed.stderr) == (
            whole.exit_code,
            whole.stdout,
            whole.stderr,
        ), args
    assert (
        "predict       Predict the minimum lifting force" in runner.invoke(listing, ["-h"]).stdout
    )
