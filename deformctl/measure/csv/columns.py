"""Which column of a CSV export is the time, the force and the position, and in which unit.

**Roles by name.** A column's name (its unit stripped, :func:`deformctl.units.split_header`) is
matched against the words of each role (:data:`ROLE_WORDS`): the whole name (``Load``) beats a
word in it (``Standard force``); names with a word of :data:`NOT_A_SIGNAL` (``Commanded force``,
``Force rate``, ``Engineering strain``) are never taken. The position signal is one of
``compression`` (a testing machine's crosshead travel), ``position`` (one palm's travel) and
``gap`` (the distance between the palms). A role given in ``--columns`` is taken as given; a
role with two equally good candidates is an error listing them (exit 2), as is a file with
none (exit 65, listing the header).

**Units.** A role's unit comes from its name (``Load (N)``), else from the units row under the
header (``(kN)``), else from ``--units``; with none, SI (s, N, m) and a warning. A unit the file
states and a ``--units`` value that differs are an error naming both (exit 2); a unit the file
states that is not a unit of the role's dimension is an error (exit 65).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from deformctl.errors import InputDataError, UsageError
from deformctl.measure.csv.options import POSITION_ROLES, ROLE_DIMENSION, ROLES, CsvOptions
from deformctl.measure.csv.table import CsvLayout
from deformctl.units import UNITS, Unit, clean_unit_text, parse_unit, split_header, unit_names

#: The words that name each role (lower case; CJK words match anywhere in a name).
ROLE_WORDS: dict[str, tuple[str, ...]] = {
    "time": ("time", "zeit", "t", "timestamp", "elapsed", "temps", "tiempo", "tempo", "时间",
             "時間", "测试时间", "试验时间"),
    "force": ("force", "load", "kraft", "standardkraft", "fz", "力", "载荷", "负荷", "荷重",
              "荷载", "拉力", "压力"),
    "compression": ("compression", "displacement", "extension", "deformation", "deflection",
                    "crosshead", "stroke", "weg", "standardweg", "traversenweg", "verformung",
                    "位移", "变形", "压缩", "变位"),
    "position": ("position", "pos", "gripper position", "palm position", "位置"),
    "gap": ("gap", "width", "opening", "aperture", "gripper width", "开口"),
}  # fmt: skip
#: A name with one of these words is not a measured signal of a role (a command, a rate, a
#: derived quantity).
NOT_A_SIGNAL: tuple[str, ...] = (
    "command", "commanded", "cmd", "target", "setpoint", "set", "soll", "desired", "reference",
    "ref", "estimate", "estimated", "stiffness", "rate", "speed", "velocity", "strain", "stress",
    "energy", "work", "index", "cycle", "count", "date", "unix",
)  # fmt: skip
_CJK = re.compile(r"[\u3040-\u9fff]")


def _words(name: str) -> list[str]:
    return [w for w in re.split(r"[\s_\-.:/,;#]+", name.lower()) if w]


def _score(base: str, role: str) -> int:
    """How well a column's base name fits a role: 3 whole name, 2 word(s), 0 none."""
    lowered = " ".join(_words(base))
    words = set(_words(base))
    if words & set(NOT_A_SIGNAL):
        return 0
    best = 0
    for word in ROLE_WORDS[role]:
        if lowered == word:
            return 3
        if _CJK.search(word):
            if word in base:
                best = max(best, 2)
        elif " " in word:
            if f" {word} " in f" {lowered} ":
                best = max(best, 2)
        elif len(word) > 1 and word in words:
            best = max(best, 2)
    return best


@dataclass(frozen=True)
class ColumnRole:
    """One role's column and unit, and where each came from.

    Attributes:
        role: time, force, position, gap or compression.
        index: the column, 0-based.
        name: its header cell.
        unit: the unit its numbers are in.
        column_from: ``name`` (matched by name) or ``--columns``.
        unit_from: ``header`` (in the name), ``units row``, ``--units`` or ``default`` (SI).
    """

    role: str
    index: int
    name: str
    unit: Unit
    column_from: str
    unit_from: str

    def describe(self) -> str:
        """``force='Load (N)' [N]``."""
        return f"{self.role}={self.name!r} [{self.unit.name}]"

    def as_dict(self) -> dict[str, Any]:
        """What the squeeze log records of this role."""
        return {
            "column": self.name,
            "unit": self.unit.name,
            "column_from": self.column_from,
            "unit_from": self.unit_from,
        }


def _find_given(layout: CsvLayout, role: str, wanted: str) -> int:
    """The column ``--columns role=wanted`` names: the header cell, or its name without unit."""
    exact = [i for i, n in enumerate(layout.names) if n == wanted]
    if exact:
        return exact[0]
    loose = [
        i
        for i, n in enumerate(layout.names)
        if split_header(n)[0].lower() == split_header(wanted)[0].lower()
        or n.lower() == wanted.lower()
    ]
    if len(loose) == 1:
        return loose[0]
    if len(loose) > 1:
        listed = ", ".join(repr(layout.names[i]) for i in loose)
        raise UsageError(f"--columns {role}={wanted!r} matches several columns: {listed}")
    raise InputDataError(
        f"--columns {role}={wanted!r} names no column of the header ({layout.describe_header()}); "
        "if the header is another line, pass --skip-rows N (the lines above it)"
    )


def _candidates(layout: CsvLayout, role: str, taken: set[int]) -> tuple[int, list[int]]:
    scores = [(_score(split_header(n)[0], role), i) for i, n in enumerate(layout.names)]
    scores = [(s, i) for s, i in scores if s > 0 and i not in taken]
    if not scores:
        return 0, []
    top = max(s for s, _ in scores)
    return top, [i for s, i in scores if s == top]


def _ambiguous(layout: CsvLayout, what: str, found: list[int], flags: str) -> UsageError:
    listed = ", ".join(repr(layout.names[i]) for i in found)
    return UsageError(f"cannot tell which column is {what}: {listed}; pass --columns {flags}")


def assign_columns(layout: CsvLayout, options: CsvOptions) -> dict[str, int]:
    """Role → column index for time, force and one position role.

    Raises:
        UsageError: a role with several equally good candidates (lists them), or a
            ``--columns`` name that matches several columns (exit 2).
        InputDataError: a role with no column (lists the header and suggests ``--skip-rows``)
            or a ``--columns`` name that is not in the header (exit 65).
    """
    chosen: dict[str, int] = {}
    for role, wanted in options.columns.items():
        chosen[role] = _find_given(layout, role, wanted)
    for role in ("time", "force"):
        if role in chosen:
            continue
        _, found = _candidates(layout, role, set(chosen.values()))
        if len(found) > 1:
            raise _ambiguous(layout, f"the {role}", found, f"{role}=NAME")
        if not found:
            raise InputDataError(_missing(layout, role))
        chosen[role] = found[0]
    if not any(r in chosen for r in POSITION_ROLES):
        taken = set(chosen.values())
        best: list[tuple[str, int]] = []
        top = 0
        for role in POSITION_ROLES:
            score, found = _candidates(layout, role, taken)
            if score > top:
                top, best = score, [(role, i) for i in found]
            elif score == top and score > 0:
                best += [(role, i) for i in found]
        if not best:
            raise InputDataError(_missing(layout, "compression, position or gap"))
        if len(best) > 1:
            raise _ambiguous(
                layout,
                "the position signal",
                [i for _, i in best],
                "compression=NAME (or position=NAME, gap=NAME)",
            )
        chosen[best[0][0]] = best[0][1]
    return {role: chosen[role] for role in ROLES if role in chosen}


def _missing(layout: CsvLayout, what: str) -> str:
    return (
        f"no column for the {what} in the header ({layout.describe_header()}); pass --columns "
        f"(e.g. {what.split(',')[0]}=NAME), or --skip-rows N if the header is another line"
    )


def _file_unit(layout: CsvLayout, index: int) -> tuple[str | None, str]:
    """The unit text the file states for a column, and where: its name or the units row."""
    _, in_name = split_header(layout.names[index])
    if in_name is not None:
        return in_name, "header"
    cell = layout.units_row[index] if index < len(layout.units_row) else ""
    if cell and clean_unit_text(cell) not in ("", "-"):
        return cell, "units row"
    return None, "default"


def column_roles(layout: CsvLayout, options: CsvOptions) -> dict[str, ColumnRole]:
    """Each role's column and unit (see the module docstring).

    Raises:
        UsageError: as :func:`assign_columns`, or a ``--units`` value that contradicts the unit
            the file states (names both; exit 2).
        InputDataError: as :func:`assign_columns`, or a unit in the file that is unknown or not
            of the role's dimension (exit 65).
    """
    chosen = assign_columns(layout, options)
    for role in options.units:
        if role not in chosen:
            mapped = ", ".join(f"{r}={layout.names[i]!r}" for r, i in chosen.items())
            raise UsageError(
                f"--units: {role!r} names no column ({mapped}); valid keys: {', '.join(chosen)}"
            )
    roles: dict[str, ColumnRole] = {}
    for role, index in chosen.items():
        dim = ROLE_DIMENSION[role]
        name = layout.names[index]
        text, where = _file_unit(layout, index)
        given = options.unit_for(role)
        given_unit = None if given is None else parse_unit(given, dim)
        if text is not None:
            unit = parse_unit(text, dim)
            if unit is None:
                other = parse_unit(text)
                what = (
                    f"a {other.dimension} unit, not a {dim} unit"
                    if other is not None
                    else f"not a known {dim} unit"
                )
                raise InputDataError(
                    f"column {name!r} ({role}): unit {text!r} in the {where} is {what}; known: "
                    f"{unit_names(dim)}"
                )
            if given_unit is not None and given_unit.si != unit.si:
                raise UsageError(
                    f"--units {role}={given} contradicts the file: column {name!r} is in "
                    f"{unit.name} (its {where} says {text!r})"
                )
        elif given_unit is not None:
            unit, where = given_unit, "--units"
        else:
            unit = next(iter(UNITS[dim].values()))
        roles[role] = ColumnRole(
            role,
            index,
            name,
            unit,
            "--columns" if role in options.columns else "name",
            where,
        )
    return roles


def describe_roles(roles: Mapping[str, ColumnRole]) -> str:
    """``time='Time (s)' [s], force='Load (N)' [N], compression='Compression (mm)' [mm]``."""
    return ", ".join(r.describe() for r in roles.values())
