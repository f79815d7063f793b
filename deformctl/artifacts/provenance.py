"""Provenance: where an artifact came from, stored inside the artifact.

Every file deformctl writes records the tool version, the command line, the sha256 of each input
file, the random seed and the settings of the run. Parquet tables keep it as JSON in the schema
metadata key ``deformctl`` (under ``"provenance"``); MCAP logs keep it as a metadata record named
``provenance`` whose values are strings (nested values JSON-encoded).
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from deformctl import jsonsafe
from deformctl.artifacts.io import PathArg, display_name, is_stdio
from deformctl.errors import MissingInputError, SchemaError
from deformctl.version import version_string

TOOL = "deformctl"
STDIN_HASH = "stdin"  #: recorded instead of a hash for an input read from ``-``


def input_digest(path: PathArg) -> str:
    """What provenance records for an input: :func:`sha256_file`, or ``stdin`` for ``-``."""
    return STDIN_HASH if is_stdio(path) else sha256_file(path)


def sha256_file(path: PathArg) -> str:
    """Return the hex sha256 of a file's bytes (of a dataset directory: see below).

    A directory (a sweep dataset) hashes the sorted names and sha256 of its files, those of
    its subdirectories included (``_failures/part-00000.parquet``), hidden files left out.

    Raises:
        MissingInputError: the file cannot be read (exit 66).
    """
    if os.path.isdir(path):
        root = os.fspath(path)
        digest = hashlib.sha256()
        for dirpath, dirnames, filenames in os.walk(root):
            dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
            for name in sorted(f for f in filenames if not f.startswith(".")):
                full = os.path.join(dirpath, name)
                rel = os.path.relpath(full, root).replace(os.sep, "/")
                digest.update(f"{rel}\0{sha256_file(full)}\n".encode())
        return digest.hexdigest()
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
    except OSError as err:
        raise MissingInputError(f"cannot be read: {err.strerror or err}", path=path) from err
    return digest.hexdigest()


def _json_default(value: object) -> object:
    """Make numpy scalars, arrays and paths JSON-serialisable."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def to_json(value: object) -> str:
    """Canonical JSON (sorted keys, no whitespace) of settings-like values."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=_json_default)


@dataclass(frozen=True)
class Provenance:
    """Where an artifact came from.

    Attributes:
        tool_version: the deformctl version that wrote the file.
        command_line: the command as typed, ``argv`` with ``argv[0]`` reduced to its base name.
        inputs: input path (as given) → hex sha256 of its bytes (``"stdin"`` for ``-``).
        seed: the random seed of the run, or None when nothing random happened.
        settings: free-form, JSON-serialisable settings (e.g. simulator parameters).
        tool: the writing tool's name, ``"deformctl"``.
    """

    tool_version: str
    command_line: tuple[str, ...] = ()
    inputs: Mapping[str, str] = field(default_factory=dict)
    seed: int | None = None
    settings: Mapping[str, Any] = field(default_factory=dict)
    tool: str = TOOL

    @classmethod
    def from_invocation(
        cls,
        inputs: Iterable[PathArg] = (),
        *,
        seed: int | None = None,
        settings: Mapping[str, Any] | None = None,
        argv: Sequence[str] | None = None,
    ) -> Provenance:
        """Build the provenance of the running command.

        Args:
            inputs: the input files; each is hashed (``-`` is recorded as ``"stdin"``).
            seed: the run's random seed.
            settings: JSON-serialisable settings; normalised through JSON so a round trip
                through a file compares equal.
            argv: the command line; defaults to :data:`sys.argv`.

        Raises:
            MissingInputError: an input cannot be read.
        """
        args = list(sys.argv if argv is None else argv)
        if args:
            args[0] = os.path.basename(args[0]) or args[0]
        hashes = {
            display_name(p) if is_stdio(p) else os.fspath(p): (input_digest(p)) for p in inputs
        }
        norm = json.loads(to_json(dict(settings or {})))
        return cls(
            tool_version=version_string(),
            command_line=tuple(args),
            inputs=hashes,
            seed=None if seed is None else int(seed),
            settings=norm,
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable dict (the form stored in Parquet metadata)."""
        return {
            "tool": self.tool,
            "tool_version": self.tool_version,
            "command_line": list(self.command_line),
            "inputs": dict(self.inputs),
            "seed": self.seed,
            "settings": dict(self.settings),
        }

    @classmethod
    def from_dict(cls, data: object, *, path: PathArg | None = None) -> Provenance:
        """Rebuild from :meth:`to_dict` output; malformed data is a :class:`SchemaError`."""
        if not isinstance(data, dict):
            raise SchemaError("provenance is not an object", path=path, field="provenance")
        try:
            tool = data["tool"]
            version = data["tool_version"]
            cmd = data["command_line"]
            inputs = data["inputs"]
            seed = data["seed"]
            settings = data["settings"]
        except KeyError as err:
            raise SchemaError(
                f"provenance lacks {err.args[0]!r}", path=path, field="provenance"
            ) from None
        ok = (
            isinstance(tool, str)
            and isinstance(version, str)
            and isinstance(cmd, list)
            and all(isinstance(a, str) for a in cmd)
            and isinstance(inputs, dict)
            and all(isinstance(k, str) and isinstance(v, str) for k, v in inputs.items())
            and (seed is None or (isinstance(seed, int) and not isinstance(seed, bool)))
            and isinstance(settings, dict)
        )
        if not ok:
            raise SchemaError("provenance has a malformed value", path=path, field="provenance")
        return cls(
            tool_version=version,
            command_line=tuple(cmd),
            inputs=inputs,
            seed=seed,
            settings=settings,
            tool=tool,
        )

    def to_mcap_metadata(self) -> dict[str, str]:
        """The MCAP ``provenance`` metadata record: flat string values, nested ones as JSON."""
        return {
            "tool": self.tool,
            "tool_version": self.tool_version,
            "command_line": to_json(list(self.command_line)),
            "inputs": to_json(dict(self.inputs)),
            "seed": to_json(self.seed),
            "settings": to_json(dict(self.settings)),
        }

    @classmethod
    def from_mcap_metadata(
        cls, data: Mapping[str, str], *, path: PathArg | None = None
    ) -> Provenance:
        """Rebuild from :meth:`to_mcap_metadata` output; malformed data is a SchemaError."""
        try:
            decoded: dict[str, Any] = {
                "tool": data["tool"],
                "tool_version": data["tool_version"],
            }
            for key in ("command_line", "inputs", "seed", "settings"):
                decoded[key] = jsonsafe.loads(data[key], allow_nan=True)
        except KeyError as err:
            raise SchemaError(
                f"provenance lacks {err.args[0]!r}", path=path, field="provenance"
            ) from None
        except ValueError as err:
            raise SchemaError(
                f"provenance is not valid JSON ({err})", path=path, field="provenance"
            ) from None
        return cls.from_dict(decoded, path=path)
