"""MCAP logs of squeezes and lift attempts: JSON messages with JSON Schemas, one sample per message.

Layout of a log written here (it opens in Foxglove):

* metadata record ``deformctl``: ``kind`` (``squeeze_log`` or ``lift_log``) and ``format_version``;
* metadata record ``provenance`` (see :class:`~deformctl.artifacts.provenance.Provenance`);
* one metadata record ``object`` per object: its catalog row, each value JSON-encoded;
* one channel per object, message encoding ``json``, schema encoding ``jsonschema`` with the
  schema files of ``schemas/``: ``/squeeze/<object_id>`` (``squeeze_sample``) in a squeeze log;
  ``/lift/<object_id>/attempt_sample`` (``lift_attempt_sample``) and
  ``/lift/<object_id>/attempt_result`` (``lift_attempt_result``) in a lift log. Logs of the first
  layout, every object on ``/squeeze`` or ``/lift/attempt_sample`` and ``/lift/attempt_result``,
  are still read; the readers go by each message's ``object_id``.

``log_time`` (ns since the Unix epoch) never decreases through a file. A squeeze or attempt
that carries its source's clock (``SqueezeSeries.start_time_ns``: a bag's header stamps or a
CSV's absolute times; ``TrialOutcome.start_time_ns``: a rig attempt's wall clock) is placed
there. The others (simulated ones) are laid end to end from a fixed epoch, :data:`LOG_EPOCH_NS`
(2000-01-01T00:00:00Z, or the writer's ``epoch_ns``), in write order with :data:`GAP_S` between
them, so the same inputs give the same bytes and a plot shows them one after another. The time
since the squeeze or attempt began, ``time_s``, is a message field and is what the readers
return.

Integrity: the writer enables the chunk CRCs, the data-section CRC and the summary CRC. Before the
mcap library parses anything, :func:`load_mcap` checks the closing magic, the footer and both
section CRCs, so a truncated file or any flipped byte is refused (exit 65) instead of decoding
into different numbers. Reading then goes through the mcap library's :class:`StreamReader`, which
checks every chunk CRC, and every message is validated against its JSON Schema.
:func:`read_squeeze_log` first tries a bulk reader that makes the same checks on all the samples
at once (its own scan of the records; about 1.7x faster) and falls back to that reference path
for any file it cannot vouch for, so what it returns and what it refuses are the reference
path's.

Modules: :mod:`~deformctl.artifacts.mcap.contents` (the layout's names, the integrity checks,
:class:`McapContents`), :mod:`~deformctl.artifacts.mcap.read` (the reference readers),
:mod:`~deformctl.artifacts.mcap.bulk` (the bulk squeeze-log reader) and
:mod:`~deformctl.artifacts.mcap.write` (the writers). Their public names are re-exported here,
each loaded on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from deformctl.lazy import lazy_face

# ruff: noqa: F401 - the imports below are the public names (deformctl.lazy.lazy_face)
if TYPE_CHECKING:  # for type checkers; at run time each loads on first use
    from deformctl.artifacts.mcap.contents import (
        FORMAT_VERSION,
        GAP_S,
        KIND_LIFT,
        KIND_SQUEEZE,
        LOG_EPOCH_NS,
        MCAP_KINDS,
        MCAP_MAGIC,
        McapContents,
        decode_objects,
        decode_provenance,
        lift_topic,
        load_mcap,
        squeeze_topic,
        topic_schema,
    )
    from deformctl.artifacts.mcap.read import (
        lift_attempts_from_contents,
        read_lift_log,
        read_squeeze_log,
        squeezes_from_contents,
    )
    from deformctl.artifacts.mcap.write import write_lift_log, write_squeeze_log

#: Importing this package imports none of its modules, so a command that only reads logs does
#: not load the writers (and the MCAP library's writer), nor one that writes them the readers.
__getattr__, __dir__ = lazy_face(globals())
