"""``make fuzz``: seeded hostile inputs through the CLI, and the fraction handled cleanly.

Good artifacts are written once (a catalog, a squeeze log, a ROS 2 bag, the
coefficients / lift-results / index tables, the bundled grip model), then each case damages one
of them the way a disk, a cable, a recorder or a user does (a flipped bit, a cut, zeroed bytes,
a value replaced by 1e308, -20, 0, NaN, text or nothing, a column scaled by 10^3, a short row)
and runs the command that reads it, in process (typer's runner). A case is **clean** when:

* the command exits 0, 1, 2, 65 or 66 without an exception other than ``SystemExit``;
* a failure prints exactly one ``error:`` line (warnings may precede it), no traceback, and
  leaves no output file behind (``lift`` keeps its attempts: exit 1 only);
* a success prints no force that is not a force: an interpolated or predicted L_f is finite and
  > 0, and one outside [F_w, 10 F_w] carries ``prediction_implausible``;
* a recording with a unit slip of 10³ (a column scaled, or its label changed) that ``measure``
  accepts carries a warning naming the unit that would make it plausible.

The later kinds: a CSV export with a unit slip (``measure --csv``),
an index whose rig rows ``adapt`` must refuse or use, a hostile ``--max-force-n`` on every
``lift`` output (single file and ``-o DIR/``), and a model whose stored training ranges or
target range are damaged (``predict``).

The second hostile run's classes (tests/fuzz/hostile_cases.py: the rig's absolute limit, a
tiny μ, tampered calibration scores, a coverage below 1/(n + 1), one model loader, the
documented bounds at every stage, a reversed bag, a flipped bit without CRC checks, a catalog of
thousands of columns, a relabelled log, a short row, a table without rows, a device as a bag and
the CSV exports) also hold each case to its right exit code, a flag it must carry, the rig
requests it must not exceed, or the verdict a second command must share.

Usage: ``python -m tests.fuzz.hostile_cli --cases 1000 --seed 0`` (``make fuzz``); it prints
every unclean case, the clean count per class and the clean fraction, and exits 1 when one is
unclean.
"""

from __future__ import annotations

import argparse
import io
import math
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))  # the checkout, for tests._helpers and tests.fuzz
from tests.fuzz.hostile_cases import CLASSES, ELSEWHERE, write_extra_base  # noqa: E402

KINDS = (
    "catalog", "squeeze_log", "bag", "tables", "index", "model",
    "recording", "rig_rows", "max_force", "model_meta", *CLASSES,
)  # fmt: skip
VALUES = ("1e308", "-20", "0", "nan", "inf", "-1e-300", "abc", "")


@dataclass
class Case:
    name: str
    argv: list[str]
    output: Path | None
    check: Callable[[str], str | None] | None = None  # stdout -> problem, for exit 0
    needs_warning: bool = False  # exit 0 must carry a "plausible ..." warning (a unit slip)
    expect: tuple[int, ...] | None = None  # the exit codes that are right (None: any clean one)
    stderr_needs: str | None = None  # exit 0 must say this on stderr (a flag's name)
    after: Callable[[], str | None] | None = None  # files the command left -> problem
    same_as: list[str] | None = None  # a command that must accept or refuse alike
    max_s: float | None = None  # the longest the command may take, s
    stdin: bytes | None = None


def _write_base(root: Path) -> dict[str, Path]:
    """The good artifacts every case starts from."""
    from deformctl.artifacts import write_table
    from deformctl.artifacts.mcap import write_squeeze_log
    from deformctl.measure.recording import SqueezeSeries
    from deformctl.table import build_index_table
    from tests._helpers.ros2_bags import write_bag

    base = {"catalog": root / "objects.csv"}
    shutil.copy(REPO / "datasets/paper/objects.csv", base["catalog"])
    t = np.linspace(0.0, 2.0, 400)
    comp = 0.004 * np.sin(np.pi * t / 2.0) ** 2
    force = 3000.0 * comp + 60.0 * np.gradient(comp, t)
    series = [SqueezeSeries("A", i, t, force, comp) for i in range(2)]
    base["squeeze_log"] = root / "squeeze.mcap"
    obj = {"object_id": "A", "size_x_cm": 10.0, "size_y_cm": 10.0, "size_z_cm": 10.0,
           "weight_n": 2.0, "friction_mu": 0.5}  # fmt: skip
    write_squeeze_log(base["squeeze_log"], [obj], series, provenance=None)
    base["bag"] = root / "bag.mcap"
    write_bag(base["bag"], 30.0, 6.0, seed=1, force_rate_hz=200.0, n_squeezes=2)
    cat = pd.read_csv(base["catalog"])
    ids = cat["object_id"].astype(str)
    w, mu = cat["weight_n"].to_numpy(float), cat["friction_mu"].to_numpy(float)
    coef = pd.DataFrame({"object_id": ids, "deformability_n_per_cm": cat.iloc[:, 8],
                         "damping_ns_per_cm": cat.iloc[:, 9], "quality": "ok"})  # fmt: skip
    f_w = w / (2 * mu)
    lift = pd.DataFrame({"object_id": ids, "weight_n": w, "friction_mu": mu, "f_w_n": f_w,
                         "lift_force_n": 1.4 * f_w, "f_d_n": 0.4 * f_w, "attempts": 6,
                         "converged": True, "protocol": "refine"})  # fmt: skip
    base["coefficients"], base["lift"] = root / "coef.parquet", root / "lift.parquet"
    write_table(coef, base["coefficients"], "coefficients", provenance=None)
    write_table(lift, base["lift"], "lift_results", provenance=None)
    base["index"] = root / "index.parquet"
    write_table(build_index_table(coef, lift), base["index"], "index_table", provenance=None)
    base["model"] = root / "grip.skops"
    from deformctl.grip.fast import resolve_model_path

    shutil.copy(resolve_model_path("grip"), base["model"])
    base["recording"] = root / "export.csv"
    tr = np.arange(0.0, 2.0, 1.0 / 500.0)
    dr = 0.003 * np.sin(np.pi * tr / 2.0) ** 2  # 3 mm, a 10 N Kelvin-Voigt squeeze
    fr = (
        2000.0 * dr
        + 30.0 * np.gradient(dr, tr)
        + 0.01 * np.random.default_rng(0).normal(size=tr.size)
    )
    rows = [f"{a:.4f},{b:.6f},{c * 1e3:.6f}" for a, b, c in zip(tr, fr, dr, strict=True)]
    base["recording"].write_text("Time (s),Load (N),Compression (mm)\n" + "\n".join(rows) + "\n")
    write_extra_base(root, base)
    return base


def _bytes_damage(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    how = rng.integers(4)
    at = int(rng.integers(max(len(data), 1)))
    if how == 0:
        out = bytearray(data)
        out[at] ^= 1 << int(rng.integers(8))
        return f"bit flip at {at}", bytes(out)
    if how == 1:
        return f"cut at {at}", data[:at]
    if how == 2:
        out = bytearray(data)
        out[at : at + 16] = bytes(min(16, len(data) - at))
        return f"16 zero bytes at {at}", bytes(out)
    return "junk appended", data + bytes(rng.integers(0, 256, 64, dtype=np.uint8))


def _frame_damage(df: pd.DataFrame, rng: np.random.Generator) -> tuple[str, pd.DataFrame]:
    numeric = [c for c in df.columns if df[c].dtype.kind == "f"]
    col = numeric[int(rng.integers(len(numeric)))]
    row = int(rng.integers(len(df)))
    out = df.copy()
    if rng.random() < 0.3:
        factor = float(rng.choice([1e3, 1e-3, -1.0]))
        out[col] = out[col] * factor
        return f"{col} x {factor:g}", out
    value = float(rng.choice([1e308, -20.0, 0.0, math.nan, math.inf, -1e-300, 1e-300]))
    out.loc[row, col] = value
    return f"{col}[{row}] = {value!r}", out


def _csv_damage(text: str, rng: np.random.Generator) -> tuple[str, str]:
    lines = text.splitlines()
    i = 1 + int(rng.integers(len(lines) - 1))
    cells = lines[i].split(",")
    if rng.random() < 0.25:
        lines[i] = ",".join(cells[:-1])
        return f"row {i} one field short", "\n".join(lines) + "\n"
    j = int(rng.integers(len(cells)))
    value = str(rng.choice(VALUES))
    cells[j] = value
    lines[i] = ",".join(cells)
    return f"row {i} field {j} = {value!r}", "\n".join(lines) + "\n"


def _lift_force_ok(low_n: float, high_n: float) -> Callable[[str], str | None]:
    """A lookup's check: the interpolated L_f is finite and within the good table's
    [min F_w, 10 x max F_w] (a blend of entries cannot leave it)."""

    def check(stdout: str) -> str | None:
        for line in stdout.splitlines():
            if line.startswith("interpolated lift_force_n:"):
                value = float(line.split(":")[1].split()[0])
                if not (math.isfinite(value) and low_n <= value <= high_n):
                    return f"printed L_f {value} outside [{low_n:g}, {high_n:g}] N"
        return None

    return check


def _prediction_ok(stdout: str) -> str | None:
    table = pd.read_csv(io.StringIO(stdout))
    lift = table["predicted_lift_force_n"].to_numpy(float)
    if not np.all(np.isfinite(lift) & (lift > 0)):
        return f"printed L_f {lift.tolist()}"
    if "f_w_n" in table.columns:
        f_w = table["f_w_n"].to_numpy(float)
        odd = (lift < f_w * 0.995) | (lift > 10 * f_w)
        flagged = table.get("prediction_implausible", pd.Series(False, index=table.index))
        if np.any(odd & ~flagged.to_numpy(bool)):
            return "implausible L_f without prediction_implausible"
    return None


#: A recording's unit slips: (what, column, scale of the values, header text replaced, or None,
#: whether ``measure`` must warn or refuse). ``lbf`` relabels N values as lbf: 44 N, plausible.
SLIPS: tuple[tuple[str, int, float, tuple[str, str] | None, bool], ...] = (
    ("force in kN read as N", 1, 1e-3, None, True),
    ("force in mN read as N", 1, 1e3, None, True),
    ("compression in m under (mm)", 2, 1e-3, None, True),
    ("compression in um under (mm)", 2, 1e3, None, True),
    ("N values under [kN]", 1, 1.0, ("Load (N)", "Load [kN]"), True),
    ("N values under (mN)", 1, 1.0, ("Load (N)", "Load (mN)"), True),
    ("mm values under (m)", 2, 1.0, ("Compression (mm)", "Compression (m)"), True),
    ("s values under (ms)", 0, 1.0, ("Time (s)", "Time (ms)"), True),
    ("s values under (us)", 0, 1.0, ("Time (s)", "Time (us)"), True),
    ("N values under [lbf]", 1, 1.0, ("Load (N)", "Load [lbf]"), False),
    ("force x 1e-6", 1, 1e-6, None, True),
    ("force x 1e-9", 1, 1e-9, None, True),
)


def _recording_case(i: int, base: dict[str, Path], work: Path, rng: np.random.Generator) -> Case:
    what, column, scale, relabel, warns = SLIPS[int(rng.integers(len(SLIPS)))]
    lines = base["recording"].read_text().splitlines()
    if relabel is not None:
        lines[0] = lines[0].replace(*relabel)
    if scale != 1.0:
        body = []
        for line in lines[1:]:
            cells = line.split(",")
            cells[column] = f"{float(cells[column]) * scale:.12g}"
            body.append(",".join(cells))
        lines = [lines[0], *body]
    path = work / f"export{i}.csv"
    path.write_text("\n".join(lines) + "\n")
    out = work / f"out{i}.mcap"
    argv = ["measure", "csv", str(path), "--weight-n", "1", "--object-id", "A", "-o", str(out)]
    return Case(f"recording {what}: measure", argv, out, needs_warning=warns)


def _rig_rows_case(i: int, base: dict[str, Path], work: Path, rng: np.random.Generator) -> Case:
    from deformctl.artifacts import write_table
    from deformctl.grip.fast import Predictor

    frame = pd.read_parquet(base["index"]).copy()
    grip = Predictor.load(str(base["model"]))
    cols = [frame[c].to_numpy(float) for c in grip.features]
    frame["lift_force_n"] = 1.2 * grip.predict_many(*cols).lift_force_n
    frame["source"], frame["converged"] = "rig", True
    what, frame = _frame_damage(frame, rng)
    path = work / f"rig{i}.parquet"
    try:
        write_table(frame, path, "index_table", provenance=None)
    except Exception:  # the writer refuses it: a foreign writer does not
        frame.to_parquet(path)
    out = work / f"adapted{i}.skops"
    argv = ["adapt", str(base["model"]), str(path), "-o", str(out)]
    return Case(f"rig rows {what}: adapt", argv, out)


def _max_force_case(i: int, base: dict[str, Path], work: Path, rng: np.random.Generator) -> Case:
    value = str(rng.choice([v for v in VALUES if v != "1e308"] + ["-inf", "1e-400", "5 N"]))
    dataset = rng.random() < 0.5
    out = f"{work / f'sweep{i}'}/" if dataset else str(work / f"lift{i}.parquet")
    runner = ["sim"] if dataset else ["rig", "--command", "true"]
    argv = ["lift", runner[0], str(base["catalog"]), *runner[1:], "--max-force-n", value, "-o", out]
    return Case(f"--max-force-n {value!r} ({'DIR/' if dataset else 'file'}): lift", argv,
                Path(out.rstrip("/")))  # fmt: skip


def _model_meta_case(i: int, base: dict[str, Path], work: Path, rng: np.random.Generator) -> Case:
    from deformctl.adapt import model_file_bytes
    from deformctl.grip.fast import read_model_metadata

    meta = dict(read_model_metadata(base["model"]))
    value = float(rng.choice([1e308, -20.0, 0.0, math.nan, math.inf, 1e-300, 1.5, 3.0]))
    if rng.random() < 0.5:
        low, high = meta["target_range"]["lift_ratio_f_w"]
        pair = [value, high] if rng.random() < 0.5 else [low, value]
        meta["target_range"] = {"lift_ratio_f_w": pair}
        what = f"target range {pair}"
    else:
        ranges = dict(meta["training_range"])
        key = sorted(ranges)[int(rng.integers(len(ranges)))]
        ranges[key] = [ranges[key][0], value]
        meta["training_range"] = ranges
        what = f"training range {key} = {ranges[key]}"
    path = work / f"model{i}.skops"
    path.write_bytes(model_file_bytes(str(base["model"]), meta))
    argv = ["predict", str(path), "--weight-n", "2.9", "--deformability-n-per-cm", "30",
            "--damping-ns-per-cm", "0.47", "--friction-mu", "0.5"]  # fmt: skip
    return Case(f"model {what}: predict", argv, None, _prediction_ok)


def make_case(i: int, base: dict[str, Path], work: Path, rng: np.random.Generator) -> Case:
    kind = KINDS[i % len(KINDS)]
    out = work / f"out{i}"
    later = {"recording": _recording_case, "rig_rows": _rig_rows_case,
             "max_force": _max_force_case, "model_meta": _model_meta_case}  # fmt: skip
    if kind in later:
        return later[kind](i, base, work, rng)
    if kind in CLASSES:
        return CLASSES[kind](i, base, work, rng)
    if kind == "catalog":
        what, text = _csv_damage(base["catalog"].read_text(encoding="utf-8"), rng)
        path = work / f"cat{i}.csv"
        path.write_text(text, encoding="utf-8")
        if rng.random() < 0.5:
            return Case(f"catalog {what}: inspect", ["inspect", str(path)], None)
        argv = ["predict", "grip", "--catalog", str(path), str(base["index"]), "-o", f"{out}.csv"]
        return Case(f"catalog {what}: predict", argv, Path(f"{out}.csv"))
    if kind in ("squeeze_log", "bag", "model"):
        what, data = _bytes_damage(base[kind].read_bytes(), rng)
        path = work / f"{kind}{i}{base[kind].suffix}"
        path.write_bytes(data)
        if kind == "squeeze_log":
            argv = ["characterize", str(path), "-o", f"{out}.parquet"]
            return Case(f"squeeze log {what}: characterize", argv, Path(f"{out}.parquet"))
        if kind == "bag":
            argv = ["measure", "bag", str(path), "--wrench-topic", "/left/wrench",
                    "--position-topic", "/left/palm_pose", "--object-id", "A",
                    "--weight-n", "1", "-o", f"{out}.mcap"]  # fmt: skip
            return Case(f"bag {what}: measure", argv, Path(f"{out}.mcap"))
        argv = ["predict", str(path), "--weight-n", "2.9", "--deformability-n-per-cm", "30",
                "--damping-ns-per-cm", "0.47", "--friction-mu", "0.5"]  # fmt: skip
        return Case(f"model {what}: predict", argv, None, _prediction_ok)
    if kind == "tables":
        side = "coefficients" if rng.random() < 0.5 else "lift"
        what, frame = _frame_damage(pd.read_parquet(base[side]), rng)
        path = work / f"{side}{i}.parquet"
        frame.to_parquet(path)  # a foreign writer: no provenance, any value
        coef = path if side == "coefficients" else base["coefficients"]
        lift = path if side == "lift" else base["lift"]
        argv = ["table", str(coef), str(lift), "-o", f"{out}.parquet"]
        return Case(f"{side} {what}: table", argv, Path(f"{out}.parquet"))
    from deformctl.artifacts import write_table

    what, frame = _frame_damage(pd.read_parquet(base["index"]), rng)
    path = work / f"index{i}.parquet"
    try:
        write_table(frame, path, "index_table", provenance=None)
    except Exception:  # the writer refuses it: a foreign writer does not
        frame.to_parquet(path)
    query = "weight_n=3,deformability_n_per_cm=30,damping_ns_per_cm=1"
    argv = ["table", str(path), "--lookup", query, "--interpolate", "3"]
    f_w = pd.read_parquet(base["index"])["f_w_n"]
    check = _lift_force_ok(float(f_w.min()), 10.0 * float(f_w.max()))
    return Case(f"index {what}: lookup", argv, None, check)


def judge(case: Case, result: object) -> str | None:
    """None when clean, else why not."""
    code = result.exit_code  # type: ignore[attr-defined]
    exc = result.exception  # type: ignore[attr-defined]
    if exc is not None and not isinstance(exc, SystemExit):
        return f"{type(exc).__name__}: {exc}"
    if code not in (0, 1, 2, 65, 66):
        return f"exit {code}"
    if case.expect is not None and code not in case.expect:
        err_line = (result.stderr or "").strip().splitlines()[-1:]  # type: ignore[attr-defined]
        return f"exit {code}, expected {'/'.join(map(str, case.expect))}: {err_line}"
    if case.after is not None:
        problem = case.after()
        if problem is not None:
            return problem
    err = result.stderr  # type: ignore[attr-defined]
    if "Traceback" in err:
        return "traceback"
    if code != 0:
        lines = [ln for ln in err.splitlines() if not ln.startswith("warning: ")]
        if len(lines) != 1 or not lines[0].startswith("error: "):
            return f"not one error line: {err[-300:]!r}"
        if case.output is not None and case.output.exists() and code != 1:
            return "output written on failure"
        return None
    if case.needs_warning and not any(
        ln.startswith("warning: ") and "plausible" in ln for ln in err.splitlines()
    ):
        return "a unit slip passed without a warning naming the unit"
    if case.stderr_needs is not None and case.stderr_needs not in err:
        return f"exit 0 without {case.stderr_needs!r} on stderr"
    if case.check is not None:
        return case.check(result.stdout)  # type: ignore[attr-defined]
    return None


def run(
    cases: int,
    seed: int,
    codes: dict[int, int] | None = None,
    per_kind: dict[str, list[int]] | None = None,
) -> tuple[int, list[str]]:
    """Run ``cases`` seeded cases; (clean count, one line per unclean case). ``per_kind``
    collects [clean, total] per artifact kind."""
    from typer.testing import CliRunner

    from deformctl.cli import app

    runner = CliRunner()
    rng = np.random.default_rng(seed)
    unclean: list[str] = []
    with tempfile.TemporaryDirectory(prefix="deformctl-fuzz-") as tmp:
        root = Path(tmp)
        base = _write_base(root)
        for i in range(cases):
            case = make_case(i, base, root, rng)
            started = time.perf_counter()
            result = runner.invoke(app, case.argv, input=case.stdin)
            took = time.perf_counter() - started
            if codes is not None:
                codes[result.exit_code] = codes.get(result.exit_code, 0) + 1
            problem = judge(case, result)
            if problem is None and case.max_s is not None and took > case.max_s:
                problem = f"took {took:.1f} s, more than {case.max_s:g} s"
            if problem is None and case.same_as is not None:
                other = runner.invoke(app, case.same_as)
                problem = judge(Case(case.name, case.same_as, None), other)
                if problem is None and (other.exit_code == 0) != (result.exit_code == 0):
                    problem = (
                        f"{case.argv[0]} exits {result.exit_code}, {case.same_as[0]} "
                        f"{other.exit_code}: two verdicts on one file"
                    )
            if problem is not None:
                unclean.append(f"case {i} ({case.name}): {problem}")
            if per_kind is not None:
                tally = per_kind.setdefault(KINDS[i % len(KINDS)], [0, 0])
                tally[0] += problem is None
                tally[1] += 1
    return cases - len(unclean), unclean


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=600)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    started = time.perf_counter()
    codes: dict[int, int] = {}
    per_kind: dict[str, list[int]] = {}
    clean, unclean = run(args.cases, args.seed, codes, per_kind)
    for line in unclean:
        print(line)
    for kind, (good, total) in per_kind.items():
        where = " (fixed on the CSV branch)" if kind in ELSEWHERE else ""
        print(f"  {kind:<16} {good}/{total} clean{where}")
    seconds = time.perf_counter() - started
    print(
        f"fuzz: {clean}/{args.cases} clean ({100.0 * clean / args.cases:.1f} %), seed {args.seed}, "
        f"{len(KINDS)} artifact kinds, {seconds:.0f} s; exit codes "
        + ", ".join(f"{k}: {v}" for k, v in sorted(codes.items()))
    )
    return 0 if not unclean else 1


if __name__ == "__main__":
    sys.exit(main())
