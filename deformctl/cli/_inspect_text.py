"""What text-mode ``deformctl inspect`` prints for an artifact's summary (its ``describe``
record): the file, schema, counts, fields with units, provenance, a model's metadata, per-object
lines, and a dataset directory's summary."""

from __future__ import annotations

import datetime
import json
from typing import Any

from deformctl.blas import blas_summary


def _utc(ns: int) -> str:
    """A log time (ns since the Unix epoch) in ISO 8601 UTC, to the nanosecond."""
    seconds, frac = divmod(ns, 1_000_000_000)
    stamp = datetime.datetime.fromtimestamp(seconds, datetime.UTC)
    return f"{stamp:%Y-%m-%dT%H:%M:%S}.{frac:09d}Z"


def _unit(unit: object) -> str:
    return str(unit) if unit else "-"


def _model_lines(info: dict[str, Any]) -> list[str]:
    """The model-file part of :func:`render_text`."""
    lines = [f"tool version: {info['tool_version']}", f"seed: {info['seed']}"]
    lines.append(f"features: {', '.join(info['features'])} -> {info['target']}")
    lines.append("training range:")
    for feat, rng in info["training_range"].items():
        lines.append(f"  {feat:<24} {rng[0]:.6g} .. {rng[1]:.6g}" if rng else f"  {feat}: -")
    hp = info.get("hyperparameters") or {}
    if hp:
        lines.append(f"hyperparameters: {json.dumps(hp, sort_keys=True)}")
    cal = f"{info['n_calibration']} calibration / " if info.get("n_calibration") else ""
    lines.append(
        f"form: {info.get('form', 'paper')}; split: {info['n_train']} train / {cal}"
        f"{info['n_test']} test"
    )
    if info.get("blas") is not None:  # older model files did not record it
        lines.append(f"BLAS of the fit: {blas_summary(info['blas'])}")
    for key, entry in info["metrics"].items():
        for split, m in entry.items():
            lines.append(
                f"  {key:<17} {split:<5} max rel err {_pct(m.get('max_rel_error'))}, "
                f"median {_pct(m.get('median_rel_error'))}, MAE {_num(m.get('mae_n'), '.3f')} N, "
                f"R2 {_num(m.get('r2'), '.4f')}"
            )
    for p, c in (info.get("conformal") or {}).items():
        lines.append(
            f"upper bound P = {p}: margin {_pct(c.get('margin'))}, on the test rows coverage "
            f"{_num(c.get('coverage'), '.3f')}, mean margin {_pct(c.get('mean_margin'))}"
        )
    adapted = info.get("adapted")
    if adapted:  # a model corrected by `adapt` with rig lifts
        rows = adapted.get("rows") or []
        alpha = adapted.get("alpha")
        lines.append(
            f"adapted: from {adapted.get('base_model')} with {len(rows)} rig rows of "
            f"{adapted.get('index')} (ridge alpha {'inf' if alpha is None else f'{alpha:.3g}'}, "
            f"correction {adapted.get('coefficients')}); bound: {adapted.get('bound_rule')}"
        )
        lines.extend(
            f"  {r['object_id']}: L_f {r['lift_force_n']:.4g} N, predicted "
            f"{r['predicted_before_n']:.4g} N before, {r['predicted_after_n']:.4g} N after"
            for r in rows
        )
    if info.get("form") == "grip":
        from deformctl.grip.laws import law_summary_lines

        lines += law_summary_lines(info.get("laws"))
    if info.get("notes"):
        lines.append("notes: " + ", ".join(f"{k}={v}" for k, v in sorted(info["notes"].items())))
    return lines


def _pct(value: object) -> str:
    return f"{100.0 * value:.2f} %" if isinstance(value, int | float) else "-"


def _num(value: object, fmt: str, missing: str = "-") -> str:
    return format(value, fmt) if isinstance(value, int | float) else missing


def _per_object_lines(info: dict[str, Any]) -> list[str]:
    """The data part of :func:`render_text`: a squeeze log's or a coefficients table's objects."""
    lines = []
    for o in info.get("squeeze_summary") or []:
        rupt = "; ".join(
            f"rupture in squeeze #{r['squeeze_index']} at {r['time_s']:.3g} s, {r['force_n']:.3g} N"
            for r in o["ruptures"]
        )
        lines.append(
            f"  {o['object_id']}: {o['squeezes']} squeeze(s), peak force "
            f"{_num(o['peak_force_n'], '.4g')} N, peak compression "
            f"{_num(o['peak_compression_m'], '.4g')} m, force {_num(o['force_rate_hz'], '.4g')} "
            f"Hz, position {_num(o['position_rate_hz'], '.4g')} Hz, phase {o['phase']}"
            + (f"; {rupt}" if rupt else "")
            + (f"; columns {o['columns']}" if o.get("columns") else "")
            + (
                f"; recording flags {','.join(o['recording_flags'])}"
                if o.get("recording_flags")
                else ""
            )
        )
    for c in info.get("coefficients") or []:
        lines.append(
            f"  {c['object_id']}: D {_num(c['deformability_n_per_cm'], '.4g')} N/cm, "
            f"λ {_num(c['damping_ns_per_cm'], '.4g', 'NaN')} N·s/cm, R² {_num(c['r2'], '.4f')}, "
            f"quality {c['quality'] if c['quality'] is not None else 'not recorded (v1 table)'}"
        )
    lines.extend(_start_lines(info.get("starts") or []))
    return (["per object:", *lines]) if lines else []


def _start_lines(starts: list[dict[str, Any]]) -> list[str]:
    """A seeded lift log's objects: the prediction, its bound, what the search found and the
    attempts it saved against a search from F_w (replayed against the L_f found)."""
    lines = []
    for s in starts:
        bound = (
            f"bound {_num(s.get('lift_force_upper_n'), '.4g')} N (P = {s['coverage']:g})"
            if s.get("coverage") is not None
            else "no bound"
        )
        outcome = "converged" if s.get("converged") else "NOT converged"
        saved = s.get("attempts_saved")
        lines.append(
            f"  {s['object_id']}: predicted L_f {_num(s.get('predicted_lift_force_n'), '.4g')} N, "
            f"{bound}, found L_f {_num(s.get('lift_force_n'), '.4g')} N, "
            f"{s.get('attempts')} attempts ({outcome}"
            + ("" if s.get("in_training_range") else ", outside the range: from F_w")
            + f"), from F_w {_num(s.get('attempts_from_f_w'), 'd')}, saved "
            + (f"{saved:d}" if isinstance(saved, int) else "-")
        )
    return lines


def render_text(info: dict[str, Any]) -> str:
    """The human-readable form of :func:`deformctl.artifacts.describe` output."""
    lines = [f"file: {info['path']}", f"format: {info['format']}", f"kind: {info['kind']}"]
    schema = info.get("schema")
    if schema:
        lines.append(f"schema: {schema['name']} v{schema['version']}")
    if "rows" in info:
        lines.append(f"rows: {info['rows']}")
        lines.append("columns:")
        for c in info["columns"]:
            req = "required" if c["required"] else "optional"
            lines.append(f"  {c['name']:<30} {c['dtype']:<8} {_unit(c['unit']):<8} {req}")
    if "messages" in info:
        lines.append(f"messages: {info['messages']}")
        rng = info.get("time_range")
        if rng:
            lines.append(
                f"time range: {_utc(rng['start_ns'])} .. {_utc(rng['end_ns'])} "
                f"({rng['duration_s']:.3f} s)"
            )
        for key in ("squeezes", "attempts", "lifted"):
            if key in info:
                lines.append(f"{key}: {info[key]}")
        lines.append("channels:")
        fields: dict[str, list[dict[str, str]]] = {}
        for ch in info["channels"]:
            lines.append(f"  {ch['topic']}: {ch['messages']} messages, schema {ch['schema']}")
            fields.setdefault(ch["schema"], ch.get("fields", []))
        for schema, schema_fields in fields.items():
            if schema_fields:
                lines.append(f"fields of {schema}:")
            for f in schema_fields:
                lines.append(f"  {f['name']:<20} {f['type']:<12} {_unit(f['unit'])}")
    if info["kind"] == "model":
        lines.extend(_model_lines(info))
    lines.extend(_per_object_lines(info))
    objects = info.get("objects") or []
    if objects:
        ids = ", ".join(str(o.get("object_id")) for o in objects)
        lines.append(f"objects ({len(objects)}): {ids}")
    prov = info.get("provenance")
    if prov:
        lines.append("provenance:")
        lines.append(f"  tool: {prov['tool']} {prov['tool_version']}")
        lines.append(f"  command: {' '.join(prov['command_line'])}")
        lines.append(f"  seed: {prov['seed']}")
        for p, digest in prov["inputs"].items():
            lines.append(f"  input: {p} sha256:{digest}")
        if prov["settings"]:
            lines.append(f"  settings: {json.dumps(prov['settings'], sort_keys=True)}")
    else:
        lines.append("provenance: none")
    return "\n".join(lines)


def render_dataset(info: dict[str, Any]) -> str:
    """Plain-text summary of a dataset directory (see
    :func:`deformctl.artifacts.dataset.describe_dataset`)."""
    state = "complete" if info["complete"] else "INCOMPLETE (rerun with --resume)"
    lines = [
        f"{info['path']}: {info['kind']} dataset (written by {info['command']})",
        f"  parts: {info['parts']} of {info['parts_expected']}, {state}",
        f"  objects: {info['objects']}, rows: {info['rows']}, failed: {info['failed']}",
        f"  logs: {info['logs']} _logs/part-*.mcap",
        "  columns: "
        + ", ".join(
            f"{c['name']} ({c['unit']})" if c["unit"] else c["name"] for c in info["columns"]
        ),
    ]
    if info.get("seed") is not None:
        lines.append(f"  seed: {info['seed']}")
    return "\n".join(lines)
