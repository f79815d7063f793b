"""deformctl.units: the constants against their definitions, and unit names as headers and units
rows write them."""

from __future__ import annotations

import pytest

from deformctl.units import (
    CM,
    GF_N,
    GIB,
    GRAVITY_M_S2,
    INCH_M,
    KGF_N,
    LBF_N,
    MM,
    N_PER_CM,
    NS_PER_CM,
    OZF_N,
    UNITS,
    clean_unit_text,
    parse_unit,
    s_to_ns,
    split_header,
    unit_names,
)

POUND_KG = 0.45359237  #: the international avoirdupois pound (1959), exact


def test_constants_against_their_definitions() -> None:
    assert GRAVITY_M_S2 == 9.80665  # standard gravity (CGPM 1901), exact
    assert pytest.approx(POUND_KG * GRAVITY_M_S2, rel=1e-15) == LBF_N
    assert pytest.approx(LBF_N, rel=1e-15) == OZF_N * 16
    assert (GRAVITY_M_S2, pytest.approx(GRAVITY_M_S2, rel=1e-15)) == (KGF_N, GF_N * 1000)
    assert pytest.approx(2.54 * CM, rel=1e-15) == INCH_M
    assert (CM, MM, GIB) == (0.01, 0.001, 1_073_741_824)
    # 2 N/cm is 2 N per 0.01 m = 200 N/m; 0.5 N·s/cm is 50 N·s/m
    assert pytest.approx(2.0 / CM) == 2.0 * N_PER_CM
    assert pytest.approx(0.5 / CM) == 0.5 * NS_PER_CM


def test_seconds_to_integer_nanoseconds() -> None:
    assert s_to_ns(1.5) == 1_500_000_000
    assert s_to_ns(0.0) == 0
    assert s_to_ns(6e-10) == 1  # rounded, not truncated
    assert isinstance(s_to_ns(2.0), int)


def test_units_of_a_dimension_convert_to_si() -> None:
    assert unit_names("length") == "m, cm, mm, µm, in"
    assert UNITS["time"]["min"].to_si(2.0) == 120.0
    assert UNITS["force"]["kN"].to_si(0.25) == 250.0
    assert all(u.dimension == d for d, units in UNITS.items() for u in units.values())


def test_spellings_and_slips() -> None:
    assert clean_unit_text(" ( [ mm ] ) ") == "mm"
    assert clean_unit_text("us") == "µs"
    assert clean_unit_text("μm") == "µm"  # Greek mu -> micro sign
    for text, name in [("sec", "s"), ("秒", "s"), ("kp", "kgf"), ("Millimetres", "mm"),
                       ("microns", "µm"), ("NEWTON", "N")]:  # fmt: skip
        unit = parse_unit(text)
        assert unit is not None, text
        assert unit.name == name, text
    assert parse_unit("Mm") is None
    assert parse_unit("Ms") is None
    assert parse_unit("") is None
    assert parse_unit("[ ]") is None
    assert parse_unit("s", "force") is None


def test_unit_names_from_headers() -> None:
    cases = {
        "Load (N)": ("Load", "N"),
        "Force [kN]": ("Force", "kN"),
        "Displacement/mm": ("Displacement", "mm"),
        "Time (s)": ("Time", "s"),
        "Zeit [s]": ("Zeit", "s"),
        "Time in ms": ("Time", "ms"),
        "位移 (mm)": ("位移", "mm"),
        "Force/Weight": ("Force/Weight", None),
        "Pos": ("Pos", None),
    }
    for header, want in cases.items():
        assert split_header(header) == want, header
    for text, name, si in [
        ("um", "µm", 1e-6),
        ("μm", "µm", 1e-6),
        ("[kN]", "kN", 1e3),
        ("lbf", "lbf", 4.4482216152605),
        ("ozf", "ozf", 4.4482216152605 / 16),
        ("gf", "gf", 9.80665e-3),
        ("kgf", "kgf", 9.80665),
        ("mN", "mN", 1e-3),
        ("(ms)", "ms", 1e-3),
        ("µs", "µs", 1e-6),
        ("in", "in", 0.0254),
        ("cm", "cm", 0.01),
    ]:
        unit = parse_unit(text)
        assert unit is not None, text
        assert (unit.name, unit.si) == (name, pytest.approx(si)), text
    assert parse_unit("MN") is None  # a meganewton is not a millinewton
    assert parse_unit("kN", "length") is None
    assert parse_unit("furlong") is None
