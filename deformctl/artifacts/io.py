"""Paths in and out: existence checks, ``-`` for stdin/stdout, atomic writes.

Every artifact writer goes through :func:`atomic_output`: the data is written to a temporary file
in the destination's directory and moved into place with :func:`os.replace` only when the writer
finished without an exception, so a reader never sees half a file and a failed write leaves
nothing behind. An existing destination is refused unless ``force`` is true.

``-`` stands for stdin (inputs) or stdout (outputs). Inputs are read into memory whole, which is
what MCAP needs anyway (its reader seeks).

Temporary files are named ``.<output name>.deformctl-<pid>-<random>.tmp``: a run killed before
its rename (``kill -9``) leaves one behind, and the next run writing the same output removes the
ones whose process is gone (:func:`remove_stale_temporaries`). Outputs written inside
:func:`committed_together` are renamed into place together when the block ends (in the order
they were written: the table last), so a failure leaves none of them.

Output checks (:func:`check_output_path`, before any work): the folder exists and is writable,
the name fits the file system (with room for the temporary name), a path ending in ``/`` is a
directory (refused where a file is written), binary formats are not written to a terminal, and
an output is never one of the command's inputs (every input path is noted when it is checked),
``--force`` or not.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import stat
import sys
from collections.abc import Iterator
from contextvars import ContextVar
from pathlib import Path
from typing import Any

from deformctl.errors import (
    DeformctlError,
    InputDataError,
    MissingInputError,
    OutputExistsError,
    UsageError,
)

STDIO = "-"  #: the path that means stdin or stdout

PathArg = str | os.PathLike[str]


def is_stdio(path: PathArg) -> bool:
    """True when ``path`` is ``-`` (stdin for inputs, stdout for outputs)."""
    return os.fspath(path) == STDIO


def display_name(path: PathArg) -> str:
    """The name used in error messages: the path as given, ``<stdin>`` for ``-``."""
    return "<stdin>" if is_stdio(path) else os.fspath(path)


#: The inputs the running command has checked (resolved paths): an output may never be one of
#: them. None outside a command (library use may read a file and write it back on purpose).
_INPUTS: set[str] | None = None

#: Room kept in a file name for the temporary name around it (``.NAME.deformctl-PID-RAND.tmp``).
TEMP_NAME_ROOM = 40


def note_input(path: PathArg) -> None:
    """Remember ``path`` as an input of the running command (see :func:`check_not_an_input`)."""
    if _INPUTS is not None and not is_stdio(path):
        _INPUTS.add(os.path.realpath(path))


@contextlib.contextmanager
def command_inputs() -> Iterator[None]:
    """Track the inputs of one command (the CLI wraps every command in this)."""
    global _INPUTS
    outer, _INPUTS = _INPUTS, set()
    try:
        yield
    finally:
        _INPUTS = outer


def forget_inputs(path: PathArg) -> None:
    """Forget ``path`` as an input: a file the command updates in place on purpose (a catalog a
    row is appended to)."""
    if _INPUTS is not None:
        _INPUTS.discard(os.path.realpath(path))


def check_not_an_input(path: PathArg) -> None:
    """Refuse an output that resolves to one of the running command's inputs, ``--force`` or
    not.

    Raises:
        UsageError: one line naming the path (exit 2).
    """
    if _INPUTS and not is_stdio(path) and os.path.realpath(path) in _INPUTS:
        raise UsageError(f"{os.fspath(path)}: the output is one of the inputs; choose another name")


def check_input_path(path: PathArg) -> Path | str:
    """Check that an input exists and is a readable file.

    Args:
        path: the input path, or ``-`` for stdin.

    Returns:
        ``"-"`` unchanged, otherwise the path as a :class:`~pathlib.Path`.

    Raises:
        MissingInputError: the path does not exist, is a directory or cannot be read (exit 66).
    """
    if is_stdio(path):
        return STDIO
    p = Path(path)
    if not p.exists():
        raise MissingInputError("no such file", path=p)
    if p.is_dir():
        raise MissingInputError("is a directory, expected a file", path=p)
    if not os.access(p, os.R_OK):
        raise MissingInputError("cannot be read (permission denied)", path=p)
    note_input(p)
    return p


#: The most bytes one input is read into memory: an artifact deformctl writes (a log, a table,
#: a model) is far smaller; a larger one, or a device that never ends (``/dev/zero``), is refused
#: instead of filling the memory. ``DEFORMCTL_READ_BUDGET_GIB`` raises it.
READ_BUDGET_BYTES = 2 << 30
_BLOCK_BYTES = 1 << 20


def read_budget_bytes() -> int:
    """:data:`READ_BUDGET_BYTES`, or ``DEFORMCTL_READ_BUDGET_GIB`` GiB when set to a number > 0."""
    raw = os.environ.get("DEFORMCTL_READ_BUDGET_GIB")
    try:
        gib = float(raw) if raw else 0.0
    except ValueError:
        gib = 0.0
    return int(gib * (1 << 30)) if gib > 0 and gib < 1 << 20 else READ_BUDGET_BYTES


def read_input_bytes(path: PathArg) -> bytes:
    """Read a whole input file (or stdin for ``-``) into memory, within the reading budget.

    The file type and size come first: a device (``/dev/zero``, a terminal, a socket) is refused
    before any read, a regular file larger than :func:`read_budget_bytes` too; stdin and pipes
    are read up to the budget.

    Raises:
        MissingInputError: the input does not exist or cannot be opened (exit 66).
        InputDataError: a device, or more bytes than the budget (exit 65).
    """
    checked = check_input_path(path)
    budget = read_budget_bytes()
    if isinstance(checked, str):
        return _read_capped(sys.stdin.buffer, budget, "<stdin>")
    try:
        mode = checked.stat()
        if stat.S_ISCHR(mode.st_mode) or stat.S_ISBLK(mode.st_mode) or stat.S_ISSOCK(mode.st_mode):
            raise InputDataError("is a device, not a file: refused before reading", path=checked)
        if stat.S_ISREG(mode.st_mode) and mode.st_size > budget:
            raise InputDataError(
                f"is {mode.st_size / (1 << 30):.3g} GiB, more than the reading budget of "
                f"{budget / (1 << 30):.3g} GiB (DEFORMCTL_READ_BUDGET_GIB raises it)",
                path=checked,
            )
        with checked.open("rb") as fh:
            return _read_capped(fh, budget, checked)
    except OSError as err:
        raise MissingInputError(f"cannot be read: {err.strerror or err}", path=checked) from err


def _read_capped(fh: Any, budget: int, name: PathArg) -> bytes:
    """Everything ``fh`` holds, refusing more than ``budget`` bytes."""
    chunks: list[bytes] = []
    total = 0
    while True:
        block = fh.read(_BLOCK_BYTES)
        if not block:
            return b"".join(chunks)
        total += len(block)
        if total > budget:
            raise InputDataError(
                f"more than the reading budget of {budget / (1 << 30):.3g} GiB "
                "(DEFORMCTL_READ_BUDGET_GIB raises it)",
                path=name,
            )
        chunks.append(block)


def check_output_path(path: PathArg, force: bool, *, binary: bool = True) -> Path | str:
    """Check that an output may be written, before any work.

    Args:
        path: the output path, or ``-`` for stdout.
        force: overwrite an existing file.
        binary: the format is binary (Parquet, MCAP, skops): refused on a terminal.

    Returns:
        ``"-"`` unchanged, otherwise the path as a :class:`~pathlib.Path`.

    Raises:
        OutputExistsError: the file exists and ``force`` is false (exit 1).
        UsageError: binary output to a terminal, a path ending in ``/`` (a directory where a file
            is written), a file name too long for the file system, or an output that is one of
            the inputs (exit 2).
        DeformctlError: the path is a directory, its directory does not exist or is not
            writable (exit 1).
    """
    if is_stdio(path):
        if binary and sys.stdout.isatty():
            raise UsageError(
                "refusing to write binary output to a terminal; redirect stdout or give -o FILE"
            )
        return STDIO
    text = os.fspath(path)
    if text.endswith(("/", os.sep)):
        raise UsageError(f"{text}: ends in '/', a directory; this output is one file")
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    try:
        name_max = os.pathconf(parent, "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    length = len(os.fsencode(p.name))
    if length + TEMP_NAME_ROOM > name_max:
        raise UsageError(
            f"{text}: the file name is {length} bytes; this file system allows {name_max}, "
            f"less {TEMP_NAME_ROOM} for the temporary name"
        )
    check_not_an_input(path)
    try:
        if p.is_dir():
            raise DeformctlError("is a directory, expected a file name", path=p)
        if p.exists() and not force:
            raise OutputExistsError(p)
        if not parent.is_dir():
            raise DeformctlError(f"directory {str(parent)!r} does not exist", path=p)
    except OSError as err:  # a path component too long, a symlink loop, ...
        raise UsageError(f"{text}: not a usable output path ({err.strerror or err})") from None
    if not os.access(parent, os.W_OK | os.X_OK):
        raise DeformctlError(f"directory {str(parent)!r} is not writable", path=p)
    return p


def _temp_pattern(name: str) -> re.Pattern[str]:
    return re.compile(re.escape(f".{name}.deformctl-") + r"(\d+)-[0-9a-f]+\.tmp")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: alive
        return True
    return True


def stale_temporaries(dest: PathArg) -> list[Path]:
    """The temporary files of ``dest`` left by killed runs (their process is gone)."""
    p = Path(dest)
    parent = p.parent if str(p.parent) else Path(".")
    pattern = _temp_pattern(p.name)
    try:
        names = os.listdir(parent)
    except OSError:
        return []
    out = []
    for name in sorted(names):
        m = pattern.fullmatch(name)
        if m is not None and not _alive(int(m.group(1))):
            out.append(parent / name)
    return out


def remove_stale_temporaries(dest: PathArg) -> list[Path]:
    """Remove (and return) the temporary files of ``dest`` whose writer was killed."""
    removed = []
    for tmp in stale_temporaries(dest):
        with contextlib.suppress(OSError):
            tmp.unlink()
            removed.append(tmp)
    return removed


#: The outputs of the enclosing :func:`committed_together` block: (temporary, destination, force).
_GROUP: ContextVar[list[tuple[Path, Path, bool]] | None] = ContextVar("_GROUP", default=None)


@contextlib.contextmanager
def committed_together() -> Iterator[None]:
    """Rename every output written inside the block into place together, at its end.

    Each :func:`atomic_output` in the block writes its temporary file as usual but leaves the
    rename to the end of the block, which renames them in the order written (write the table
    last); an exception (or a kill) anywhere in the block leaves none of the outputs.

    Raises:
        OutputExistsError: an output appeared meanwhile and its writer had no ``force`` (exit 1);
            nothing is renamed then.
    """
    if _GROUP.get() is not None:  # nested: the outer block commits
        yield
        return
    pending: list[tuple[Path, Path, bool]] = []
    token = _GROUP.set(pending)
    try:
        yield
        for _tmp, dest, force in pending:
            if dest.exists() and not force:
                raise OutputExistsError(dest)
        for tmp, dest, _force in pending:
            try:
                os.replace(tmp, dest)
            except OSError as err:
                raise DeformctlError(f"cannot write: {err.strerror or err}", path=dest) from None
    finally:
        _GROUP.reset(token)
        for tmp, _dest, _force in pending:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_output(
    path: PathArg, *, force: bool = False, durable: bool = False, binary: bool = True
) -> Iterator[Path]:
    """Yield a temporary path to write to; move it to ``path`` when the block succeeds.

    The temporary file lives in the destination's directory (so the final :func:`os.replace` is
    atomic) and is removed when the block raises. For ``path == "-"`` the finished file is copied
    to stdout instead.

    Args:
        path: the destination, or ``-`` for stdout.
        force: overwrite an existing destination.
        durable: ``fsync`` the file before the rename (a sweep's parts, which a resumed run
            trusts after a crash).
        binary: a binary format (refused on a terminal stdout).

    Yields:
        A path to an empty temporary file that the caller writes.

    Raises:
        OutputExistsError: the destination exists and ``force`` is false; checked both before the
            block runs and again before the rename.
        DeformctlError: the temporary file cannot be created (a read-only folder) or written
            (a full disk, ``ulimit -f``): one line, nothing left behind (exit 1).

    Example:
        >>> with atomic_output("out.parquet", force=True) as tmp:  # doctest: +SKIP
        ...     tmp.write_bytes(data)
    """
    dest = check_output_path(path, force, binary=binary)
    if isinstance(dest, str):
        with tempfile_dir() as tmpdir:
            tmp = Path(tmpdir) / "stdout"
            tmp.touch()
            yield tmp
            with tmp.open("rb") as src:
                shutil.copyfileobj(src, sys.stdout.buffer)
            sys.stdout.buffer.flush()
        return
    parent = dest.parent if str(dest.parent) else Path(".")
    remove_stale_temporaries(dest)
    tmp = parent / f".{dest.name}.deformctl-{os.getpid()}-{os.urandom(4).hex()}.tmp"
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as err:
        raise DeformctlError(
            f"cannot write in {str(parent)!r}: {err.strerror or err}", path=dest
        ) from None
    os.close(fd)
    group = _GROUP.get()
    try:
        yield tmp
        if dest.exists() and not force:
            raise OutputExistsError(dest)
        if durable:
            with tmp.open("rb") as fh:
                os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        if group is not None:
            group.append((tmp, dest, force))
        else:
            os.replace(tmp, dest)
    except OSError as err:  # a full disk, a file size limit, a folder gone read-only
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise DeformctlError(f"cannot write: {err.strerror or err}", path=dest) from None
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise


@contextlib.contextmanager
def tempfile_dir() -> Iterator[str]:
    """A private temporary directory (for a stdout output), removed afterwards."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="deformctl-") as tmpdir:
        yield tmpdir


def atomic_write_bytes(path: PathArg, data: bytes) -> None:
    """Write ``data`` to ``path`` (overwriting it) through :func:`atomic_output`, fsynced."""
    with atomic_output(path, force=True, durable=True) as tmp:
        tmp.write_bytes(data)
