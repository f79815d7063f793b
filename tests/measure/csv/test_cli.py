"""``deformctl measure --csv``: bad exports, many files per call, and what is said and recorded.

Every bad file gets exactly one ``error:`` line naming the file and the fix, its documented exit
code, and nothing written. Many files go into one log or a dataset directory, one object per
file; a file that fails is recorded with its reason and the others go on (exit 1).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_squeeze_log
from deformctl.artifacts.dataset import read_dataset, read_failures
from deformctl.artifacts.mcap import load_mcap
from deformctl.artifacts.mcap.contents import decode_provenance
from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, EXIT_FAILURE, EXIT_NOINPUT, EXIT_USAGE

from .._exports import kv_squeeze, write_export

runner = CliRunner()
HEADER = "Time (s),Load (N),Compression (mm)\n"
LINES = [f"{i / 100:.2f},{i / 10:.3f},{i / 50:.4f}\n" for i in range(40)]
ROWS = "".join(LINES)
MIXED = HEADER + "".join(LINES[:3]) + "0.50;5.000;1.0000\n" + "".join(LINES[3:])


def _measure(*args: str, stdin: str | None = None) -> tuple[int, str]:
    res = runner.invoke(app, ["measure", *args], input=stdin)
    return res.exit_code, res.stderr


def _refused(path: Path, out: Path, code: int, line: str, *extra: str) -> None:
    """``measure --csv path``: exactly ``error: <path>: <line>``, exit ``code``, no output."""
    got, err = _measure("csv", str(path), "--weight-n", "1", "-o", str(out), *extra)
    assert (got, err) == (code, f"error: {path}: {line}\n")
    assert not out.exists()


BAD_FILES = {
    "preamble_no_header": (
        "Sample A\nSpeed (mm/min): 10\n" + ROWS,
        EXIT_DATAERR,
        "no header row: the numbers start at line 3 and lines 1-2 hold no row of column names; "
        "add a header line naming the columns (time, force, compression, ...) or pass "
        "--skip-rows N (the lines before the header)",
    ),
    "unknown_unit": (
        "Time (s),Load (furlong),Compression (mm)\n" + ROWS,
        EXIT_DATAERR,
        "column 'Load (furlong)' (force): unit 'furlong' in the header is not a known force unit; "
        "known: N, kN, mN, daN, lbf, ozf, kgf, gf",
    ),
    "unit_of_another_dimension": (
        "Time (mm),Load (N),Compression (mm)\n" + ROWS,
        EXIT_DATAERR,
        "column 'Time (mm)' (time): unit 'mm' in the header is a length unit, not a time unit; "
        "known: s, ms, µs, ns, min, h",
    ),
    "mixed_delimiters": (
        MIXED,
        EXIT_DATAERR,
        "mixed delimiters: line 5 splits into 3 cells at ';', not at ',' (1 cell(s)) like the "
        "rows above it; write the file with one delimiter",
    ),
    "text_in_numbers": (
        HEADER + ROWS.replace("0.20,2.000", "0.20,n/a", 1),
        EXIT_DATAERR,
        "line 22: 'n/a' in column 'Load (N)' is not a number",
    ),
    "empty_cell": (
        HEADER + ROWS.replace("0.20,2.000", "0.20,", 1),
        EXIT_DATAERR,
        "line 22: empty cell in column 'Load (N)'",
    ),
    "empty_file": ("", EXIT_DATAERR, "empty file (0 bytes)"),
    "blank_lines": ("\n\n  \n", EXIT_DATAERR, "no text: the file holds only blank lines"),
    "header_only": (
        HEADER,
        EXIT_DATAERR,
        "no rows of numbers in the first 2 lines (delimiters tried: ,, ;, tab); is this a CSV "
        "export?",
    ),
    "single_row": (
        HEADER + "0.00,0.000,0.0000\n",
        EXIT_DATAERR,
        "only 1 data row (line 2): a squeeze needs at least 2",
    ),
    "time_backwards": (
        HEADER + ROWS.replace("0.05,", "0.02,", 1),
        EXIT_DATAERR,
        "time goes back at data row 6 (line 7): 'Time (s)' is 0.02 after 0.04",
    ),
    "ambiguous_comma": (
        "Zeit [s];Kraft [N];Weg [mm]\n1;1,234;2,000\n2;2,345;3,000\n3;3,456;4,000\n",
        EXIT_USAGE,
        "cannot tell whether ',' is the decimal mark or the thousands separator (every number "
        "with a comma reads as digit groups, e.g. 1,234); pass --decimal , or --thousands ,",
    ),
    "two_force_columns": (
        "Time (s),Force A (N),Force B (N),Compression (mm)\n0,0,0,0\n1,1,1,1\n2,2,2,2\n",
        EXIT_USAGE,
        "cannot tell which column is the force: 'Force A (N)', 'Force B (N)'; pass --columns "
        "force=NAME",
    ),
}


@pytest.mark.parametrize("case", BAD_FILES, ids=list(BAD_FILES))
def test_bad_export_one_line_exit_code_nothing_written(tmp_path: Path, case: str) -> None:
    text, code, line = BAD_FILES[case]
    path = tmp_path / f"{case}.csv"
    path.write_text(text, encoding="utf-8")
    _refused(path, tmp_path / "out.mcap", code, line)
    _refused(path, tmp_path / "out", code, line, "--object-id", "a")


def test_contradicting_units_and_wrong_encoding(tmp_path: Path) -> None:
    path = tmp_path / "c.csv"
    path.write_text(HEADER + ROWS)
    _refused(
        path,
        tmp_path / "o.mcap",
        EXIT_USAGE,
        "--units force=kN contradicts the file: column 'Load (N)' is in N (its header says 'N')",
        "--units",
        "force=kN",
    )
    gbk = tmp_path / "gbk.csv"
    gbk.write_bytes(("时间(s),力(N),位移(mm)\n" + ROWS).encode("gbk"))
    _refused(
        gbk,
        tmp_path / "o.mcap",
        EXIT_DATAERR,
        "not UTF-8 text: byte 0xbc on line 1 does not decode; pass --encoding gbk (it reads as "
        "gbk: '时间(s),力(N),位移(mm)')",
    )
    latin = tmp_path / "latin.csv"
    latin.write_bytes((HEADER + ROWS + "# Prüfung\n").encode("cp1252"))
    _refused(
        latin,
        tmp_path / "o.mcap",
        EXIT_DATAERR,
        "not UTF-8 text: byte 0xfc on line 42 does not decode; pass --encoding cp1252 (it reads "
        "as cp1252: '# Prüfung')",
    )
    _refused(
        path,
        tmp_path / "o.mcap",
        EXIT_DATAERR,
        "--skip-rows 3: line 4 holds numbers, not column names; count the lines above the header",
        "--skip-rows",
        "3",
    )
    assert _measure("csv", str(tmp_path / "no.csv"), "--weight-n", "1", "-o", "x.mcap") == (
        EXIT_NOINPUT,
        f"error: {tmp_path / 'no.csv'}: no such file\n",
    )


def test_ten_million_rows_are_refused_by_the_memory_budget(tmp_path: Path) -> None:
    """10 million rows: about 2.3 GiB (250 B per row, measured), above the 2 GiB default; the
    refusal comes before the file is read (from its size and the first rows)."""
    path = tmp_path / "big.csv"
    with path.open("wb") as fh:
        fh.write(HEADER.encode())
        block = b"1,2,3\n" * 1_000_000
        for _ in range(10):
            fh.write(block)
    _refused(
        path,
        tmp_path / "o.mcap",
        EXIT_USAGE,
        "about 10,000,000 data rows, an estimated 2.33 GiB in memory, above the memory budget of "
        "2 GiB (250 B per row); split the file or raise --memory-budget-gib",
    )
    path.unlink()


def test_mapping_and_file_facts_are_printed_and_recorded(tmp_path: Path) -> None:
    s = kv_squeeze()
    path = write_export(tmp_path / "foam.csv", s, preamble=("Machine: UTM 5900", "Operator: A"))
    log = tmp_path / "foam.mcap"
    code, err = _measure("csv", str(path), "--weight-n", "0.7", "-o", str(log))
    assert code == 0
    lines = err.splitlines()
    assert lines[0] == (
        f"{path}: columns: time='Time (s)' [s], force='Load (N)' [N], compression='Compression "
        "(mm)' [mm]"
    )
    assert lines[1].startswith(f"{log}: 1 squeeze(s) of 'foam', 8.0 s, force 100 Hz")
    (obj,), _ = read_squeeze_log(log)
    assert obj["object_id"] == "foam"  # the file's stem
    assert obj["csv"]["preamble"] == {"Machine": "UTM 5900", "Operator": "A"}
    assert obj["csv"]["columns"]["force"]["unit_from"] == "header"
    assert obj["csv"]["layout"]["sniffed"] == ["delimiter", "decimal", "thousands", "header"]
    settings = decode_provenance(load_mcap(log.read_bytes(), log)).settings  # type: ignore[union-attr]
    assert settings["source"] == "csv"
    assert settings["columns"] == {}
    assert "recording_flags" not in obj


def test_stdin_and_options_that_need_one_file(tmp_path: Path) -> None:
    text = HEADER + "".join(
        f"{t:.2f},{f:.6f},{1e3 * d:.6f}\n" for t, f, d in zip(*_kv_cols(), strict=True)
    )
    log = tmp_path / "s.mcap"
    code, err = _measure(
        "csv", "-", "--object-id", "s", "--weight-n", "1", "-o", str(log), stdin=text
    )
    assert code == 0, err
    assert err.splitlines()[0].startswith("<stdin>: columns: time='Time (s)'")
    code, err = _measure("csv", "-", "--weight-n", "1", "-o", str(log), "--force", stdin=text)
    assert (code, err) == (EXIT_USAGE, "error: --csv - (stdin) needs --object-id\n")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text(text)
    b.write_text(text)
    code, err = _measure(
        "csv", str(a), str(b), "--object-id", "x", "--weight-n", "1", "-o", "o.mcap"
    )
    assert code == EXIT_USAGE
    assert err.startswith("error: --object-id names one object, but 2 files are given")
    code, err = _measure("csv", str(a), str(b), "-o", "o.mcap")
    assert (code, err) == (
        EXIT_USAGE,
        f"error: {a}: no weight for object 'a': give --weight-n or a weight_n column in "
        "--objects-from\n",
    )
    (tmp_path / "sub").mkdir()
    c = tmp_path / "sub" / "a.csv"
    c.write_text(text)
    code, err = _measure("csv", str(a), str(c), "--weight-n", "1", "-o", "o.mcap")
    assert code == EXIT_USAGE
    assert f"files {a} and {c} are both object 'a'" in err


def _kv_cols() -> tuple[object, object, object]:
    s = kv_squeeze()
    return s.t, s.f, s.d


def test_many_files_one_log_with_a_failure(tmp_path: Path) -> None:
    s = kv_squeeze()
    good = [write_export(tmp_path / f"g{i}.csv", s) for i in range(3)]
    bad = tmp_path / "bad.csv"
    bad.write_text(HEADER + "0,1,2\n")
    mapping = tmp_path / "objects.csv"
    mapping.write_text(
        "file,object_id,weight_n,size_x_cm,size_y_cm,size_z_cm,friction_mu\n"
        "g0.csv,sponge,0.5,6,6,4,0.8\ng1,foam,,,,,\n"
    )
    log = tmp_path / "all.mcap"
    files = [str(p) for p in (*good, bad)]
    code, err = _measure(
        "csv", *files, "--weight-n", "0.7", "--objects-from", str(mapping), "-o", str(log)
    )
    assert code == EXIT_FAILURE
    lines = err.splitlines()
    assert lines == [
        "columns: time='Time (s)' [s], force='Load (N)' [N], compression='Compression (mm)' "
        "[mm] (all 3 files)",
        f"error: {bad}: only 1 data row (line 2): a squeeze needs at least 2",
        f"{log}: 3 object(s) from 4 files, 3 squeeze(s), 24.0 s; 1 file(s) failed (recorded in "
        "the log)",
    ]
    objects, squeezes = read_squeeze_log(log)
    assert [(o["object_id"], o["weight_n"]) for o in objects] == [
        ("sponge", 0.5),
        ("foam", 0.7),
        ("g2", 0.7),
    ]
    assert (objects[0]["size_x_cm"], objects[0]["friction_mu"]) == (6.0, 0.8)
    assert len(squeezes) == 3
    settings = decode_provenance(load_mcap(log.read_bytes(), log)).settings  # type: ignore[union-attr]
    assert settings["_failures"] == [
        {
            "file": str(bad),
            "object_id": "bad",
            "cause": "bad_input",
            "error": f"{bad}: only 1 data row (line 2): a squeeze needs at least 2",
        }
    ]
    res = runner.invoke(app, ["characterize", str(log), "-o", str(tmp_path / "c.parquet")])
    assert res.exit_code == 0, res.stderr


def test_many_files_dataset_directory_with_a_failure(tmp_path: Path) -> None:
    s = kv_squeeze()
    files = [str(write_export(tmp_path / f"f{i}.csv", s)) for i in range(3)]
    bad = tmp_path / "mixed.csv"
    bad.write_text(MIXED)
    out = tmp_path / "squeeze"
    code, err = _measure(
        "csv", *files, str(bad), "--weight-n", "0.7", "--workers", "1", "-o", f"{out}/"
    )
    assert code == EXIT_FAILURE
    lines = err.splitlines()
    assert lines[0] == (
        f"{out}: columns: time='Time (s)' [s], force='Load (N)' [N], compression='Compression "
        "(mm)' [mm] (all 3 files)"
    )
    assert lines[1] == (
        f"error: {bad}: mixed delimiters: line 5 splits into 3 cells at ';', not at ',' (1 "
        "cell(s)) like the rows above it; write the file with one delimiter"
    )
    assert lines[2].startswith(f"{out}: measure: 3 done, 1 failed")
    rows = read_dataset(out)
    assert list(rows["object_id"]) == ["f0", "f1", "f2"]
    assert set(rows["recording_flags"]) == {"ok"}
    failures = read_failures(out)
    assert list(failures["object_id"]) == ["mixed"]
    assert list(failures["cause"]) == ["bad_input"]  # a documented cause, not a class
    coef = tmp_path / "coef.parquet"
    res = runner.invoke(app, ["characterize", f"{out}/", "-o", str(coef), "--model", "kv"])
    assert res.exit_code == 0, res.stderr
    manifest = json.loads((out / "_sweep.json").read_text())
    assert manifest["fingerprint"]["settings"]["source"] == "csv"
