"""The options of a CSV export, checked once: how its text is read and what its columns mean.

``measure --csv`` builds them from its flags and the library takes them
(:func:`deformctl.measure.stage.read_recording`); :meth:`CsvOptions.as_dict` is what the squeeze
log's provenance records. Every field left ``None`` is found in the file itself (the delimiter,
the decimal mark, the header row, the columns and their units, the force's sign) and what was
found is recorded next to what was given (:class:`deformctl.measure.csv.table.CsvLayout`).
"""

from __future__ import annotations

import codecs
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from deformctl.errors import UsageError
from deformctl.measure.options import check_position_options
from deformctl.quantities import LAG_S, MEMORY_BUDGET_GIB
from deformctl.units import parse_unit, unit_names

#: The delimiters a file's rows are tried with, in order of preference on a tie.
DELIMITERS: tuple[str, ...] = (",", ";", "\t")
#: Names of the delimiters for messages and options (``--delimiter tab``).
DELIMITER_NAMES: dict[str, str] = {",": ",", ";": ";", "\t": "tab"}
DECIMALS: tuple[str, ...] = (".", ",")
#: Thousands separators a file may use (``1,234.5``, ``1.234,5``, ``1 234,5``, ``1'234.5``).
THOUSANDS: tuple[str, ...] = (",", ".", " ", "'")
ForceSign = Literal["auto", "positive", "negative"]
FORCE_SIGNS: tuple[str, ...] = ("auto", "positive", "negative")
#: The roles a column can have; ``position``, ``gap`` and ``compression`` are the position
#: signal (one of them), see :mod:`deformctl.measure.recording`.
ROLES: tuple[str, ...] = ("time", "force", "position", "gap", "compression")
POSITION_ROLES: tuple[str, ...] = ("position", "gap", "compression")
#: The dimension of each role's unit.
ROLE_DIMENSION: dict[str, str] = {
    "time": "time",
    "force": "force",
    "position": "length",
    "gap": "length",
    "compression": "length",
}
#: A shift of the force against the position larger than this is refused, s.
MAX_LAG_S = LAG_S.high
#: The memory a CSV run may use by default, GiB (the simulator's default budget).
DEFAULT_CSV_MEMORY_BUDGET_GIB = 2.0


def _delimiter(value: str | None) -> str | None:
    if value is None:
        return None
    named = {"tab": "\t", "\\t": "\t", "comma": ",", "semicolon": ";"}
    d = named.get(value.lower(), value)
    if d not in DELIMITERS:
        raise UsageError(f"--delimiter must be one of ',', ';', tab, got {value!r}")
    return d


@dataclass(frozen=True)
class CsvDialect:
    """How the text of a CSV export is read.

    Attributes:
        delimiter: ``,``, ``;`` or a tab (``tab``); None: the one that splits the data rows
            into the same number of numeric cells (sniffed from the first rows).
        decimal: ``.`` or ``,``; None: sniffed (a comma only when it is not the delimiter and
            no cell is read differently either way).
        thousands: the thousands separator (``,``, ``.``, space, ``'``); None: sniffed from
            grouped numbers such as ``"1,234.5"``.
        encoding: the text encoding (any Python codec name: ``utf-8``, ``gbk``,
            ``cp1252``); a UTF-8 byte-order mark is skipped.
        skip_rows: the header is the line after this many lines (a preamble); None: the
            first row of mostly text cells followed by numeric rows.

    Raises:
        UsageError: an unknown delimiter, decimal mark, separator or encoding, a decimal mark
            equal to the delimiter or the separator, or a negative ``skip_rows`` (exit 2).
    """

    delimiter: str | None = None
    decimal: str | None = None
    thousands: str | None = None
    encoding: str = "utf-8"
    skip_rows: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "delimiter", _delimiter(self.delimiter))
        if self.decimal is not None and self.decimal not in DECIMALS:
            raise UsageError(f"--decimal must be '.' or ',', got {self.decimal!r}")
        if self.thousands is not None:
            if self.thousands.lower() == "space":
                object.__setattr__(self, "thousands", " ")
            if self.thousands not in THOUSANDS:
                raise UsageError(
                    f"--thousands must be one of ',', '.', space, \"'\", got {self.thousands!r}"
                )
        if self.decimal is not None and self.decimal in (self.delimiter, self.thousands):
            raise UsageError(
                f"--decimal {self.decimal!r} is also the "
                f"{'delimiter' if self.decimal == self.delimiter else 'thousands separator'}"
            )
        try:
            codecs.lookup(self.encoding)
        except LookupError:
            raise UsageError(
                f"--encoding: unknown encoding {self.encoding!r} (e.g. utf-8, gbk, cp1252, latin-1)"
            ) from None
        if self.skip_rows is not None and (
            isinstance(self.skip_rows, bool) or not isinstance(self.skip_rows, int)
        ):
            raise UsageError(f"--skip-rows must be an integer >= 0, got {self.skip_rows!r}")
        if self.skip_rows is not None and self.skip_rows < 0:
            raise UsageError(f"--skip-rows must be an integer >= 0, got {self.skip_rows}")

    def as_dict(self) -> dict[str, Any]:
        """The dialect by name, for provenance (None: found in the file)."""
        return {
            "delimiter": self.delimiter,
            "decimal": self.decimal,
            "thousands": self.thousands,
            "encoding": self.encoding,
            "skip_rows": self.skip_rows,
        }


def parse_lag(text: str | float | None) -> float | Literal["auto"] | None:
    """``--lag-s``: ``auto``, a number of seconds (:data:`deformctl.quantities.LAG_S`), or None
    (not given).

    Raises:
        UsageError: neither ``auto`` nor a number within the rule (exit 2).
    """
    if text is None:
        return None
    if text == "auto":
        return "auto"
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise UsageError(f"{LAG_S.flag} must be auto or {LAG_S.rule}, got {text!r}") from None
    problem = LAG_S.problem(value)
    if problem is not None:
        raise UsageError(f"{LAG_S.flag} must be auto or {problem.removeprefix('must be ')}")
    return value


@dataclass(frozen=True)
class CsvOptions:
    """What the columns of a CSV export are, and how to read them (``measure --csv``).

    Attributes:
        dialect: how the text is read (:class:`CsvDialect`).
        columns: role → column, for the roles to take from a given column (a header name,
            with or without its unit, e.g. ``Load (N)`` or ``Load``); the roles not given are
            found by name (:mod:`deformctl.measure.csv.columns`). Roles: ``time``, ``force``
            and at most one of ``position`` (a travel, read as ``position_is`` says), ``gap``
            (between the palms) or ``compression`` (a testing machine's crosshead travel).
        units: role → unit, for the roles whose unit the file does not state; a unit the file
            states must agree (else exit 2 naming both). Time s/ms/µs/ns/min, force
            N/kN/mN/daN/lbf/ozf/kgf/gf, length m/cm/mm/µm/in.
        force_sign: ``positive`` (compression gives a positive force), ``negative`` (it gives
            a negative one: flipped), ``auto`` (the sign that grows with the compression).
        lag_s: shift the force this much earlier before anything else (it lags the position
            by ``lag_s``), ``auto`` (the lag estimated on the loading ramp, when it can be
            estimated) or None (estimated and reported, not shifted).
        position_is: how a ``position`` column is read: ``travel`` (the compression: a
            testing machine's crosshead travel, a gripper's jaw travel; the default), ``palm``
            (one palm's travel, its partner mirroring it: d = 2 × travel) or ``gap`` (the
            distance between the palms: d = gap(t0) − gap).
        compression_zero: ``first`` (the first row) or ``lead_in``.
        position_increases_when: ``closing`` or ``opening``; None: a compression grows when
            closing, a gap when opening, one palm's sign is found.
        memory_budget_gib: refuse a file whose reading would need more memory than this, GiB.

    Raises:
        UsageError: an unknown role, two position roles, a unit that names no known unit of
            the role's dimension, or a value outside its rule (exit 2).
    """

    dialect: CsvDialect = field(default_factory=CsvDialect)
    columns: Mapping[str, str] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    force_sign: ForceSign = "auto"
    lag_s: float | Literal["auto"] | None = None
    position_is: Literal["travel", "palm", "gap"] = "travel"
    compression_zero: Literal["first", "lead_in"] = "first"
    position_increases_when: Literal["closing", "opening"] | None = None
    memory_budget_gib: float = DEFAULT_CSV_MEMORY_BUDGET_GIB

    kind = "csv"  #: the ``source`` a squeeze log's object row records

    def __post_init__(self) -> None:
        object.__setattr__(self, "columns", {k.strip(): v for k, v in self.columns.items()})
        object.__setattr__(self, "units", {k.strip(): v for k, v in self.units.items()})
        for option, mapping in (("--columns", self.columns), ("--units", self.units)):
            unknown = sorted(set(mapping) - set(ROLES))
            if unknown:
                raise UsageError(
                    f"{option}: unknown key {unknown[0]!r}; valid keys: {', '.join(ROLES)}"
                )
        given = [k for k in POSITION_ROLES if k in self.columns]
        if len(given) > 1:
            raise UsageError(
                f"--columns maps {' and '.join(given)}: give one position signal (position, gap "
                "or compression)"
            )
        for role, name in self.columns.items():
            if not str(name).strip():
                raise UsageError(f"--columns: {role}= names no column")
        for role, text in self.units.items():
            dim = ROLE_DIMENSION[role]
            if parse_unit(text, dim) is None:
                raise UsageError(
                    f"--units: unknown {dim} unit {text!r} for {role}; known: {unit_names(dim)}"
                )
        if self.force_sign not in FORCE_SIGNS:
            raise UsageError(
                f"--force-sign must be one of {', '.join(FORCE_SIGNS)}, got {self.force_sign!r}"
            )
        object.__setattr__(self, "lag_s", parse_lag(self.lag_s))
        check_position_options(
            self.position_is, self.compression_zero, self.position_increases_when
        )
        MEMORY_BUDGET_GIB.check(self.memory_budget_gib)

    def unit_for(self, role: str) -> str | None:
        """The unit given for ``role`` (as written), or None."""
        return self.units.get(role)

    def as_dict(self) -> dict[str, Any]:
        """The options by name, for provenance (None: found in the file)."""
        return {
            **self.dialect.as_dict(),
            "columns": dict(self.columns),
            "units": dict(self.units),
            "force_sign": self.force_sign,
            "lag_s": self.lag_s,
            "position_is": self.position_is,
            "compression_zero": self.compression_zero,
            "position_increases_when": self.position_increases_when,
            "memory_budget_gib": self.memory_budget_gib,
        }
