"""Unit constants. SI inside the code; the paper's units (cm, N/cm, N·s/cm) at the edges.

Multiply a value in the named unit by the constant to get SI, divide to go back::

    stiffness_n_per_m = deformability_n_per_cm * N_PER_CM
"""

from __future__ import annotations

import re
from dataclasses import dataclass

GRAVITY_M_S2 = 9.80665  #: standard gravity, m/s²

CM = 0.01  #: metres per centimetre
MM = 0.001  #: metres per millimetre
N_PER_CM = 100.0  #: (N/m) per (N/cm)
NS_PER_CM = 100.0  #: (N·s/m) per (N·s/cm)
NS_PER_S = 1_000_000_000  #: nanoseconds per second
GIB = 1024**3  #: bytes per gibibyte


def s_to_ns(t_s: float) -> int:
    """Seconds to integer nanoseconds (rounded), as MCAP log times want."""
    return round(t_s * NS_PER_S)


# ---------------------------------------------------------------------------- unit names

LBF_N = 4.4482216152605  #: newtons per pound-force (exact by definition)
OZF_N = LBF_N / 16.0  #: newtons per ounce-force
KGF_N = GRAVITY_M_S2  #: newtons per kilogram-force
GF_N = GRAVITY_M_S2 / 1000.0  #: newtons per gram-force
INCH_M = 0.0254  #: metres per inch (exact by definition)


@dataclass(frozen=True)
class Unit:
    """A unit of one dimension: how it is spelled and what one of it is in SI.

    Attributes:
        name: the canonical spelling (``mm``, ``kN``, ``µs``).
        dimension: ``time``, ``force`` or ``length``.
        si: multiply a value in this unit by ``si`` to get s, N or m.
    """

    name: str
    dimension: str
    si: float

    def to_si(self, value: float) -> float:
        """``value`` (in this unit) in s, N or m."""
        return value * self.si


#: Every unit known, by canonical name, per dimension (SI first, then the common slips).
UNITS: dict[str, dict[str, Unit]] = {
    "time": {
        name: Unit(name, "time", si)
        for name, si in (
            ("s", 1.0),
            ("ms", 1e-3),
            ("µs", 1e-6),
            ("ns", 1e-9),
            ("min", 60.0),
            ("h", 3600.0),
        )
    },
    "force": {
        name: Unit(name, "force", si)
        for name, si in (
            ("N", 1.0),
            ("kN", 1e3),
            ("mN", 1e-3),
            ("daN", 10.0),
            ("lbf", LBF_N),
            ("ozf", OZF_N),
            ("kgf", KGF_N),
            ("gf", GF_N),
        )
    },
    "length": {
        name: Unit(name, "length", si)
        for name, si in (
            ("m", 1.0),
            ("cm", 1e-2),
            ("mm", 1e-3),
            ("µm", 1e-6),
            ("in", INCH_M),
        )
    },
}

#: Other spellings (matched after lower-casing) → canonical name. ``u`` and the Greek ``μ``
#: (U+03BC) stand for the micro sign ``µ`` (U+00B5).
_ALIASES: dict[str, str] = {
    "sec": "s", "secs": "s", "second": "s", "seconds": "s", "sek": "s", "sekunden": "s",
    "秒": "s", "msec": "ms", "millisecond": "ms", "milliseconds": "ms", "usec": "µs",
    "microsecond": "µs", "microseconds": "µs", "minute": "min", "minutes": "min",
    "hr": "h", "hour": "h", "hours": "h",
    "newton": "N", "newtons": "N", "kilonewton": "kN", "kilonewtons": "kN",
    "millinewton": "mN", "millinewtons": "mN", "decanewton": "daN", "lbf": "lbf",
    "ozf": "ozf", "kgf": "kgf", "kp": "kgf", "gf": "gf", "牛": "N", "千牛": "kN",
    "meter": "m", "meters": "m", "metre": "m", "metres": "m", "米": "m",
    "centimeter": "cm", "centimeters": "cm", "centimetre": "cm", "centimetres": "cm",
    "millimeter": "mm", "millimeters": "mm", "millimetre": "mm", "millimetres": "mm",
    "毫米": "mm", "micrometer": "µm", "micrometers": "µm", "micrometre": "µm",
    "micrometres": "µm", "micron": "µm", "microns": "µm", "inch": "in", "inches": "in",
}  # fmt: skip
#: Spellings that look like a known unit in lower case but are another one (meganewton).
_NOT_UNITS = frozenset({"MN", "Mm", "Ms"})


def _lookup() -> dict[str, Unit]:
    table: dict[str, Unit] = {}
    for units in UNITS.values():
        for name, unit in units.items():
            table[name.lower()] = unit
    for alias, name in _ALIASES.items():
        table[alias.lower()] = next(u[name] for u in UNITS.values() if name in u)
    return table


_BY_SPELLING = _lookup()


def clean_unit_text(text: str) -> str:
    """A unit as written in a header or a units row, without brackets and blanks: ``[kN]`` →
    ``kN``, ``( mm )`` → ``mm``; ``u`` / ``μ`` prefixes become ``µ``."""
    t = text.strip()
    while len(t) >= 2 and t[0] + t[-1] in ("()", "[]", "{}", "<>"):
        t = t[1:-1].strip()
    t = t.replace("μ", "µ")  # Greek mu → micro sign
    if len(t) == 2 and t[0] == "u" and t[1] in "ms":  # um, us
        t = "µ" + t[1]
    return t


def parse_unit(text: str, dimension: str | None = None) -> Unit | None:
    """The unit ``text`` names (``N``, ``[kN]``, ``(mm)``, ``um``, ``µs``, ``sec``, ``lbf``).

    Args:
        text: the unit as written; brackets and blanks around it are ignored.
        dimension: only a unit of this dimension (``time``, ``force``, ``length``) is returned.

    Returns:
        The unit, or None when ``text`` names no known unit (of ``dimension``).
    """
    t = clean_unit_text(text)
    if not t or t in _NOT_UNITS:
        return None
    unit = _BY_SPELLING.get(t.lower())
    if unit is None or (dimension is not None and unit.dimension != dimension):
        return None
    return unit


def unit_names(dimension: str) -> str:
    """The canonical units of ``dimension`` for messages: ``N, kN, mN, ...``."""
    return ", ".join(UNITS[dimension])


#: ``Load (N)``, ``Force [kN]``, ``Zeit [s]``, ``Displacement/mm``, ``Time in s``.
_HEADER_UNIT = (
    re.compile(r"^(?P<name>.*?)\s*[(\[{<]\s*(?P<unit>[^()\[\]{}<>]*?)\s*[)\]}>]\s*$"),
    re.compile(r"^(?P<name>.*?[^\s/])\s*/\s*(?P<unit>[^/\s][^/]*?)\s*$"),
    re.compile(r"^(?P<name>.+?)\s+in\s+(?P<unit>\S+)\s*$"),
)


def split_header(name: str) -> tuple[str, str | None]:
    """A column name and the unit it states: ``Load (N)`` → ``("Load", "N")``.

    Brackets (``Time (s)``, ``Force [kN]``), a slash (``Displacement/mm``) or ``in``
    (``Time in s``) mark the unit; the unit text is returned as written (see
    :func:`parse_unit`). A name without one is returned whole with None.
    """
    text = name.strip()
    for pattern in _HEADER_UNIT:
        m = pattern.match(text)
        if m and m.group("unit").strip() and m.group("name").strip():
            if pattern is not _HEADER_UNIT[0] and parse_unit(m.group("unit")) is None:
                continue  # "Force/Weight", "Time in tests": not a unit
            return m.group("name").strip(), m.group("unit").strip()
    return text, None
