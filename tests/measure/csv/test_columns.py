"""CSV exports read with the columns and units given by option or by the file's header rows.

A known Kelvin–Voigt squeeze written as CSV must read back, through ``read_recording`` and
``fit_lsq``, to the D and λ it was written with; a missing column, an unknown or conflicting unit
and a bad columns mapping are one-line errors naming what is wrong.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deformctl.characterize import fit_lsq, kelvin_voigt_piecewise_linear
from deformctl.errors import EXIT_USAGE, InputDataError, MissingInputError, UsageError
from deformctl.measure import CsvOptions, read_recording

from .._errors import _err


def _csv_rows(rate_hz: float = 500.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(0.0, 4.0, 1.0 / rate_hz)
    knots_t = np.array([0.0, 1.0, 2.6, 3.6, 4.0])
    knots_f = np.array([0.0, 10.0, 10.0, 0.0, 0.0])
    f = np.interp(t, knots_t, knots_f)
    d = kelvin_voigt_piecewise_linear(t, knots_t, knots_f, 2000.0, 300.0)  # 20 N/cm, 3 N·s/cm
    return t, f, d


def test_csv_plain_with_option_units(tmp_path: Path) -> None:
    t, f, d = _csv_rows()
    path = tmp_path / "plain.csv"
    lines = ["Time,Load,Crosshead"] + [
        f"{ti * 1e3:.6f},{fi / 4.4482216152605:.9f},{di * 1e3:.9f}"
        for ti, fi, di in zip(t, f, d, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    (sq,) = read_recording(
        path,
        CsvOptions(
            columns={"time": "Time", "force": "Load", "compression": "Crosshead"},
            units={"time": "ms", "force": "lbf", "compression": "mm"},
        ),
        "foam",
    ).squeezes
    np.testing.assert_allclose(sq.time_s, t, atol=1e-9)
    np.testing.assert_allclose(sq.force_n, f, atol=1e-7)
    np.testing.assert_allclose(sq.compression_m, d, atol=1e-11)
    fit = fit_lsq([sq])
    assert fit.deformability_n_per_cm == pytest.approx(20.0, rel=1e-3)
    assert fit.damping_ns_per_cm == pytest.approx(3.0, rel=1e-3)


def _two_header_csv(path: Path, units: tuple[str, str, str]) -> None:
    t, f, d = _csv_rows()
    gap_in = (0.1 - d) / 0.0254
    lines = ["Zeit,Kraft,Weg", ",".join(units)] + [
        f"{ti:.6f},{fi / 1e3:.12f},{gi:.12f}" for ti, fi, gi in zip(t, f, gap_in, strict=True)
    ]
    path.write_text("\ufeff" + "\n".join(lines) + "\n")


def test_csv_two_header_rows_units_from_file(tmp_path: Path) -> None:
    path = tmp_path / "machine.csv"
    _two_header_csv(path, ("s", "[kN]", "(in)"))
    (sq,) = read_recording(
        path, CsvOptions(columns={"time": "Zeit", "force": "Kraft", "gap": "Weg"}), "foam"
    ).squeezes
    _, f, d = _csv_rows()
    np.testing.assert_allclose(sq.force_n, f, atol=1e-8)
    np.testing.assert_allclose(sq.compression_m, d, atol=1e-12)
    # an option that agrees with the file is fine
    read_recording(
        path,
        CsvOptions(columns={"time": "Zeit", "force": "Kraft", "gap": "Weg"}, units={"force": "kN"}),
        "foam",
    )


def test_csv_missing_column(tmp_path: Path) -> None:
    path = tmp_path / "m.csv"
    _two_header_csv(path, ("s", "kN", "in"))
    msg = _err(
        lambda: (
            read_recording(
                path, CsvOptions(columns={"time": "Zeit", "force": "Force", "gap": "Weg"}), "x"
            ).squeezes
        ),
        InputDataError,
        "--columns force='Force' names no column of the header \\(line 1: 'Zeit', 'Kraft', "
        "'Weg'\\)",
    )
    assert msg.startswith(str(path))


def test_csv_unknown_unit_in_file_and_option(tmp_path: Path) -> None:
    path = tmp_path / "u.csv"
    _two_header_csv(path, ("s", "kgm", "in"))
    cols = {"time": "Zeit", "force": "Kraft", "gap": "Weg"}
    _err(
        lambda: read_recording(path, CsvOptions(columns=cols), "x").squeezes,
        InputDataError,
        "column 'Kraft' \\(force\\): unit 'kgm' in the units row is not a known force unit; known: "
        "N, kN, mN, daN, lbf, ozf, kgf, gf",
    )
    with pytest.raises(UsageError, match="unknown time unit 'fortnight'") as info:
        read_recording(path, CsvOptions(columns=cols, units={"time": "fortnight"}), "x")
    assert info.value.exit_code == EXIT_USAGE


def test_csv_conflicting_units(tmp_path: Path) -> None:
    path = tmp_path / "c.csv"
    _two_header_csv(path, ("s", "kN", "in"))
    _err(
        lambda: (
            read_recording(
                path,
                CsvOptions(
                    columns={"time": "Zeit", "force": "Kraft", "gap": "Weg"}, units={"gap": "mm"}
                ),
                "x",
            ).squeezes
        ),
        UsageError,
        "--units gap=mm contradicts the file: column 'Weg' is in in \\(its units row says 'in'\\)",
    )


def test_csv_bad_columns_mapping_and_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MissingInputError):
        read_recording(
            tmp_path / "no.csv", CsvOptions(columns={"time": "t", "force": "f", "gap": "g"}), "x"
        )
    path = tmp_path / "c.csv"
    _two_header_csv(path, ("s", "kN", "in"))
    with pytest.raises(UsageError, match="--columns maps position and gap: give one position"):
        read_recording(
            path,
            CsvOptions(columns={"time": "Zeit", "force": "Kraft", "gap": "Weg", "position": "Weg"}),
            "x",
        )
