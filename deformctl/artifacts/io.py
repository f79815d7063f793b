"""Paths in and out: existence checks, ``-`` for stdin/stdout, atomic writes.

Every artifact writer goes through :func:`atomic_output`: the data is written to a temporary file
in the destination's directory and moved into place with :func:`os.replace` only when the writer
finished without an exception, so a reader never sees half a file and a failed write leaves
nothing behind. An existing destination is refused unless ``force`` is true.

``-`` stands for stdin (inputs) or stdout (outputs). Inputs are read into memory whole, which is
what MCAP needs anyway (its reader seeks).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

from deformctl.errors import DeformctlError, MissingInputError, OutputExistsError

STDIO = "-"  #: the path that means stdin or stdout

PathArg = str | os.PathLike[str]


def is_stdio(path: PathArg) -> bool:
    """True when ``path`` is ``-`` (stdin for inputs, stdout for outputs)."""
    return os.fspath(path) == STDIO


def display_name(path: PathArg) -> str:
    """The name used in error messages: the path as given, ``<stdin>`` for ``-``."""
    return "<stdin>" if is_stdio(path) else os.fspath(path)


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
    return p


def read_input_bytes(path: PathArg) -> bytes:
    """Read a whole input file (or stdin for ``-``) into memory.

    Raises:
        MissingInputError: the input does not exist or cannot be opened (exit 66).
    """
    checked = check_input_path(path)
    if isinstance(checked, str):
        return sys.stdin.buffer.read()
    try:
        return checked.read_bytes()
    except OSError as err:
        raise MissingInputError(f"cannot be read: {err.strerror or err}", path=checked) from err


def check_output_path(path: PathArg, force: bool) -> Path | str:
    """Check that an output may be written.

    Args:
        path: the output path, or ``-`` for stdout.
        force: overwrite an existing file.

    Returns:
        ``"-"`` unchanged, otherwise the path as a :class:`~pathlib.Path`.

    Raises:
        OutputExistsError: the file exists and ``force`` is false (exit 1).
        DeformctlError: the path is a directory or its directory does not exist (exit 1).
    """
    if is_stdio(path):
        return STDIO
    p = Path(path)
    if p.is_dir():
        raise DeformctlError("is a directory, expected a file name", path=p)
    if p.exists() and not force:
        raise OutputExistsError(p)
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise DeformctlError(f"directory {str(parent)!r} does not exist", path=p)
    return p


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_output(path: PathArg, *, force: bool = False, durable: bool = False) -> Iterator[Path]:
    """Yield a temporary path to write to; move it to ``path`` when the block succeeds.

    The temporary file lives in the destination's directory (so the final :func:`os.replace` is
    atomic) and is removed when the block raises. For ``path == "-"`` the finished file is copied
    to stdout instead.

    Args:
        path: the destination, or ``-`` for stdout.
        force: overwrite an existing destination.
        durable: ``fsync`` the file before the rename (a sweep's parts, which a resumed run
            trusts after a crash).

    Yields:
        A path to an empty temporary file that the caller writes.

    Raises:
        OutputExistsError: the destination exists and ``force`` is false; checked both before the
            block runs and again before the rename.

    Example:
        >>> with atomic_output("out.parquet", force=True) as tmp:  # doctest: +SKIP
        ...     tmp.write_bytes(data)
    """
    dest = check_output_path(path, force)
    if isinstance(dest, str):
        with tempfile.TemporaryDirectory(prefix="deformctl-") as tmpdir:
            tmp = Path(tmpdir) / "stdout"
            tmp.touch()
            yield tmp
            with tmp.open("rb") as src:
                shutil.copyfileobj(src, sys.stdout.buffer)
            sys.stdout.buffer.flush()
        return
    parent = dest.parent if str(dest.parent) else Path(".")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        if dest.exists() and not force:
            raise OutputExistsError(dest)
        if durable:
            with tmp.open("rb") as fh:
                os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise


def atomic_write_bytes(path: PathArg, data: bytes) -> None:
    """Write ``data`` to ``path`` (overwriting it) through :func:`atomic_output`, fsynced."""
    with atomic_output(path, force=True, durable=True) as tmp:
        tmp.write_bytes(data)
