"""The "too small" side of the plausibility checks, as flags with a line naming the unit.

Each unit slip of the issue is written as a CSV export of a known Kelvin–Voigt squeeze (10 N
peak, 3 mm compression, 100 Hz): the recording is read, flagged (``force_unit_doubtful``,
``compression_unit_doubtful``, ``time_unit_doubtful``) and warned about with the unit that makes
it plausible; the flags reach ``characterize``'s quality, so the fit is never ``ok``. The same
squeeze in its right units is silent.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.cli import app
from deformctl.measure import CsvOptions, read_recording
from deformctl.squeeze.flags import DOUBT_FLAGS

from ._exports import kv_squeeze, write_export

runner = CliRunner()


def _flags(path: Path) -> tuple[tuple[str, ...], tuple[str, ...]]:
    rec = read_recording(path, CsvOptions(), "A")
    return rec.flags, rec.warnings


def test_the_right_units_are_silent(tmp_path: Path) -> None:
    flags, warnings = _flags(write_export(tmp_path / "ok.csv", kv_squeeze()))
    assert not set(flags) & set(DOUBT_FLAGS)
    assert not any("doubt" in w or "plausible in" in w for w in warnings)


@pytest.mark.parametrize(
    ("names", "units", "flag", "head", "tail"),
    [
        # force in kN read as N (the column says N, the numbers are kN)
        (("Time (s)", "Load (N)", "Compression (mm)"), ("s", "kN", "mm"), "force_unit_doubtful",
         "column 'Load (N)': peak force ", " N is below 50 mN; plausible in kN"),
        # an (mN) label on N values
        (("Time (s)", "Load (mN)", "Compression (mm)"), ("s", "N", "mm"), "force_unit_doubtful",
         "column 'Load (mN)': peak force ", " N is below 50 mN; plausible in N"),
        # N values under a [kN] label (peak below the 10 kN refusal)
        (("Time (s)", "Load [kN]", "Compression (mm)"), ("s", "N", "mm"), "force_unit_doubtful",
         "column 'Load [kN]': peak force ", " N is above 3 kN for a soft object; plausible in N"),
        # compression in m under an (mm) label
        (("Time (s)", "Load (N)", "Compression (mm)"), ("s", "N", "m"), "compression_unit_doubtful",
         "column 'Compression (mm)': peak compression ", " µm is below 20 µm; plausible in m"),
        # ms stamps of a 2 kHz logger, no unit stated, read as seconds
        (("Time", "Load (N)", "Compression (mm)"), ("ms", "N", "mm"), "time_unit_doubtful",
         "column 'Time': time unit not stated and the sample rate is ",
         " Hz (below 10 Hz); plausible in ms"),
    ],
)  # fmt: skip
def test_each_unit_slip_is_flagged_naming_the_unit(
    tmp_path: Path, names: tuple[str, ...], units: tuple[str, ...], flag: str, head: str, tail: str
) -> None:
    squeeze = kv_squeeze(peak_n=5.0, rate_hz=2000.0, duration_s=2.0)  # a 2 kHz logger
    path = write_export(tmp_path / "slip.csv", squeeze, names=names, units=units, digits=9)
    flags, warnings = _flags(path)
    assert flag in flags
    tail += ": is the unit right?"
    assert [w for w in warnings if w.startswith(head) and w.endswith(tail)], warnings


def test_the_flag_reaches_characterize_quality(tmp_path: Path) -> None:
    csv = write_export(tmp_path / "kn.csv", kv_squeeze(), units=("s", "kN", "mm"), digits=9)
    log, table = tmp_path / "kn.mcap", tmp_path / "kn.parquet"
    res = runner.invoke(
        app, ["measure", "csv", str(csv), "--weight-n", "1", "-o", str(log), "--object-id", "A"]
    )
    assert res.exit_code == 0, res.stderr
    assert "warning:" in res.stderr
    assert "plausible in kN" in res.stderr
    res = runner.invoke(app, ["characterize", str(log), "-o", str(table), "--allow-flagged"])
    assert res.exit_code == 0, res.stderr
    quality = str(read_table(table, "coefficients")["quality"][0])
    assert "force_unit_doubtful" in quality
