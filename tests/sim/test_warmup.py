"""The first simulated run of an install says it compiles, once; warmup does it first."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.sim import ObjectSpec, SimSettings, first_use, squeeze
from deformctl.sim.protocols import compile_kernels

SPEC = ObjectSpec("cube", (4.0, 4.0, 4.0), 1.0, 0.5, 10.0, 0.5)


@pytest.fixture
def fresh_marker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A process whose kernels count as never compiled: its marker is a file that does not exist
    yet (numba's real cache still serves the kernels, so the warm-up runs in about a second)."""
    marker = tmp_path / "cache" / "deformctl-kernels-test.compiled"
    monkeypatch.setattr(first_use, "marker_path", lambda: marker)
    monkeypatch.setattr(first_use, "_CHECKED", False)
    return marker


def test_the_first_run_says_it_compiles_on_one_line_then_never_again(fresh_marker: Path) -> None:
    err = io.StringIO()
    assert first_use.ensure_compiled(compile_kernels, err) is True
    lines = err.getvalue().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("deformctl: compiling the simulator's kernels once")
    assert "'deformctl warmup'" in lines[0]
    seconds = float(lines[0].rsplit("done in ", 1)[1].removesuffix(" s"))
    assert seconds > 0
    assert fresh_marker.exists()
    again = io.StringIO()
    assert first_use.ensure_compiled(compile_kernels, again) is False  # this process
    first_use._CHECKED = False
    assert (
        first_use.ensure_compiled(compile_kernels, again) is False
    )  # a later process: the marker is there
    assert again.getvalue() == ""


def test_a_simulated_run_checks_first(
    fresh_marker: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    squeeze(
        SPEC,
        peak_force_n=1.0,
        ramp_s=0.01,
        hold_s=0.01,
        settings=SimSettings(particles_per_side=4, grip_settle_s=0.01),
    )
    assert "compiling the simulator's kernels once" in capsys.readouterr().err
    assert fresh_marker.exists()


def test_the_real_marker_lives_beside_numbas_cache_and_names_the_sources() -> None:
    from deformctl.sim._kernel_cache import sources_digest

    marker = first_use.marker_path()
    assert marker is not None
    assert sources_digest()[:16] in marker.name


def test_warmup_command(fresh_marker: Path) -> None:
    from deformctl.cli import app

    result = CliRunner().invoke(app, ["warmup"])
    assert result.exit_code == 0, result.output
    assert "compiled or loaded in" in result.stderr
    assert fresh_marker.exists()
