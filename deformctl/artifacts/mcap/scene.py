"""A simulated run's scene as MCAP messages: ``/scene`` (Foxglove's SceneUpdate) and ``/palms``.

``/scene`` carries one ``foxglove.SceneUpdate`` per frame, JSON-encoded against the JSON Schema
Foxglove publishes (``schemas/foxglove/SceneUpdate.json``, embedded unchanged as the channel's
schema), so Foxglove's 3-D panel draws it: entity ``palms`` (two cubes, each palm's inner face on
its contact face), entity ``object`` (one sphere per surface particle; the particles on a palm's
face green while that contact sticks, red when it slipped since the previous frame, the others
grey) and, when the object starts on the table, entity ``table`` (a thin slab below z = 0). Every
entity is in frame ``world`` (z up, metres) and replaces its previous version (same ``id``); its
metadata names the object, the run (``squeeze`` or ``lift``), its index and the frame's
``time_s`` since the run began. Positions and sizes are rounded to 0.1 µm
(:data:`SCENE_DECIMALS`).

``/palms`` carries one ``deformctl.PalmContact`` message per frame (``schemas/
palm_contact.schema.json``): each palm's position, normal and tangential force, its sliding since
the previous frame and its stick/slip state (0/1), plottable in Foxglove's Plot panel
(``/palms.normal_left_n``...).

Both topics are shared by every object of a log: the runs lie one after another in log time, so
the one layout (docs/foxglove/deformctl-layout.json) shows whichever is playing.
"""

from __future__ import annotations

import functools
import json
from importlib.resources import files
from typing import Any, NamedTuple

import numpy as np

from deformctl.artifacts.mcap.contents import PALMS_TOPIC, SCENE_TOPIC, McapContents
from deformctl.errors import SchemaError
from deformctl.scene import NO_PALM, SceneFrames
from deformctl.units import NS_PER_S

#: The schema name Foxglove recognises (its published JSON Schema's title).
SCENE_SCHEMA_NAME = "foxglove.SceneUpdate"
FRAME_ID = "world"
#: Colours (r, g, b, a): a free surface particle, a stuck contact, a slipping one, palms, table.
GREY = (0.72, 0.74, 0.78, 1.0)
STUCK = (0.16, 0.68, 0.29, 1.0)
SLIPPING = (0.89, 0.16, 0.14, 1.0)
PALM = (0.25, 0.42, 0.75, 0.55)
TABLE = (0.45, 0.45, 0.45, 0.6)
TABLE_THICKNESS_M = 0.004


class SceneMessage(NamedTuple):
    """One decoded ``/scene`` message: its log time (ns) and the ``foxglove.SceneUpdate``."""

    log_time_ns: int
    update: dict[str, Any]


def foxglove_schema_bytes() -> bytes:
    """The published JSON Schema of ``foxglove.SceneUpdate``, as shipped (see its README)."""
    return (files("deformctl.schemas") / "foxglove" / "SceneUpdate.json").read_bytes()


def foxglove_schema() -> dict[str, Any]:
    """:func:`foxglove_schema_bytes`, parsed."""
    schema: dict[str, Any] = json.loads(foxglove_schema_bytes())
    return schema


def _color(c: tuple[float, float, float, float]) -> str:
    return '{"r":%r,"g":%r,"b":%r,"a":%r}' % c  # noqa: UP031 - a template filled per primitive


_IDENTITY = '{"x":0.0,"y":0.0,"z":0.0,"w":1.0}'


#: Decimals of the drawn positions and sizes, m: 0.1 µm, ten times finer than the smallest slip
#: tolerance of a preset (1 µm), and a quarter of the log's size at full precision (the paper's
#: four objects' scene: 0.94 MB against 3.57 MB compressed). ``/palms`` keeps every digit.
SCENE_DECIMALS = 7


def _vector(x: float, y: float, z: float) -> str:
    return '{"x":%.7f,"y":%.7f,"z":%.7f}' % (x, y, z)  # noqa: UP031 - SCENE_DECIMALS


def _pose(x: float, y: float, z: float) -> str:
    return '{"position":%s,"orientation":%s}' % (_vector(x, y, z), _IDENTITY)  # noqa: UP031


def _entity(stamp: str, eid: str, meta: str, cubes: str = "", spheres: str = "") -> str:
    return (
        '{"timestamp":%s,"frame_id":"%s","id":"%s","lifetime":{"sec":0,"nsec":0},'  # noqa: UP031
        '"frame_locked":false,"metadata":%s,"arrows":[],"cubes":[%s],"spheres":[%s],'
        '"cylinders":[],"lines":[],"triangles":[],"texts":[],"models":[]}'
        % (stamp, FRAME_ID, eid, meta, cubes, spheres)
    )


def _box(centre: np.ndarray, size: tuple[float, float, float], color: str) -> str:
    return '{"pose":%s,"size":%s,"color":%s}' % (  # noqa: UP031
        _pose(*(float(v) for v in centre)),
        _vector(*size),
        color,
    )


@functools.lru_cache(maxsize=16)
def _spheres_writer(diameter_m: float) -> Any:
    """The compiled writer of a frame's spheres of one diameter. Colour index of a sphere: 0 grey
    (touching no palm), else 1 + 2 palm + (1 if that palm slipped)."""
    from deformctl.artifacts.mcap._scene_text import SpheresWriter  # numba: only with a scene

    d = diameter_m
    colours = [_color(GREY), _color(STUCK), _color(SLIPPING), _color(STUCK), _color(SLIPPING)]
    return SpheresWriter(_IDENTITY, _vector(d, d, d), colours)


#: Where a frame's own values go in the per-run template of its ``/scene`` message.
_STAMP, _META, _CUBES, _SPHERES = "\x00", "\x01", "\x02", "\x03"
#: The ``/palms`` fields after the run's head, in order (the last two integers).
_PALM_FIELDS = (
    "time_s",
    "palm_left_x_m",
    "palm_right_x_m",
    "palm_z_m",
    "normal_left_n",
    "normal_right_n",
    "tangential_left_n",
    "tangential_right_n",
    "slip_left_m",
    "slip_right_m",
)


def _template(text: str) -> str:
    """``text`` as a ``%`` template: its markers ``%s`` (stamp, meta, cubes, in that order)."""
    text = text.replace("%", "%%")
    for marker in (_STAMP, _META, _CUBES):
        text = text.replace(marker, "%s")
    return text


def _scene_templates(table: str) -> tuple[str, str]:
    """The templates of a frame's ``/scene`` message before and after its spheres: filled with
    (stamp, meta, cubes, stamp, meta) and (stamp, meta) or ().  Control characters never occur
    in JSON text, so they mark the frame's values."""
    text = '{"deletions":[],"entities":[%s,%s' % (  # noqa: UP031
        _entity(_STAMP, "palms", _META, cubes=_CUBES),
        _entity(_STAMP, "object", _META, spheres=_SPHERES),
    )
    if table:
        text += "," + _entity(_STAMP, "table", _META, cubes=table)
    before, after = text.split(_SPHERES)
    return _template(before), _template(after + "]}")


def _palm_texts(scene: SceneFrames, palm_head: str) -> list[bytes]:
    """Each frame's ``/palms`` message: ``palm_head`` and the frame's contact state, the same
    text as ``json.dumps`` (a finite float's ``repr`` is its JSON form)."""
    columns = np.column_stack(
        [
            scene.time_s,
            scene.palm_x_m,
            scene.palm_z_m,
            scene.normal_force_n,
            scene.tangential_force_n,
            scene.slip_m,
        ]
    )
    if not np.isfinite(columns).all():  # json.dumps's refusal, as before
        json.dumps(float(columns[~np.isfinite(columns)][0]), allow_nan=False)
    fields = ",".join(f'"{key}":%r' for key in _PALM_FIELDS)
    template = f'{palm_head},{fields},"slipping_left":%d,"slipping_right":%d}}'
    flags = scene.slipping.astype(np.int64).tolist()
    return [
        (template % (*row, *flag)).encode()
        for row, flag in zip(columns.tolist(), flags, strict=True)
    ]


def scene_messages(
    scene: SceneFrames,
    *,
    object_id: str,
    run: str,
    index: int,
    start_ns: int,
    t0_s: float,
) -> list[tuple[int, str, bytes]]:
    """Every ``/scene`` and ``/palms`` message of one run, in log-time order.

    The run's fixed text (the entities' layout, the metadata's head, the table, the spheres'
    orientation, size and colours) is made once; each frame fills in its time stamp, palm
    positions and particles, the particles of all frames in one compiled pass.

    Args:
        scene: the run's frames.
        object_id, run, index: the object, ``squeeze`` or ``lift``, the squeeze / attempt index.
        start_ns: the log time of the run's first sample, ns.
        t0_s: the time of that sample on the scene's time base, s: a frame at ``t`` is logged at
            ``start_ns + round((t - t0_s) 1e9)``, the samples' own rule.

    Returns:
        ``(log_time_ns, topic, JSON bytes)`` per message, two per frame.
    """
    meta_head = json.dumps(
        [
            {"key": "object_id", "value": object_id},
            {"key": "run", "value": run},
            {"key": "index", "value": str(int(index))},
        ],
        separators=(",", ":"),
    )[:-1]
    spheres = _spheres_writer(scene.particle_diameter_m)
    side = scene.contact_side.astype(np.int64)
    on_palm = side != NO_PALM
    table = ""
    if scene.table:
        first = scene.positions_m[0]
        centre = np.array([first[:, 0].mean(), first[:, 1].mean(), -0.5 * TABLE_THICKNESS_M])
        size = (
            3.0 * float(np.ptp(first[:, 0]) or 0.1),
            2.0 * float(np.ptp(first[:, 1]) or 0.1),
            TABLE_THICKNESS_M,
        )
        table = _box(centre, size, _color(TABLE))
    before, after = _scene_templates(table)
    head = {"object_id": object_id, "run": run, "index": int(index)}
    palm_head = json.dumps(head, separators=(",", ":"))[:-1]
    times = start_ns + np.rint((scene.time_s - t0_s) * NS_PER_S).astype(np.int64)
    palm_of = np.maximum(side, 0)
    colour = np.where(on_palm, 1 + 2 * palm_of + scene.slipping[:, palm_of].astype(np.int64), 0)
    # the drawn palms (SceneFrames.palm_centres_m of every frame): outside the object, each inner
    # face on its contact face, at the palms' height
    half = 0.5 * scene.palm_size_m[0]
    y, z0 = scene.palm_centre_m
    left = (scene.palm_x_m[:, 0] - half).tolist()
    right = (scene.palm_x_m[:, 1] + half).tolist()
    heights = (z0 + scene.palm_z_m).tolist()
    palm_size = _vector(*scene.palm_size_m)
    cube = '{"pose":{"position":{"x":%.7f,"y":%.7f,"z":%.7f},"orientation":' + _IDENTITY
    cube += '},"size":' + palm_size + ',"color":' + _color(PALM) + "}"
    heads, tails = [], []
    log_ns = times.tolist()
    for k, t_s in enumerate(scene.time_s.tolist()):
        stamp = '{"sec":%d,"nsec":%d}' % divmod(log_ns[k], NS_PER_S)  # noqa: UP031
        meta = '%s,{"key":"time_s","value":"%r"}]' % (meta_head, t_s)  # noqa: UP031
        cubes = f"{cube % (left[k], y, heights[k])},{cube % (right[k], y, heights[k])}"
        heads.append((before % (stamp, meta, cubes, stamp, meta)).encode())
        tails.append((after % ((stamp, meta) if table else ())).encode())
    updates = spheres.messages(scene.positions_m, colour, heads, tails)
    palms = _palm_texts(scene, palm_head)
    out: list[tuple[int, str, bytes]] = []
    for k, t in enumerate(log_ns):
        out.append((t, SCENE_TOPIC, updates[k]))
        out.append((t, PALMS_TOPIC, palms[k]))
    return out


def scene_frames_of(contents: McapContents, *, validate: bool = True) -> list[SceneMessage]:
    """The ``/scene`` messages of a verified log, decoded, in file order.

    Args:
        contents: the log (:func:`~deformctl.artifacts.mcap.load_mcap`).
        validate: check each message against the published ``foxglove.SceneUpdate`` JSON Schema
            (and the channel's embedded schema against the shipped one).

    Raises:
        SchemaError: a scene channel whose schema is not Foxglove's, or a message that does not
            match it (exit 65).
    """
    channels = [c for c in contents.channels.values() if c.topic == SCENE_TOPIC]
    if not channels:
        return []
    published = foxglove_schema_bytes()
    for channel in channels:
        schema = contents.schemas.get(channel.schema_id)
        if (
            schema is None
            or schema.name != SCENE_SCHEMA_NAME
            or schema.encoding != "jsonschema"
            or channel.message_encoding != "json"
            or json.loads(schema.data) != json.loads(published)
        ):
            raise SchemaError(
                f"channel {SCENE_TOPIC}: not Foxglove's published {SCENE_SCHEMA_NAME} JSON "
                "Schema with JSON messages",
                path=contents.path,
                field=SCENE_TOPIC,
            )
    ids = {c.id for c in channels}
    out = []
    for msg in contents.messages:
        if msg.channel_id not in ids:
            continue
        try:
            update = json.loads(msg.data)
        except ValueError as err:
            raise SchemaError(
                f"a {SCENE_TOPIC} message is not JSON ({err})",
                path=contents.path,
                field=SCENE_TOPIC,
            ) from None
        if validate:
            check_scene_update(update, path=contents.path)
        out.append(SceneMessage(msg.log_time, update))
    return out


@functools.cache
def _scene_validator() -> Any:
    import jsonschema  # only a log's scene check needs it

    schema = foxglove_schema()
    return jsonschema.validators.validator_for(schema)(schema)


def check_scene_update(update: Any, *, path: str) -> None:
    """Check one decoded message against Foxglove's published ``foxglove.SceneUpdate`` schema
    (about 50 ms for a frame of 200 particles).

    Raises:
        SchemaError: it does not match, naming where (exit 65).
    """
    import jsonschema

    error = jsonschema.exceptions.best_match(_scene_validator().iter_errors(update))
    if error is not None:
        where = "/".join(str(p) for p in error.absolute_path) or "(root)"
        raise SchemaError(
            f"a {SCENE_TOPIC} message does not match {SCENE_SCHEMA_NAME} at {where}: "
            f"{error.message[:160]}",
            path=path,
            field=SCENE_TOPIC,
        )
