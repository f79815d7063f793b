"""The printed-output blocks of the docs, and what the commands print now.

A ``text`` block that shows what commands print is preceded by the commands, each between
backticks::

    <!-- output-of: `deformctl characterize ef10.mcap -o ef10.parquet` -->

(optionally ``; rel 0.05`` before ``-->`` for a wider number tolerance). tests/test_docs.py runs
each page's ``sh`` blocks with a shell that marks where each command starts in the output
(:data:`TRAP`), so the output of every command run is known by its text; a marked command that
none of the page's blocks ran before the output block is run there (a command is named as bash
names it: ``>&2`` is ``1>&2``). stdout and stderr are read together, in the order printed.

:func:`mismatch` compares the block with that output line by line (blank lines and runs of
spaces do not count): text must be equal; ``…`` in the block stands for any text; a number with
a decimal point or exponent may differ by :data:`NUMBER_REL_TOL` of itself or one unit of its
last printed digit, whichever is larger; a whole number must be equal.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

#: The tolerance of decimal numbers in output blocks (relative), unless the marker states one.
NUMBER_REL_TOL = 0.02
#: What the shell prints (on stdout) before each simple command it runs.
SENTINEL = "@@docs-command@@ "
#: Prefix of every ``sh`` block run: announce each command (``$BASH_COMMAND``) on stdout.
TRAP = f'trap \'printf "\\n{SENTINEL}%s\\n" "$BASH_COMMAND"\' DEBUG\n'

ITEM = re.compile(
    r"(?:<!-- docs-test: skip \((?P<why>[^)]*)\) -->\n)?```sh\n(?P<code>.*?)```"
    r"|(?:<!-- output-of: (?P<cmds>(?:`[^`]+`\s*)+)(?:; rel (?P<rel>[0-9.e-]+)\s*)?-->\n)?"
    r"(?:<!-- (?P<bench>bench:[\w]+) -->\n)?```text\n(?P<out>.*?)```",
    re.S,
)
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


@dataclass(frozen=True)
class Item:
    """One ``sh`` block (``code``) or ``text`` block (``out``) of a page, in page order."""

    line: int
    code: str | None = None
    why: str | None = None
    out: str | None = None
    commands: tuple[str, ...] = ()
    rel: float = NUMBER_REL_TOL
    bench: str | None = None


def items(text: str) -> list[Item]:
    """The page's ``sh`` and ``text`` blocks, in order."""
    found = []
    for m in ITEM.finditer(text):
        line = text.count("\n", 0, m.start())
        if m["code"] is not None:
            found.append(Item(line, code=m["code"], why=m["why"]))
            continue
        cmds = tuple(re.findall(r"`([^`]+)`", m["cmds"] or ""))
        rel = float(m["rel"]) if m["rel"] else NUMBER_REL_TOL
        found.append(Item(line, out=m["out"], commands=cmds, rel=rel, bench=m["bench"]))
    return found


def norm_command(command: str) -> str:
    """A command's text with line continuations and runs of spaces collapsed."""
    return " ".join(command.replace("\\\n", " ").split())


def split_by_command(output: str) -> list[tuple[str, str]]:
    """``(command, its output)`` of a run under :data:`TRAP`, in order."""
    parts: list[tuple[str, list[str]]] = []
    for line in output.split("\n"):
        if line.startswith(SENTINEL):
            parts.append((norm_command(line[len(SENTINEL) :]), []))
        elif parts:
            parts[-1][1].append(line)
    return [(cmd, "\n".join(lines)) for cmd, lines in parts]


def _lines(text: str) -> list[str]:
    return [" ".join(line.split()) for line in text.splitlines() if line.strip()]


def _pattern(doc_line: str) -> tuple[re.Pattern[str], list[str]]:
    """A regex for one block line (numbers captured, ``…`` any text) and its numbers."""
    pieces: list[str] = []
    numbers: list[str] = []
    pos = 0
    for m in re.finditer(rf"{NUMBER.pattern}|…", doc_line):
        pieces.append(re.escape(doc_line[pos : m.start()]))
        if m.group() == "…":
            pieces.append(".*?")
        else:
            pieces.append(f"({NUMBER.pattern})")
            numbers.append(m.group())
        pos = m.end()
    pieces.append(re.escape(doc_line[pos:]))
    return re.compile("".join(pieces)), numbers


def _close(doc: str, now: str, rel: float) -> bool:
    if not re.search(r"[.eE]", doc):
        return doc.lstrip("+") == now.lstrip("+")
    a, b = float(doc), float(now)
    mantissa = doc.lower().split("e")[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    exponent = int(doc.lower().split("e")[1]) if "e" in doc.lower() else 0
    last_digit = 10.0 ** (exponent - decimals)
    return abs(a - b) <= max(rel * abs(a), last_digit) * (1 + 1e-9)


def mismatch(block: str, output: str, rel: float) -> str | None:
    """Why ``block`` is not what was printed (``output``), or None when it is."""
    doc, now = _lines(block), _lines(output)
    if len(doc) != len(now):
        return f"{len(doc)} line(s) shown, {len(now)} printed"
    for k, (d, n) in enumerate(zip(doc, now, strict=True), start=1):
        pattern, numbers = _pattern(d)
        m = pattern.fullmatch(n)
        if m is None:
            return f"line {k} differs:\n  shown:   {d}\n  printed: {n}"
        for want, got in zip(numbers, m.groups(), strict=True):
            if not _close(want, got, rel):
                return f"line {k}: {want} shown, {got} printed (rel {rel:g}):\n  printed: {n}"
    return None
