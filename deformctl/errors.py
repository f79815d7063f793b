"""The exceptions deformctl raises on purpose.

Every error a user can cause (bad input data, a missing file, an existing output, an invalid
option combination) is a :class:`DeformctlError`. The CLI catches only this hierarchy and turns it
into one line on stderr, ``error: <file>: <what is wrong>``, and the class's exit code. Any other
exception is a bug and keeps its traceback.

Exit codes (documented in the README):

==== =========================================================
0    success
1    failure (e.g. a search that did not converge, output exists)
2    usage error (bad option values or combinations)
65   bad input data (EX_DATAERR): a file that does not match its schema
66   missing input file (EX_NOINPUT)
==== =========================================================
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from os import PathLike
from typing import Any

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_DATAERR = 65
EXIT_NOINPUT = 66


class DeformctlError(Exception):
    """Base class; ``str(err)`` is the one-line message, prefixed by the path when known."""

    exit_code: int = EXIT_FAILURE

    def __init__(self, message: str, *, path: str | PathLike[str] | None = None) -> None:
        self.message = " ".join(str(message).split())  # always one line
        self.path = None if path is None else str(path)
        super().__init__(self.message)

    def __str__(self) -> str:
        return f"{self.path}: {self.message}" if self.path else self.message

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle by attributes: an error raised in a worker process reaches the client whole
        (subclasses take other constructor arguments than ``args``)."""
        return _rebuild_error, (type(self), dict(self.__dict__))


def _rebuild_error(cls: type[DeformctlError], state: dict[str, Any]) -> DeformctlError:
    err = cls.__new__(cls)
    Exception.__init__(err, state.get("message", ""))
    err.__dict__.update(state)
    return err


class UsageError(DeformctlError):
    """An option value or combination that cannot work (exit 2)."""

    exit_code = EXIT_USAGE


class InputDataError(DeformctlError):
    """An input file or value that exists but is not valid data (exit 65)."""

    exit_code = EXIT_DATAERR


class SchemaError(InputDataError):
    """An artifact that does not match its schema; names the offending field when known."""

    def __init__(
        self,
        message: str,
        *,
        path: str | PathLike[str] | None = None,
        field: str | None = None,
    ) -> None:
        self.field = field
        super().__init__(f"field {field!r}: {message}" if field else message, path=path)


class MissingInputError(DeformctlError):
    """An input path that does not exist or cannot be opened (exit 66)."""

    exit_code = EXIT_NOINPUT


class OutputExistsError(DeformctlError):
    """An output that exists already; pass ``--force`` to overwrite it (exit 1)."""

    def __init__(self, path: str | PathLike[str]) -> None:
        super().__init__("exists already, not overwriting (use --force)", path=path)


class SimulationError(DeformctlError):
    """The simulator could not produce a valid result (e.g. non-finite state)."""


class SearchError(DeformctlError):
    """A lifting-force search that failed or did not converge (exit 1)."""


class RigError(DeformctlError):
    """An external rig command that crashed, timed out or answered garbage (exit 1)."""


@contextmanager
def error_context(path: str | PathLike[str]) -> Iterator[None]:
    """Name ``path`` in any :class:`DeformctlError` raised inside that names no file yet.

    For library calls that work on data already read (a join of two tables, a prediction), so
    the CLI's one line still reads ``error: <file>: <what is wrong>``.
    """
    try:
        yield
    except DeformctlError as err:
        if err.path is None:
            err.path = str(path)
        raise
