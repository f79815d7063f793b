"""A ROS 2 bag as ``ros2 bag record`` writes it: a folder of ``metadata.yaml`` and its files.

:func:`bag_parts` turns what ``measure bag`` is given into the MCAP files to read, in order:

* one ``.mcap`` file: itself;
* a rosbag2 folder: its ``metadata.yaml`` (``rosbag2_bagfile_information``) names the storage
  (``storage_identifier``), the files (``relative_file_paths``, in recording order, each
  relative to the folder) and the messages each topic holds (``topics_with_message_count``);
  the reader then checks that the files hold that many messages on each topic it reads
  (:func:`check_counts`), so a file left out or cut short is not read as a shorter recording;
* a SQLite bag (``storage_identifier: sqlite3``, a ``.db3`` file, or a file that starts with the
  SQLite header) is refused with one line naming a converter to MCAP (``rosbags-convert`` of the
  ``rosbags`` package, or ``ros2 bag convert``).

A folder without ``metadata.yaml``, or with one that is not the rosbag2 layout, is refused with
one line (exit 65); ``ros2 bag reindex`` rewrites a lost ``metadata.yaml``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from deformctl.errors import InputDataError, MissingInputError

#: The name of a rosbag2 folder's index.
METADATA = "metadata.yaml"
#: The first bytes of an SQLite database (a ``.db3`` bag).
SQLITE_MAGIC = b"SQLite format 3\x00"
#: What a SQLite bag is told to do.
CONVERT_HINT = (
    "convert it to MCAP first, e.g. `rosbags-convert --src BAG --dst OUT --dst-storage mcap` "
    "(pip package rosbags) or `ros2 bag convert`"
)


@dataclass(frozen=True)
class BagParts:
    """The MCAP files of one bag, in order, and the per-topic message counts its index states.

    Attributes:
        files: the ``.mcap`` files (one for a single file).
        message_counts: topic -> messages, from ``metadata.yaml`` (empty for a single file).
        metadata: the folder's ``metadata.yaml`` (None for a single file).
    """

    files: tuple[Path, ...]
    message_counts: Mapping[str, int] = field(default_factory=dict)
    metadata: Path | None = None


def _sqlite_refusal(path: Path, what: str) -> InputDataError:
    return InputDataError(f"{what} is a SQLite (.db3) ROS 2 bag: {CONVERT_HINT}", path=path)


def _is_sqlite(path: Path) -> bool:
    try:
        with path.open("rb") as fh:
            return fh.read(len(SQLITE_MAGIC)) == SQLITE_MAGIC
    except OSError:
        return False


def bag_parts(path: str | Path) -> BagParts:
    """The files to read for the bag ``path`` (a ``.mcap`` file or a rosbag2 folder).

    Raises:
        MissingInputError: ``path`` does not exist, or a file the index names is missing (66).
        InputDataError: a SQLite bag (with the converter to use), a folder without a readable
            ``metadata.yaml`` or with one of another layout, a storage other than MCAP, or a
            path that is neither a file nor a folder (65).
    """
    p = Path(path)
    if not p.exists():
        raise MissingInputError("no such bag file or folder", path=p)
    if p.is_dir():
        return _folder(p)
    if not p.is_file():  # /dev/zero, a FIFO: it exists, and it is no bag
        raise InputDataError("not a bag: not a regular file or a rosbag2 folder", path=p)
    if p.suffix == ".db3" or _is_sqlite(p):
        raise _sqlite_refusal(p, "the file")
    return BagParts((p,))


def _folder(folder: Path) -> BagParts:
    meta = folder / METADATA
    if not meta.is_file():
        db3 = sorted(folder.glob("*.db3"))
        if db3:
            raise _sqlite_refusal(folder, "the folder")
        raise InputDataError(
            f"not a rosbag2 folder: no {METADATA} (`ros2 bag reindex` rewrites it)", path=folder
        )
    info = _bag_information(meta)
    storage = info.get("storage_identifier")
    if storage == "sqlite3":
        raise _sqlite_refusal(folder, f"the folder ({METADATA}: storage_identifier sqlite3)")
    if storage != "mcap":
        raise InputDataError(
            f"{METADATA}: storage_identifier {storage!r}, expected 'mcap'", path=folder
        )
    relative = info.get("relative_file_paths")
    if (
        not isinstance(relative, list)
        or not relative
        or not all(isinstance(r, str) and r for r in relative)
    ):
        raise InputDataError(f"{METADATA}: relative_file_paths is not a list of files", path=meta)
    files: list[Path] = []
    for rel in relative:
        f = folder / rel
        if Path(rel).is_absolute() or ".." in Path(rel).parts:
            raise InputDataError(f"{METADATA}: file {rel!r} is outside the bag folder", path=meta)
        if f.suffix == ".db3":
            raise _sqlite_refusal(folder, "the folder")
        if f.suffix != ".mcap":
            raise InputDataError(
                f"{METADATA}: file {rel!r} is not an .mcap file (a compressed bag? "
                "`ros2 bag decompress` it first)",
                path=meta,
            )
        if not f.is_file():
            raise MissingInputError(
                f"the file {rel!r} that {METADATA} lists is missing", path=folder
            )
        files.append(f)
    return BagParts(tuple(files), _counts(info, meta), meta)


def _bag_information(meta: Path) -> dict[str, Any]:
    import yaml

    try:
        doc = yaml.safe_load(meta.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as err:
        first = " ".join(str(err).split())[:120]
        raise InputDataError(f"not readable as YAML ({first})", path=meta) from None
    except OSError as err:
        raise MissingInputError(f"cannot be read: {err.strerror or err}", path=meta) from None
    info = doc.get("rosbag2_bagfile_information") if isinstance(doc, dict) else None
    if not isinstance(info, dict):
        raise InputDataError("has no rosbag2_bagfile_information mapping", path=meta)
    return info


def _counts(info: Mapping[str, Any], meta: Path) -> dict[str, int]:
    entries = info.get("topics_with_message_count") or []
    if not isinstance(entries, list):
        raise InputDataError(f"{METADATA}: topics_with_message_count is not a list", path=meta)
    counts: dict[str, int] = {}
    for entry in entries:
        topic = entry.get("topic_metadata", {}) if isinstance(entry, dict) else None
        name = topic.get("name") if isinstance(topic, dict) else None
        count = entry.get("message_count") if isinstance(entry, dict) else None
        if not isinstance(name, str) or not isinstance(count, int) or isinstance(count, bool):
            raise InputDataError(
                f"{METADATA}: a topics_with_message_count entry lacks its name or count",
                path=meta,
            )
        counts[name] = counts.get(name, 0) + count
    return counts


def check_counts(parts: BagParts, read: Mapping[str, int], folder: Path) -> None:
    """Refuse a folder whose files hold another number of messages on a topic read than its
    ``metadata.yaml`` states (a file missing, cut short or from another recording).

    Raises:
        InputDataError: the first topic whose count differs (exit 65).
    """
    for topic, n in read.items():
        stated = parts.message_counts.get(topic)
        if stated is not None and stated != n:
            raise InputDataError(
                f"{METADATA} states {stated} messages on topic {topic!r}, its files hold {n}: "
                "a file cut short or from another recording?",
                path=folder,
            )
