"""Temporary files of killed writers, outputs committed together, and
the output checks made before any work.
"""

from __future__ import annotations

import os
import pty
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.artifacts import io as aio
from deformctl.cli import app
from deformctl.errors import DeformctlError, UsageError

runner = CliRunner()
DATA = Path(__file__).parents[1] / "data"
COEFS, LIFT, INDEX = (
    DATA / f"{k}.parquet" for k in ("coefficients", "lift_results", "index_table")
)
SQUEEZE = DATA / "squeeze_2x2.mcap"


def _one_line(stderr: str) -> str:
    assert stderr.startswith("error: "), stderr
    assert stderr.count("\n") == 1, stderr
    return stderr


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _write(out: Path, *extra: str) -> tuple[int, str]:
    """A command with no input file: ``population`` writes a small catalog to ``out``."""
    result = runner.invoke(app, ["population", "-n", "3", "-o", str(out), *extra])
    return result.exit_code, result.stderr


def test_stale_temporaries_of_dead_writers_go_on_the_next_run(tmp_path: Path) -> None:
    out = tmp_path / "t.parquet"
    stale = tmp_path / f".t.parquet.deformctl-{_dead_pid()}-0badc0de.tmp"
    alive = tmp_path / f".t.parquet.deformctl-{os.getpid()}-0badc0de.tmp"  # a writer still running
    other = tmp_path / f".u.parquet.deformctl-{_dead_pid()}-0badc0de.tmp"  # another output's
    for p in (stale, alive, other):
        p.write_bytes(b"half a file")
    result = runner.invoke(app, ["inspect", str(COEFS)])
    assert result.exit_code == 0
    code, _ = _write(out)
    assert code == 0
    assert out.exists()
    assert not stale.exists()
    assert alive.exists()
    assert other.exists()


def test_inspect_lists_stale_temporaries(tmp_path: Path) -> None:
    target = tmp_path / "c.parquet"
    shutil.copy(COEFS, target)
    stale = tmp_path / f".c.parquet.deformctl-{_dead_pid()}-0badc0de.tmp"
    stale.write_bytes(b"")
    result = runner.invoke(app, ["inspect", str(target)])
    assert result.exit_code == 0
    assert f"stale temporary file of a killed run: {stale}" in result.stderr
    result = runner.invoke(app, ["inspect", str(target), "--json"])
    assert str(stale) in result.stdout


KILLED_WRITER = """
import os, signal, sys
from deformctl.artifacts.io import atomic_output, committed_together
a, b = sys.argv[1:3]
with committed_together():
    with atomic_output(a) as tmp:
        tmp.write_bytes(b"first")
    with atomic_output(b) as tmp:
        tmp.write_bytes(b"second")
        os.kill(os.getpid(), signal.SIGKILL)
"""


def test_a_writer_killed_between_two_outputs_leaves_neither(tmp_path: Path) -> None:
    a, b = tmp_path / "lift.mcap", tmp_path / "lift.parquet"
    proc = subprocess.run([sys.executable, "-c", KILLED_WRITER, str(a), str(b)], check=False)
    assert proc.returncode == -signal.SIGKILL
    assert not a.exists()
    assert not b.exists()
    leftovers = sorted(p.name for p in tmp_path.iterdir())
    assert len(leftovers) == 2
    assert all(".deformctl-" in n and n.endswith(".tmp") for n in leftovers)
    code, _ = _write(b)  # the next run writing the table removes its leftover
    assert code == 0
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".lift.parquet")) == []


def test_a_failure_inside_committed_together_leaves_nothing(tmp_path: Path) -> None:
    a, b = tmp_path / "a.bin", tmp_path / "b.bin"

    def fail_second() -> None:
        with aio.committed_together():
            with aio.atomic_output(a) as tmp:
                tmp.write_bytes(b"a")
            raise RuntimeError("the second write failed")

    with pytest.raises(RuntimeError):
        fail_second()
    assert list(tmp_path.iterdir()) == []
    with aio.committed_together():
        for p in (a, b):
            with aio.atomic_output(p) as tmp:
                tmp.write_bytes(b"x")
        assert not a.exists()  # renamed only at the end of the block
    assert a.read_bytes() == b.read_bytes() == b"x"


def test_lift_log_without_its_table_is_never_left(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from deformctl.lift import stage

    def fail(*args: object, **kwargs: object) -> None:
        raise DeformctlError("disk full (simulated)")

    monkeypatch.setattr(stage, "write_table", fail)
    cat = tmp_path / "cat.csv"
    cat.write_text("object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu\nA,5,5,5,1,0.5\n")
    log, out = tmp_path / "lift.mcap", tmp_path / "lift.parquet"
    rig = Path(__file__).parents[1] / "rigs" / "threshold_rig.py"
    argv = [
        "lift",
        "rig",
        str(cat),
        "--command",
        f"{sys.executable} {rig}",
        "-o",
        str(out),
        "--log",
        str(log),
    ]
    result = runner.invoke(app, argv)
    assert result.exit_code == 1, result.output
    assert not log.exists()
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cat.csv"]


@pytest.mark.parametrize(
    "argv",
    [
        ["characterize", "IN", "-o", "IN", "--force"],
        ["train", "IN", "-o", "IN", "--force"],
        ["table", "IN", str(LIFT), "-o", "IN", "--force"],
        ["predict", "MODEL", "IN", "-o", "IN", "--force"],
        ["lift", "sim", "IN", "-o", "IN", "--force"],
    ],
    ids=["characterize", "train", "table", "predict", "lift"],
)
def test_an_output_that_is_an_input_is_refused(argv: list[str], tmp_path: Path) -> None:
    source = {"characterize": SQUEEZE, "train": INDEX, "table": COEFS, "predict": INDEX}.get(
        argv[0], DATA / "catalog.parquet"
    )
    inp = tmp_path / source.name
    shutil.copy(source, inp)
    before = inp.read_bytes()
    argv = [str(inp) if a == "IN" else a for a in argv]
    if argv[0] == "predict":
        from tests._helpers.models import _model

        argv[1] = str(_model(tmp_path / "m.skops"))
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.output
    assert "the output is one of the inputs" in _one_line(result.stderr)
    assert inp.read_bytes() == before


def test_a_symlink_to_the_input_is_the_input(tmp_path: Path) -> None:
    inp = tmp_path / "index.parquet"
    shutil.copy(INDEX, inp)
    (tmp_path / "link.parquet").symlink_to(inp)
    result = runner.invoke(app, ["train", str(inp), "-o", str(tmp_path / "link.parquet")])
    assert result.exit_code == 2
    assert "one of the inputs" in _one_line(result.stderr)
    assert inp.read_bytes() == INDEX.read_bytes()


@pytest.mark.parametrize("command", ["table", "train"])
def test_a_trailing_slash_is_not_a_plain_file(command: str, tmp_path: Path) -> None:
    out = str(tmp_path / "tab") + "/"
    argv = {
        "table": ["table", str(COEFS), str(LIFT), "-o", out],
        "train": ["train", str(INDEX), "-o", out],
    }[command]
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.output
    assert "ends in '/'" in _one_line(result.stderr)
    assert not (tmp_path / "tab").exists()


def test_a_name_too_long_for_the_file_system(tmp_path: Path) -> None:
    code, stderr = _write(tmp_path / ("x" * 250 + ".parquet"))
    assert code == 2
    assert "file name is" in _one_line(stderr)
    assert list(tmp_path.iterdir()) == []


def test_an_unwritable_folder_is_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    real = os.access
    monkeypatch.setattr(aio.os, "access", lambda p, m: False if m & os.W_OK else real(p, m))
    code, stderr = _write(tmp_path / "t.parquet")
    assert code == 1
    assert "is not writable" in _one_line(stderr)


def test_a_write_that_fails_midway_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from deformctl.artifacts import tables

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(tables.pq, "write_table", full)
    code, stderr = _write(tmp_path / "t.parquet")
    assert code == 1
    assert "No space left on device" in _one_line(stderr)
    assert list(tmp_path.iterdir()) == []


def test_file_size_limit_in_a_real_process(tmp_path: Path) -> None:
    import resource

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (1000, 1000))

    argv = [sys.executable, "-m", "deformctl", "population", "-n", "300"]
    proc = subprocess.run(
        [*argv, "-o", str(tmp_path / "t.parquet")],
        capture_output=True,
        text=True,
        preexec_fn=limit,
        check=False,
    )
    assert proc.returncode == 1, proc.stderr
    assert "cannot write" in _one_line(proc.stderr)
    assert list(tmp_path.iterdir()) == []


def test_binary_output_is_not_written_to_a_terminal(tmp_path: Path) -> None:
    leader, follower = pty.openpty()
    argv = [sys.executable, "-m", "deformctl", "population", "-n", "3", "-o", "-"]
    proc = subprocess.run(argv, stdout=follower, stderr=subprocess.PIPE, text=True, check=False)
    os.close(follower)
    os.close(leader)
    assert proc.returncode == 2
    assert "binary output to a terminal" in _one_line(proc.stderr)


def test_text_output_may_go_to_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    class Tty:
        def isatty(self) -> bool:
            return True

    monkeypatch.setattr(aio.sys, "stdout", Tty())
    assert aio.check_output_path("-", False, binary=False) == "-"
    with pytest.raises(UsageError, match="terminal"):
        aio.check_output_path("-", False)
