"""Exports as they come: any line ends, blank lines, preambles, giant cells and text columns are
read (or refused with one line), never a traceback; the force's sign and a position column's
reading are what the instrument meant, and each run says which it used.

Known truth: a Kelvin–Voigt squeeze (``kv_squeeze``, D = 20 N/cm) and the shared phantom file
``EF10_0T_A1`` read as written (its own numbers are the truth for the line-end copies).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, InputDataError
from deformctl.measure import read_recording
from deformctl.measure.csv.batch import CsvFile, CsvFileTask, dataset_notices, summary_row
from deformctl.measure.csv.options import CsvOptions

from .._exports import Squeeze, kv_squeeze, write_export

runner = CliRunner()
PHANTOM = Path(__file__).resolve().parents[3] / "datasets" / "examples" / "phantom"


@pytest.fixture(scope="module")
def squeeze() -> Squeeze:
    return kv_squeeze()


def _same(got: np.ndarray, want: np.ndarray) -> None:
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)


@pytest.mark.parametrize("end", ["\r\n", "\r", "\n"])
@pytest.mark.parametrize("preamble", [0, 3, 7])
def test_line_ends_with_a_preamble(
    tmp_path: Path, squeeze: Squeeze, end: str, preamble: int
) -> None:
    path = write_export(
        tmp_path / "x.csv", squeeze, preamble=[f"Key {k}: {k}" for k in range(preamble)]
    )
    path.write_bytes(path.read_bytes().replace(b"\n", end.encode()))
    rec = read_recording(path, CsvOptions(), "x")
    s = rec.squeezes[0]
    assert s.time_s.shape == squeeze.t.shape
    _same(s.force_n, squeeze.f)
    assert rec.details["layout"]["header_line"] == preamble + 1


@pytest.mark.parametrize("end", [b"\r\n", b"\r"])
def test_a_crlf_or_cr_copy_of_a_phantom_file_reads_as_the_original(
    tmp_path: Path, end: bytes
) -> None:
    original = read_recording(PHANTOM / "EF10_0T_A1.csv", CsvOptions(), "p").squeezes[0]
    copy = tmp_path / "copy.csv"
    copy.write_bytes((PHANTOM / "EF10_0T_A1.csv").read_bytes().replace(b"\n", end))
    got = read_recording(copy, CsvOptions(), "p").squeezes[0]
    np.testing.assert_array_equal(got.force_n, original.force_n)
    np.testing.assert_array_equal(got.compression_m, original.compression_m)


def test_blank_first_lines_and_blank_lines_in_the_preamble(
    tmp_path: Path, squeeze: Squeeze
) -> None:
    path = write_export(tmp_path / "x.csv", squeeze, preamble=["", "", "Sample: A", ""])
    rec = read_recording(path, CsvOptions(), "x")
    _same(rec.squeezes[0].force_n, squeeze.f)
    assert rec.details["preamble"] == {"Sample": "A"}


def test_a_cell_over_128_kib_in_the_preamble_is_read_past(tmp_path: Path, squeeze: Squeeze) -> None:
    path = write_export(tmp_path / "x.csv", squeeze, preamble=["Notes: " + "x" * 140_000])
    rec = read_recording(path, CsvOptions(), "x")
    _same(rec.squeezes[0].force_n, squeeze.f)


def test_300_kb_of_zeros_on_stdin_is_one_error_line(tmp_path: Path) -> None:
    out = tmp_path / "z.mcap"
    res = runner.invoke(
        app,
        ["measure", "csv", "-", "--object-id", "z", "--weight-n", "1", "-o", str(out)],
        input="0" * 300_000,
    )
    assert res.exit_code == EXIT_DATAERR
    assert res.stderr.startswith("error: <stdin>: no rows of numbers")
    assert res.stderr.count("\n") == 1
    assert not out.exists()


def test_a_text_column_beside_the_numbers_is_left_out(tmp_path: Path, squeeze: Squeeze) -> None:
    steps = ["load" if t < 4 else "unload" for t in squeeze.t]
    rows = [
        f"{t:.4f},{f:.6f},{s},{1e3 * d:.6f}"
        for t, f, s, d in zip(squeeze.t, squeeze.f, steps, squeeze.d, strict=True)
    ]
    path = tmp_path / "x.csv"
    path.write_text("Time (s),Load (N),Step,Compression (mm)\n" + "\n".join(rows) + "\n")
    rec = read_recording(path, CsvOptions(), "x")
    _same(rec.squeezes[0].force_n, squeeze.f)
    assert set(rec.details["columns"]) == {"time", "force", "compression"}


def test_a_relaxation_keeps_its_positive_force(tmp_path: Path) -> None:
    t = np.arange(0, 6, 0.01)
    d = np.minimum(t / 0.2, 1.0) * 2.0  # mm: a fast press, then a hold
    f = np.where(t < 0.2, 5 * t / 0.2, 2 + 3 * np.exp(-(t - 0.2) / 1.5))  # jumps, then decays
    path = tmp_path / "relax.csv"
    path.write_text(
        "Time (s),Force (N),Displacement (mm)\n"
        + "".join(f"{a:.3f},{b:.5f},{c:.5f}\n" for a, b, c in zip(t, f, d, strict=True))
    )
    rec = read_recording(path, CsvOptions(), "r")
    assert rec.details["force_sign"]["flipped"] is False
    assert rec.details["force_sign"]["by"] == "one_sign"
    assert float(rec.squeezes[0].force_n.max()) == pytest.approx(5.0, abs=1e-3)


@pytest.mark.parametrize("name", ["Position (mm)", "Pos (mm)"])
def test_a_position_column_is_read_as_the_compression_by_default(
    tmp_path: Path, squeeze: Squeeze, name: str
) -> None:
    path = write_export(tmp_path / "x.csv", squeeze, names=("Time (s)", "Load (N)", name))
    rec = read_recording(path, CsvOptions(), "x")
    _same(rec.squeezes[0].compression_m, squeeze.d)
    reading = rec.details["position_reading"]
    assert (reading["role"], reading["reading"], reading["factor"]) == ("position", "travel", 1.0)
    assert any(
        n.startswith(f"position: column {name!r} (position) read as travel") for n in rec.notes
    )
    palm = read_recording(path, CsvOptions(position_is="palm"), "x")  # opt-in: one palm's travel
    _same(palm.squeezes[0].compression_m, 2.0 * squeeze.d)
    assert palm.details["position_reading"]["factor"] == 2.0


def test_the_many_files_form_says_what_the_single_file_form_says(
    tmp_path: Path, squeeze: Squeeze
) -> None:
    path = write_export(
        tmp_path / "neg.csv",
        squeeze,
        names=("Time (s)", "Load (N)", "Position (mm)"),
        force_sign=-1.0,
    )
    rec = CsvFileTask(CsvOptions()).read(CsvFile(str(path), {"object_id": "neg", "weight_n": 1.0}))
    assert any("sign flipped" in line for line in rec.notices)
    assert any(line.startswith("position: ") for line in rec.notices)
    row = summary_row(CsvFile(str(path), {"object_id": "neg"}), rec)
    import pandas as pd

    lines = dataset_notices(pd.DataFrame([row]))
    assert lines == [f"{path}: {line}" for line in rec.notices]


def test_a_file_with_no_numbers_is_still_one_error(tmp_path: Path) -> None:
    path = tmp_path / "words.csv"
    path.write_text("a,b,c\r\nx,y,z\r\nu,v,w\r\n")
    with pytest.raises(InputDataError, match="no rows of numbers"):
        read_recording(path, CsvOptions(), "w")


def test_the_unit_hint_keeps_the_position_role_and_its_reading(
    tmp_path: Path, squeeze: Squeeze
) -> None:
    path = write_export(tmp_path / "pos.csv", squeeze, names=("Time (s)", "Load (N)", "Pos"))
    with pytest.raises(InputDataError, match=r"did you mean --units position=mm\?"):
        read_recording(path, CsvOptions(), "p")  # mm values read as m: 5 m of compression
    rec = read_recording(path, CsvOptions(units={"position": "mm"}), "p")
    _same(rec.squeezes[0].compression_m, squeeze.d)  # the hint's reading is the compression
    assert rec.details["position_reading"]["reading"] == "travel"
