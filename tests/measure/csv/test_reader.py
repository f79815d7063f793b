"""``read_recording`` reads exports as testing machines and grippers write them.

Every file here is a known Kelvin–Voigt squeeze (:mod:`measure._exports`) written in one dialect;
the reader must give back the same samples in SI (to the digits written), with the columns,
units, preamble and force sign it found recorded, whatever the dialect: a preamble, units in the
names or in a units row, ``;`` with a decimal comma, quoted values with thousands separators, a
byte-order mark, a GBK header, a compressive force that is negative. The errors name what is
wrong and the fix.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deformctl.errors import EXIT_DATAERR, EXIT_USAGE, InputDataError, UsageError
from deformctl.measure import CsvDialect, CsvOptions, read_recording

from .._exports import Squeeze, kv_squeeze, write_export

PREAMBLE = (
    "EF10_0T_A_sample_1",
    "Compression test;",
    "Cylinder Diameter: 50mm;",
    "Speed (mm/min): 10;",
    "Load cell: 1kN;",
)


@pytest.fixture(scope="module")
def squeeze() -> Squeeze:
    return kv_squeeze()


def _same(rec_squeeze: object, s: Squeeze, *, atol_f: float = 2e-6, atol_d: float = 2e-9) -> None:
    """The squeeze read equals ``s`` (compression from its first sample) to the digits written."""
    t, f, d = rec_squeeze.time_s, rec_squeeze.force_n, rec_squeeze.compression_m  # type: ignore[attr-defined]
    np.testing.assert_allclose(t, s.t - s.t[0], atol=1e-9)
    np.testing.assert_allclose(f, s.f, atol=atol_f)
    np.testing.assert_allclose(d, s.d - s.d[0], atol=atol_d)


def test_phantom_layout_preamble_header_units(tmp_path: Path, squeeze: Squeeze) -> None:
    """A 5-line preamble, units in the names: found with no option; the preamble is kept."""
    path = write_export(tmp_path / "p.csv", squeeze, preamble=PREAMBLE)
    rec = read_recording(path, CsvOptions(), "x")
    _same(rec.squeezes[0], squeeze)
    csv = rec.details
    assert csv["layout"]["header_line"] == 6
    assert csv["layout"]["data_line"] == 7
    assert csv["preamble"] == {
        "Cylinder Diameter": "50mm",
        "Speed (mm/min)": "10",
        "Load cell": "1kN",
    }
    assert csv["preamble_lines"] == ["EF10_0T_A_sample_1", "Compression test"]
    assert csv["columns"]["compression"] == {
        "column": "Compression (mm)",
        "unit": "mm",
        "column_from": "name",
        "unit_from": "header",
    }
    assert rec.notes[0] == (
        "columns: time='Time (s)' [s], force='Load (N)' [N], compression='Compression (mm)' [mm]"
    )
    assert rec.warnings == ()
    assert rec.flags == ()
    same = read_recording(path, CsvOptions(CsvDialect(skip_rows=5)), "x")
    np.testing.assert_array_equal(same.squeezes[0].force_n, rec.squeezes[0].force_n)


@pytest.mark.parametrize(
    "dialect",
    [
        {"names": ("Time", "Force", "Displacement"), "units_row": ("(s)", "(kN)", "(mm)"),
         "units": ("s", "kN", "mm"), "quote": True, "digits": 9},
        {"names": ("Zeit [s]", "Kraft [N]", "Weg [mm]"), "delimiter": ";", "decimal": ","},
        {"names": ("Time (s)", "Load (N)", "Extension (mm)"), "thousands": ",", "quote": True},
        {"names": ("Zeit [s]", "Kraft [mN]", "Weg [µm]"), "units": ("s", "mN", "µm"),
         "delimiter": ";", "decimal": ",", "thousands": "."},
        {"names": ("t", "Force (N)", "Displacement/mm"), "delimiter": "\t", "bom": True},
        {"names": ("Time (ms)", "Fz [N]", "Crosshead (mm)"), "units": ("ms", "N", "mm"),
         "digits": 4},
    ],
    ids=["bluehill", "semicolon_comma", "thousands", "european_grouped", "tab_bom", "ms"],
)  # fmt: skip
def test_dialects_read_back_the_same_squeeze(
    tmp_path: Path, squeeze: Squeeze, dialect: dict[str, object]
) -> None:
    """Each dialect, with no option, gives back the samples (to the digits written) in SI."""
    path = write_export(tmp_path / "e.csv", squeeze, **dialect)  # type: ignore[arg-type]
    rec = read_recording(path, CsvOptions(), "x")
    digits = int(dialect.get("digits", 6))  # type: ignore[call-overload]
    units = dialect.get("units", ("s", "N", "mm"))
    scale_f = {"N": 1.0, "kN": 1e3, "mN": 1e-3}[units[1]]  # type: ignore[index]
    scale_d = {"mm": 1e-3, "µm": 1e-6}[units[2]]  # type: ignore[index]
    step = 10.0**-digits
    _same(rec.squeezes[0], squeeze, atol_f=step * scale_f, atol_d=step * scale_d)


def test_gbk_header_needs_encoding_and_is_then_read(tmp_path: Path, squeeze: Squeeze) -> None:
    """A GBK file (as 21 of 24 files of a real set): the error names --encoding gbk."""
    path = write_export(
        tmp_path / "gbk.csv", squeeze, names=("时间(s)", "力(N)", "位移(mm)"), encoding="gbk"
    )
    with pytest.raises(InputDataError) as info:
        read_recording(path, CsvOptions(), "x")
    assert str(info.value) == (
        f"{path}: not UTF-8 text: byte 0xbc on line 1 does not decode; pass --encoding gbk (it "
        "reads as gbk: '时间(s),力(N),位移(mm)')"
    )
    rec = read_recording(path, CsvOptions(CsvDialect(encoding="gbk")), "x")
    _same(rec.squeezes[0], squeeze)
    assert [c["column"] for c in rec.details["columns"].values()] == [
        "时间(s)",
        "力(N)",
        "位移(mm)",
    ]


def test_negative_compressive_force_is_flipped_and_recorded(
    tmp_path: Path, squeeze: Squeeze
) -> None:
    path = write_export(tmp_path / "instron.csv", squeeze, force_sign=-1.0)
    rec = read_recording(path, CsvOptions(), "x")
    _same(rec.squeezes[0], squeeze)
    assert rec.details["force_sign"] == {
        "option": "auto",
        "compressive": "negative",
        "flipped": True,
        "by": "one_sign",
    }
    assert rec.notes[1] == (
        "the force is negative under compression in column 'Load (N)': sign flipped "
        "(--force-sign auto)"
    )
    same = read_recording(path, CsvOptions(force_sign="negative"), "x")
    _same(same.squeezes[0], squeeze)
    with pytest.raises(InputDataError, match="pass --force-sign negative \\(or auto\\)") as info:
        read_recording(path, CsvOptions(force_sign="positive"), "x")
    assert info.value.exit_code == EXIT_DATAERR
    plain = read_recording(write_export(tmp_path / "p.csv", squeeze), CsvOptions(), "x")
    assert plain.details["force_sign"]["flipped"] is False
    assert len(plain.notes) == 1


def test_millimetres_under_half_a_millimetre_are_never_metres(tmp_path: Path) -> None:
    """The silent 1000x case: a (mm) header, a 0.4 mm peak. Read as mm: D = 150 N/cm, not 0.15."""
    from deformctl.characterize import fit_lsq

    s = kv_squeeze(150.0, 0.5, peak_n=6.0, position_noise_m=1e-8)  # peak d = 0.4 mm
    assert 0.3e-3 < float(s.d.max()) < 0.5e-3
    path = write_export(tmp_path / "stiff.csv", s, digits=7)
    rec = read_recording(path, CsvOptions(), "x")
    fit = fit_lsq(rec.squeezes, preload="fit", window_s=0.43)
    assert fit.deformability_n_per_cm == pytest.approx(150.0, rel=0.02)
    with pytest.raises(UsageError) as info:
        read_recording(path, CsvOptions(units={"compression": "m"}), "x")
    assert str(info.value) == (
        f"{path}: --units compression=m contradicts the file: column 'Compression (mm)' is in "
        "mm (its header says 'mm')"
    )
    assert info.value.exit_code == EXIT_USAGE
    plain = write_export(tmp_path / "plain.csv", s, names=("t", "load", "compression"), digits=7)
    rec = read_recording(plain, CsvOptions(units={"compression": "mm"}), "x")
    assert fit_lsq(rec.squeezes, preload="fit", window_s=0.43).deformability_n_per_cm == (
        pytest.approx(150.0, rel=0.02)
    )
    unitless = read_recording(plain, CsvOptions(), "x")  # read in m: said on a warning line
    assert unitless.warnings == (
        "column 't' (time) states no unit: read in s (pass --units time=UNIT to say which)",
        "column 'load' (force) states no unit: read in N (pass --units force=UNIT to say which)",
        "column 'compression' (compression) states no unit: read in m (pass --units "
        "compression=UNIT to say which)",
    )


def test_implausible_values_name_the_plausible_unit(tmp_path: Path, squeeze: Squeeze) -> None:
    """Values implausible for the unit in force (file or flag) exit 65 with the unit that fits."""
    as_m = write_export(tmp_path / "m.csv", squeeze, names=("t", "Load", "compression"))
    with pytest.raises(InputDataError) as info:  # mm values (to 5 mm) without a unit: metres
        read_recording(as_m, CsvOptions(), "x")
    assert str(info.value).endswith(
        "column 'compression': peak compression 4.94 m is implausible (above 0.5 m): did you "
        "mean --units compression=mm?"
    )
    big = Squeeze(squeeze.t, squeeze.f, squeeze.d * 200)  # 1 m of compression, in mm
    path = write_export(tmp_path / "mm.csv", big, names=("t", "Load", "Compression (mm)"), digits=3)
    with pytest.raises(InputDataError) as info:
        read_recording(path, CsvOptions(), "x")
    assert str(info.value).endswith(
        "peak compression 0.987 m is implausible (above 0.5 m): the file's header says mm; the "
        "values are plausible in µm: is the header wrong?"
    )
    strong = kv_squeeze(peak_n=20.0)
    kn = write_export(tmp_path / "kn.csv", strong, names=("t", "Force [kN]", "Compression (mm)"))
    with pytest.raises(InputDataError) as info:  # N values under a kN label: a 20 kN peak
        read_recording(kn, CsvOptions(), "x")
    assert "the values are plausible in N: is the header wrong?" in str(info.value)
    assert info.value.exit_code == EXIT_DATAERR


def test_column_roles_by_name_and_ambiguity(tmp_path: Path, squeeze: Squeeze) -> None:
    names = ("Zeit (s)", "Standard force (N)", "Commanded force (N)", "Gripper position (mm)")
    path = tmp_path / "g.csv"
    rows = [",".join(names)] + [
        f"{a:.4f},{b:.5f},{b:.5f},{-c * 1e3:.6f}"
        for a, b, c in zip(squeeze.t, squeeze.f, squeeze.d, strict=True)
    ]
    path.write_text("\n".join(rows) + "\n")
    rec = read_recording(path, CsvOptions(position_is="gap"), "x")
    assert {k: v["column"] for k, v in rec.details["columns"].items()} == {
        "time": "Zeit (s)",
        "force": "Standard force (N)",
        "position": "Gripper position (mm)",
    }
    two = tmp_path / "two.csv"
    two.write_text(
        "Time (s),Force A (N),Force B (N),Displacement (mm)\n0,0,0,0\n1,1,1,1\n2,2,2,2\n"
    )
    with pytest.raises(UsageError) as info:
        read_recording(two, CsvOptions(), "x")
    assert str(info.value) == (
        f"{two}: cannot tell which column is the force: 'Force A (N)', 'Force B (N)'; pass "
        "--columns force=NAME"
    )
    pos = tmp_path / "pos.csv"
    pos.write_text("Time (s),Load (N),Displacement (mm),Position (mm)\n0,0,0,0\n1,1,1,1\n2,2,2,2\n")
    with pytest.raises(UsageError, match="position signal: 'Position \\(mm\\)', 'Displacement"):
        read_recording(pos, CsvOptions(), "x")
    none = tmp_path / "none.csv"
    none.write_text("a,b,c\n0,0,0\n1,1,1\n2,2,2\n")
    with pytest.raises(InputDataError) as info:
        read_recording(none, CsvOptions(), "x")
    assert str(info.value) == (
        f"{none}: no column for the time in the header (line 1: 'a', 'b', 'c'); pass --columns "
        "(e.g. time=NAME), or --skip-rows N if the header is another line"
    )
    rec = read_recording(
        none,
        CsvOptions(
            columns={"time": "a", "force": "b", "compression": "c"}, units={"compression": "mm"}
        ),
        "x",
    )
    assert rec.details["columns"]["force"]["column_from"] == "--columns"


def test_ambiguous_decimal_comma_is_refused(tmp_path: Path) -> None:
    """``1,234`` under ``;``: a decimal comma or a thousands separator? 1000x either way."""
    path = tmp_path / "amb.csv"
    path.write_text("t;f;d\n1;1,234;2,000\n2;2,345;3,000\n3;3,456;4,000\n")
    with pytest.raises(UsageError) as info:
        read_recording(path, CsvOptions(), "x")
    assert str(info.value) == (
        f"{path}: cannot tell whether ',' is the decimal mark or the thousands separator (every "
        "number with a comma reads as digit groups, e.g. 1,234); pass --decimal , or --thousands ,"
    )
    with pytest.raises(UsageError, match=r"--decimal must be '\.' or ','"):
        CsvDialect(decimal=":")
    with pytest.raises(UsageError, match="--delimiter must be one of"):
        CsvDialect(delimiter="|")
    with pytest.raises(UsageError, match="--encoding: unknown encoding 'klingon'"):
        CsvDialect(encoding="klingon")
    with pytest.raises(UsageError, match="--skip-rows must be an integer >= 0, got -1"):
        CsvDialect(skip_rows=-1)
    with pytest.raises(
        UsageError, match=r"--lag-s must be auto or a number in \[-10, 10\] s, got 'soon'"
    ):
        CsvOptions(lag_s="soon")  # type: ignore[arg-type]


def test_options_record_what_was_given(tmp_path: Path) -> None:
    opts = CsvOptions(CsvDialect(delimiter="tab", decimal=","), units={"force": "kN"}, lag_s="0.1")  # type: ignore[arg-type]
    assert opts.as_dict() == {
        "delimiter": "\t",
        "decimal": ",",
        "thousands": None,
        "encoding": "utf-8",
        "skip_rows": None,
        "columns": {},
        "units": {"force": "kN"},
        "force_sign": "auto",
        "lag_s": 0.1,
        "position_is": "travel",
        "compression_zero": "first",
        "position_increases_when": None,
        "memory_budget_gib": 2.0,
    }
