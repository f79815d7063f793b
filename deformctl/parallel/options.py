"""The scale-out options of a stage command (``--workers`` ... ``--resume``), checked once.

:class:`SweepOptions` is what the CLI builds from the five flags; it checks them against the output
(:meth:`SweepOptions.check`) and gives :func:`~deformctl.parallel.sweep.run_sweep` its keyword
arguments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from deformctl.errors import UsageError

DEFAULT_CONNECT_TIMEOUT_S = 10.0  #: time allowed to reach a Dask scheduler, s
DEFAULT_PARTITION_SIZE = 100  #: objects per part of a dataset directory


def parse_workers(value: int | str) -> int | Literal["auto"]:
    """``--workers``: ``auto`` or a whole number >= 1 (the one rule for the flag and the library).

    Raises:
        UsageError: anything else (``0``, ``-1``, ``abc``, ``1.5``).
    """
    if isinstance(value, str):
        text = value.strip()
        if text.lower() == "auto":
            return "auto"
        try:
            value = int(text)
        except ValueError:
            raise UsageError(
                f"--workers must be auto or a whole number >= 1, got {value!r}"
            ) from None
    if isinstance(value, bool) or not isinstance(value, int):
        raise UsageError(f"--workers must be auto or a whole number >= 1, got {value!r}")
    if value < 1:
        raise UsageError(f"--workers must be >= 1, got {value}")
    return value


@dataclass(frozen=True)
class SweepOptions:
    """The scale-out flags of a stage command, as given (None: not given).

    Attributes:
        workers: ``--workers N`` local processes, or ``"auto"`` (the default: measured,
            :mod:`deformctl.parallel.auto`); text is parsed by :func:`parse_workers`, which
            refuses anything else.
        scheduler: ``--scheduler tcp://HOST:PORT`` of a running Dask scheduler.
        connect_timeout_s: ``--connect-timeout S``.
        partition_size: ``--partition-size N`` objects per part.
        resume: ``--resume``.
    """

    workers: int | Literal["auto"] | None = None
    scheduler: str | None = None
    connect_timeout_s: float | None = None
    partition_size: int | None = None
    resume: bool = False

    def __post_init__(self) -> None:
        if self.workers is not None:
            object.__setattr__(self, "workers", parse_workers(self.workers))

    @property
    def workers_given(self) -> bool:
        """``--workers N`` was given (``auto``, the default, is not a choice made)."""
        return self.workers is not None and self.workers != "auto"

    def given(self) -> list[str]:
        """The flags given on the command line."""
        flags = [
            ("--workers", self.workers if self.workers_given else None),
            ("--scheduler", self.scheduler),
            ("--connect-timeout", self.connect_timeout_s),
            ("--partition-size", self.partition_size),
        ]
        out = [flag for flag, value in flags if value is not None]
        return out + (["--resume"] if self.resume else [])

    def check(self, output: str, *, file_workers: bool = False) -> bool:
        """Check the flags against the output; True when the output is a dataset directory.

        Args:
            output: the ``-o`` value.
            file_workers: the command also runs a single-file output on ``--workers`` local
                processes (:func:`map_in_order`), so that flag is allowed without a directory.

        Raises:
            UsageError: a sweep flag with a single-file output (``--workers`` too unless
                ``file_workers``), both ``--workers N`` and ``--scheduler``,
                ``--connect-timeout`` without ``--scheduler`` or <= 0, ``--partition-size`` < 1.
        """
        from deformctl.artifacts.dataset import is_dataset_output  # deferred: pyarrow

        dataset = is_dataset_output(output)
        needs_dir = [f for f in self.given() if not (file_workers and f == "--workers")]
        if not dataset and needs_dir:
            raise UsageError(
                f"{needs_dir[0]} needs a dataset directory output "
                f"(end -o with /, e.g. -o {output.rstrip('/') or 'out'}/)"
            )
        if self.workers_given and self.scheduler is not None:
            raise UsageError("give either --workers (local processes) or --scheduler, not both")
        if self.connect_timeout_s is not None:
            if self.scheduler is None:
                raise UsageError("--connect-timeout needs --scheduler")
            if not (math.isfinite(self.connect_timeout_s) and self.connect_timeout_s > 0):
                raise UsageError(f"--connect-timeout must be > 0 s, got {self.connect_timeout_s}")
        if self.partition_size is not None and self.partition_size < 1:
            raise UsageError(f"--partition-size must be >= 1, got {self.partition_size}")
        return dataset

    def run_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`run_sweep` for these flags."""
        kwargs: dict[str, Any] = {
            "workers": self.workers if self.workers_given else "auto",
            "scheduler": self.scheduler,
            "resume": self.resume,
        }
        if self.connect_timeout_s is not None:
            kwargs["connect_timeout_s"] = self.connect_timeout_s
        if self.partition_size is not None:
            kwargs["partition_size"] = self.partition_size
        return kwargs
