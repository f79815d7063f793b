"""Seeded synthetic squeeze recordings of every shape real recordings take, with known truth.

Real exports (testing machines, force-controlled grippers, elastomer rigs; see the docs'
"Synthetic recordings" section) break a tool in two ways: by their **shape** (what the force and
the compression do) and by their **text** (how the file is written). :func:`draw` picks both from
one seeded generator and returns a :class:`Case`: the CSV bytes, the options a user would pass
(an encoding the error line names, a unit a header leaves out) and the truth:

Shapes (:data:`SHAPES`), each a function of the generator:

* ``kv_ramp_hold``: Kelvin–Voigt, position ramp, hold, release (D and λ identified);
* ``hc_ramp_hold``: Hunt–Crossley n in 1.2–2.5, same protocol (D: the law's secant at the
  operating force the row states);
* ``stiffening``: Hunt–Crossley n in 2.5–5, one loading at one speed (silicone phantoms; λ not
  identified);
* ``latency``: ``kv_ramp_hold`` with the force 0.03–0.2 s behind the position;
* ``logging_gap``: ``kv_ramp_hold`` with 1–6 s of samples missing in a long hold;
* ``fruit_collapse``: force-controlled squeeze of a Kelvin–Voigt fruit that collapses by 50–92 %
  within 0.1–0.4 s and is backed off (D: the fruit's before the break);
* ``slip``: force-controlled squeeze that slips (the force falls 5–30 % while the jaws jump
  on) and climbs again before its peak (a falling stretch; D not defined);
* ``buckling``: a printed structure's load–unload cycle: rise, plateau, dip, rise (D not
  defined);
* ``relaxation``: a standard linear solid pressed and held: the force jumps, then decays while
  positive (D not defined);
* ``degenerate``: a handful of rows, or a force that never changes (a clear error is right).

Text (:func:`export_bytes`): line ends ``\\n`` / ``\\r\\n`` / ``\\r``, a blank first line, a
metadata preamble (with, sometimes, a cell over 128 KiB), one header row with units, a
Bluehill-style pair of header rows with the force in kN to 4 decimals and quoted cells, a GBK
Chinese header (``--encoding gbk``), a gripper log with an unnamed index column, Unix time and
``Pos`` (mm, grows while closing) next to a commanded force and a text column, ``;`` with a
decimal comma, the compressive force negative.

:func:`run_case` runs one case through :func:`deformctl.measure.stage.read_recording`, the
squeeze-log writer, :func:`deformctl.characterize.stage.read_and_characterize` and the coefficients
writer, and sorts the outcome: ``row`` (a table was written), ``refused`` (one clear error of the
tool's own kind) or ``internal`` (any other exception: a defect). :func:`check` runs :func:`draw`
``draws`` times; ``python -m deformctl.testing.shapes check --draws 2000 --seed 0`` prints the
counts and the confidently wrong rows (quality ``ok`` with D off by more than :data:`D_TOL` or,
where the recording identifies it, λ off by more than :data:`LAMBDA_TOL`).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import traceback
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from deformctl.series import FloatArray
from deformctl.testing.exports import Samples, draw_layout, export_bytes

#: A row with quality ``ok`` whose D is off by more than this (relative) is confidently wrong.
D_TOL = 0.05
#: ... or whose λ is, where the recording identifies λ.
LAMBDA_TOL = 0.20
N_PER_CM = 100.0


@dataclass(frozen=True)
class Truth:
    """What the recording's maker knows.

    Attributes:
        shape: the shape's name (:data:`SHAPES`).
        model: the law that made the force (``kv``, ``hc``, ``sls``) or ``""`` for none.
        params: its parameters, SI (:data:`deformctl.characterize.laws.PARAMETERS`).
        d_defined: D is defined (the law's secant at the stated force); False for shapes whose
            loading has no single stiffness (slip, buckling, relaxation).
        lambda_identified: the recording identifies λ (a hold or two speeds, Kelvin–Voigt).
    """

    shape: str
    model: str = ""
    params: Mapping[str, float] = field(default_factory=dict)
    d_defined: bool = True
    lambda_identified: bool = False

    def deformability_n_per_cm(self, operating_force_n: float) -> float:
        """The true D at a force: the law's secant from first contact to it, N/cm (NaN when D
        is not defined)."""
        if not self.d_defined or not self.model:
            return math.nan
        from deformctl.characterize.laws import secant_stiffness

        return float(secant_stiffness(self.model, self.params, operating_force_n)) / N_PER_CM

    @property
    def damping_ns_per_cm(self) -> float:
        """The true λ, N·s/cm (NaN unless Kelvin–Voigt and identified)."""
        if self.model != "kv" or not self.lambda_identified:
            return math.nan
        return float(self.params["damping_ns_per_m"]) / N_PER_CM


@dataclass(frozen=True)
class Case:
    """One draw: the export's bytes, what a user passes with it, and the truth.

    Attributes:
        name: ``<seed>-<index>-<shape>-<layout>``, for messages.
        data: the CSV file's bytes.
        options: keyword arguments of :class:`deformctl.measure.csv.options.CsvOptions` (and
            ``encoding`` for its dialect) that a user would pass (a unit the header leaves out,
            the encoding the error line names).
        truth: the recording's truth.
        layout: how the text was written (line end, preamble, header style, ...).
    """

    name: str
    data: bytes
    options: Mapping[str, Any]
    truth: Truth
    layout: Mapping[str, Any]


# ---------------------------------------------------------------------------- shapes


def _u(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(rng.uniform(lo, hi))


def _rate(rng: np.random.Generator) -> float:
    return float(rng.choice([50.0, 77.0, 100.0, 200.0, 500.0]))


def _from_series(s: Any) -> Samples:
    return Samples(np.asarray(s.time_s), np.asarray(s.force_n), np.asarray(s.compression_m))


def _kv_params(rng: np.random.Generator) -> dict[str, float]:
    k = _u(rng, 200.0, 5000.0)
    return {"stiffness_n_per_m": k, "damping_ns_per_m": k * _u(rng, 0.03, 0.5)}


def _law_squeeze(
    rng: np.random.Generator, model: str, params: Mapping[str, float], **kw: Any
) -> Samples:
    from deformctl.testing.synthetic import synthetic_law_squeeze

    opts: dict[str, Any] = {
        "peak_compression_m": _u(rng, 0.002, 0.015),
        "load_s": _u(rng, 0.5, 3.0),
        "hold_s": _u(rng, 0.8, 2.0),
        "release_s": _u(rng, 1.0, 3.0),
        "rate_hz": _rate(rng),
        "lag_s": 0.0,
        "force_noise_rel": _u(rng, 0.001, 0.01),
        "seed": int(rng.integers(2**31)),
    }
    opts.update(kw)
    return _from_series(synthetic_law_squeeze(model, params, **opts))


def shape_kv_ramp_hold(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """Kelvin–Voigt ramp, hold and release: D and λ identified."""
    p = _kv_params(rng)
    return _law_squeeze(rng, "kv", p), Truth("kv_ramp_hold", "kv", p, lambda_identified=True)


def shape_hc_ramp_hold(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """Hunt–Crossley (n 1.2–2.5) ramp, hold and release."""
    n = _u(rng, 1.2, 2.5)
    d_ref = 0.01
    k = _u(rng, 2.0, 30.0) / d_ref**n  # 2–30 N at 1 cm
    p = {
        "stiffness_n_per_m_pow_n": k,
        "exponent": n,
        "damping_ns_per_m_pow_n_plus_1": k * _u(rng, 0.05, 0.5) / 0.01,
    }
    return _law_squeeze(rng, "hc", p), Truth("hc_ramp_hold", "hc", p)


def shape_stiffening(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """Hunt–Crossley n 2.5–5, one loading at one speed (λ not identified)."""
    n = _u(rng, 2.5, 5.0)
    peak = _u(rng, 0.005, 0.02)
    k = _u(rng, 5.0, 100.0) / peak**n  # 5–100 N at the peak
    p = {"stiffness_n_per_m_pow_n": k, "exponent": n, "damping_ns_per_m_pow_n_plus_1": 0.0}
    s = _law_squeeze(
        rng, "hc", p, peak_compression_m=peak, load_s=_u(rng, 20.0, 120.0), hold_s=0.0,
        release_s=0.0, rest_s=0.0, rate_hz=float(rng.choice([10.0, 20.0, 50.0])),
    )  # fmt: skip
    return s, Truth("stiffening", "hc", p)


def shape_latency(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """Kelvin–Voigt ramp-hold with the force behind the position by 0.03–0.2 s."""
    p = _kv_params(rng)
    s = _law_squeeze(rng, "kv", p, lag_s=_u(rng, 0.03, 0.2))
    return s, Truth("latency", "kv", p, lambda_identified=True)


def shape_logging_gap(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """Kelvin–Voigt ramp-hold with 1–6 s of samples missing from a long hold."""
    p = _kv_params(rng)
    gap = _u(rng, 1.0, 6.0)
    s = _law_squeeze(rng, "kv", p, hold_s=gap + 2.0)
    load_s = float(s.t[int(np.argmax(s.d >= 0.98 * float(np.max(s.d))))])  # the hold starts
    keep = ~((s.t > load_s + 0.5) & (s.t < load_s + 0.5 + gap))
    return Samples(s.t[keep], s.f[keep], s.d[keep]), Truth(
        "logging_gap", "kv", p, lambda_identified=True
    )


def shape_fruit_collapse(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """A force-controlled squeeze to collapse (50–92 % within 0.1–0.4 s), then back-off."""
    from deformctl.testing.synthetic import synthetic_rupture_backoff

    p = _kv_params(rng)
    s = synthetic_rupture_backoff(
        stiffness_n_per_m=p["stiffness_n_per_m"], damping_ns_per_m=p["damping_ns_per_m"],
        rupture_force_n=_u(rng, 1.2, 28.0), force_rate_n_per_s=_u(rng, 1.0, 10.0),
        collapse_frac=_u(rng, 0.5, 0.92), collapse_s=_u(rng, 0.1, 0.4),
        backoff_s=_u(rng, 0.3, 1.5), rate_hz=float(rng.choice([77.0, 100.0, 200.0])),
        force_noise_n=_u(rng, 0.005, 0.05), seed=int(rng.integers(2**31)),
    )  # fmt: skip
    # the jaws keep closing through the collapse (the crushed fruit gives way)
    out = _from_series(s)
    peak = int(np.argmax(out.f))
    extra = np.zeros_like(out.d)
    extra[peak:] = np.minimum(out.t[peak:] - out.t[peak], 0.3) * _u(rng, 0.0, 0.01)
    return Samples(out.t, out.f, out.d + extra), Truth("fruit_collapse", "kv", p)


def _force_ramp_kv(
    rng: np.random.Generator, k: float, c: float, peak_n: float
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    rate_hz = float(rng.choice([77.0, 100.0, 200.0]))
    b = _u(rng, 1.0, 10.0)
    t = np.arange(round(peak_n / b * rate_hz) + 1) / rate_hz
    tau = c / k
    d = (b / k) * (t - tau * (1.0 - np.exp(-t / tau)))
    return t, b * t, d, rate_hz


def shape_slip(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """A force-controlled squeeze that slips before its peak: a falling stretch."""
    p = _kv_params(rng)
    k, c = p["stiffness_n_per_m"], p["damping_ns_per_m"]
    t, f, d, rate_hz = _force_ramp_kv(rng, k, c, _u(rng, 2.0, 28.0))
    at = int(_u(rng, 0.3, 0.7) * t.size)
    drop = _u(rng, 0.05, 0.3) * f[at]
    width = max(int(_u(rng, 0.05, 0.2) * rate_hz), 2)
    fall = np.clip((np.arange(t.size) - at) / width, 0.0, 1.0)
    recover = np.clip((np.arange(t.size) - at - width) / (3 * width), 0.0, 1.0)
    f = f - drop * fall * (1.0 - recover)
    d = d + fall * drop / k  # the jaws jump on as the grip slips
    noise = np.random.default_rng(int(rng.integers(2**31))).normal(0.0, 0.01, t.size)
    return Samples(t, f + noise, d), Truth("slip", "kv", p, d_defined=False)


def shape_buckling(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """A printed structure's cycle at one speed: rise, plateau, dip, rise, unload."""
    rate_hz = float(rng.choice([10.0, 20.0, 50.0]))
    peak_d = _u(rng, 0.003, 0.015)
    load_s = _u(rng, 5.0, 30.0)
    t_load = np.arange(round(load_s * rate_hz) + 1) / rate_hz
    d_load = peak_d * t_load / load_s
    x = d_load / peak_d
    k = _u(rng, 100.0, 800.0)
    f1 = k * 0.4 * peak_d
    dip = _u(rng, 0.1, 0.3)
    plateau = np.where(x < 0.4, k * d_load, f1 * (1.0 - dip * np.sin(np.pi * (x - 0.4) / 0.3)))
    f_load = np.where(x < 0.7, plateau, f1 + 2.0 * k * (d_load - 0.7 * peak_d))
    t_un = t_load[1:] + load_s
    d_un = peak_d * (1.0 - t_load[1:] / load_s)
    f_un = f_load[-1] * (d_un / peak_d) ** 2
    t = np.concatenate([t_load, t_un])
    f = np.concatenate([f_load, f_un])
    d = np.concatenate([d_load, d_un])
    f = np.round(f / 0.1) * 0.1  # kN to 4 decimals: 0.1 N resolution
    return Samples(t, f, d), Truth("buckling", d_defined=False)


def shape_relaxation(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """A standard linear solid pressed fast and held: the force jumps, then decays."""
    from deformctl.testing.synthetic import synthetic_relaxation_hold

    k = _u(rng, 200.0, 3000.0)
    s = synthetic_relaxation_hold(
        stiffness_n_per_m=k,
        arm_stiffness_n_per_m=k * _u(rng, 0.5, 3.0),
        relaxation_time_s=_u(rng, 0.3, 3.0),
        peak_compression_m=_u(rng, 0.002, 0.01),
        load_s=_u(rng, 0.05, 0.5),
        hold_s=_u(rng, 3.0, 10.0),
        rate_hz=float(rng.choice([50.0, 100.0, 200.0])),
        seed=int(rng.integers(2**31)),
    )
    return _from_series(s), Truth("relaxation", d_defined=False)


def shape_degenerate(rng: np.random.Generator) -> tuple[Samples, Truth]:
    """Two to five rows, or a force that never changes: a clear error is the right answer."""
    n = int(rng.integers(2, 6)) if rng.random() < 0.5 else 200
    t = np.arange(n) / 100.0
    d = np.linspace(0.0, 0.005, n)
    f = np.full(n, 1.0) if n == 200 else 1.0 + 500.0 * d
    return Samples(t, f, d), Truth("degenerate", d_defined=False)


#: Every shape by name.
SHAPES: dict[str, Callable[[np.random.Generator], tuple[Samples, Truth]]] = {
    "kv_ramp_hold": shape_kv_ramp_hold,
    "hc_ramp_hold": shape_hc_ramp_hold,
    "stiffening": shape_stiffening,
    "latency": shape_latency,
    "logging_gap": shape_logging_gap,
    "fruit_collapse": shape_fruit_collapse,
    "slip": shape_slip,
    "buckling": shape_buckling,
    "relaxation": shape_relaxation,
    "degenerate": shape_degenerate,
}


# ---------------------------------------------------------------------------- draws and runs


def draw(seed: int, index: int, shape: str | None = None) -> Case:
    """Draw ``index`` of ``seed``: a shape (uniform over :data:`SHAPES` unless given) and a
    layout (:func:`deformctl.testing.exports.draw_layout`), each from its own seeded stream."""
    rng = np.random.default_rng([seed, index])
    name = shape if shape is not None else str(rng.choice(list(SHAPES)))
    samples, truth = SHAPES[name](rng)
    layout = draw_layout(rng)
    data, options = export_bytes(samples, layout)
    return Case(f"{seed}-{index}-{name}-{layout['style']}", data, options, truth, layout)


@dataclass(frozen=True)
class Outcome:
    """What one case gave.

    Attributes:
        kind: ``row`` (a coefficients row was written), ``refused`` (one error of the tool's
            own kind) or ``internal`` (any other exception).
        message: the error line, or the traceback's last line for an internal error.
        row: the coefficients row (``row``).
        notes: the lines ``measure`` printed (notes and warnings).
    """

    kind: str
    message: str = ""
    row: Mapping[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def wrong(self, truth: Truth) -> list[str]:
        """Why the row is confidently wrong (quality ``ok`` and D or λ off); empty: not."""
        if self.kind != "row" or self.row.get("quality") != "ok":
            return []
        out = []
        d = float(self.row["deformability_n_per_cm"])
        d_true = truth.deformability_n_per_cm(float(self.row["operating_force_n"]))
        if math.isfinite(d_true) and not abs(d / d_true - 1.0) <= D_TOL:
            out.append(f"D {d:.4g} vs {d_true:.4g} N/cm ({100 * (d / d_true - 1):+.1f} %)")
        lam = float(self.row["damping_ns_per_cm"])
        lam_true = truth.damping_ns_per_cm
        if math.isfinite(lam_true) and not abs(lam / lam_true - 1.0) <= LAMBDA_TOL:
            out.append(
                f"λ {lam:.4g} vs {lam_true:.4g} N·s/cm ({100 * (lam / lam_true - 1):+.1f} %)"
            )
        return out


def run_case(case: Case, workdir: Path) -> Outcome:
    """``measure --csv`` (library), the squeeze-log writer, ``characterize`` and the
    coefficients writer on one case (see the module docstring)."""
    from deformctl.errors import DeformctlError

    try:
        return _run(case, workdir)
    except DeformctlError as err:
        return Outcome("refused", str(err))
    except Exception as err:  # counting them is the point
        last = traceback.format_exception_only(type(err), err)[-1].strip()
        return Outcome("internal", last)


def _run(case: Case, workdir: Path) -> Outcome:
    from deformctl.artifacts import write_table
    from deformctl.artifacts.provenance import Provenance
    from deformctl.catalog import object_record
    from deformctl.characterize.stage import read_and_characterize
    from deformctl.measure.csv.options import CsvDialect, CsvOptions
    from deformctl.measure.stage import read_recording, recording_log

    src = workdir / "export.csv"
    src.write_bytes(case.data)
    opts = dict(case.options)
    dialect = CsvDialect(encoding=opts.pop("encoding", "utf-8"))
    options = CsvOptions(dialect=dialect, **opts)
    rec = read_recording(src, options, "obj")
    log = workdir / "log.mcap"
    obj = object_record("obj", weight_n=1.0)
    recording_log(str(src), rec, obj, options.as_dict(), output=str(log), force=True)
    result = read_and_characterize(log)
    provenance = Provenance.from_invocation([str(log)], settings={})
    write_table(
        result.table, str(workdir / "c.parquet"), "coefficients", provenance=provenance, force=True
    )
    (row,) = result.table.to_dict("records")
    return Outcome("row", row=row, notes=rec.notes + rec.warnings)


@dataclass
class Report:
    """The counts of a :func:`check` run."""

    draws: int = 0
    kinds: Counter[str] = field(default_factory=Counter)
    by_shape: dict[str, Counter[str]] = field(default_factory=dict)
    internal: list[tuple[str, str]] = field(default_factory=list)
    wrong: list[tuple[str, str]] = field(default_factory=list)

    def add(self, case: Case, out: Outcome) -> None:
        """Count one case."""
        self.draws += 1
        self.kinds[out.kind] += 1
        counts = self.by_shape.setdefault(case.truth.shape, Counter())
        counts[out.kind] += 1
        if out.kind == "internal":
            self.internal.append((case.name, out.message))
        if out.kind == "row":
            counts["ok" if out.row.get("quality") == "ok" else "flagged"] += 1
        why = out.wrong(case.truth)
        if why:
            counts["wrong"] += 1
            self.wrong.append((case.name, "; ".join(why)))

    def lines(self, limit: int = 20) -> list[str]:
        """The report's lines."""
        out = [
            f"draws: {self.draws}",
            f"internal errors: {len(self.internal)}",
            f"confidently wrong rows: {len(self.wrong)}",
            f"rows written: {self.kinds['row']}, refused with one error: {self.kinds['refused']}",
            "by shape (rows / ok / flagged / refused / internal / wrong):",
        ]
        for shape in SHAPES:
            c = self.by_shape.get(shape, Counter())
            out.append(
                f"  {shape:15s} {c['row']:5d} {c['ok']:5d} {c['flagged']:5d} {c['refused']:5d} "
                f"{c['internal']:5d} {c['wrong']:5d}"
            )
        out += [f"internal: {n}: {m}" for n, m in self.internal[:limit]]
        out += [f"wrong: {n}: {m}" for n, m in self.wrong[:limit]]
        return out


def check(
    draws: int, seed: int, *, shapes: Sequence[str] | None = None, on_case: Any = None
) -> Report:
    """Run ``draws`` seeded cases (shapes uniform over ``shapes``, default all) and count."""
    report = Report()
    names = list(shapes) if shapes else None
    with tempfile.TemporaryDirectory(prefix="deformctl-shapes-") as tmp:
        for i in range(draws):
            shape = None if names is None else names[i % len(names)]
            case = draw(seed, i, shape)
            out = run_case(case, Path(tmp))
            report.add(case, out)
            if on_case is not None:
                on_case(case, out)
    return report


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m deformctl.testing.shapes check --draws N --seed S [--shape NAME ...]``:
    print the counts; exit 1 when a draw raised an internal error."""
    parser = argparse.ArgumentParser(prog="python -m deformctl.testing.shapes")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("check", help="run seeded draws through measure --csv and characterize")
    run.add_argument("--draws", type=int, default=2000)
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--shape", action="append", choices=list(SHAPES))
    run.add_argument("--verbose", action="store_true")
    args = parser.parse_args(argv)

    def show(case: Case, out: Outcome) -> None:
        if args.verbose:
            print(f"{case.name}: {out.kind} {out.row.get('quality', out.message)}", flush=True)

    report = check(args.draws, args.seed, shapes=args.shape, on_case=show)
    for line in report.lines():
        print(line)
    return 1 if report.internal else 0


if __name__ == "__main__":
    sys.exit(main())
