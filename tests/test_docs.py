"""Executed docs: every ``sh`` block of README.md and of each page under docs/ runs.

Each file's blocks run in order in one scratch folder of their own, which links the checkout's
``datasets/``, ``examples/`` and ``tests/`` (the docs' commands name them) and nothing else.
``python``, ``python3`` and ``deformctl`` are the test interpreter's (an activated ``.venv``). A
block preceded by ``<!-- docs-test: skip (why) -->`` is not run (the reason is part of the page);
every other block must exit 0, and the test names the file, line and block that did not. The
README and the task guides (docs/guide/) run instead as a wheel user runs them: from a
venv with only the built wheel installed, each page in a folder that ``deformctl examples``
filled, with no checkout on the path (so a block that needs a file the wheel lacks fails). The
CLI reference (docs/reference/cli.md) must be what ``python -m deformctl.cli.reference`` prints
now, and every relative link of the docs must name a file that exists.

Printed output never goes stale: every ``text`` block (but the generated CLI reference's) is
either marked with the commands that print it, and equal to what they print now (numbers at a
stated tolerance: tests/_helpers/docs_output.py), or is a benchmark's (``<!-- bench:NAME -->``,
rewritten by ``make bench``). No block names a folder a fresh clone lacks, and the ranges the
docs state for the bundled grip model and its population are the ones the code holds;
docs/development.md names only modules, files and names that exist.
"""

from __future__ import annotations

import ast
import importlib
import math
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests._helpers import docs_output
from tests._helpers.wheel import venv_env

pytestmark = pytest.mark.docs

REPO = Path(__file__).resolve().parents[1]
BLOCK = re.compile(
    r"(?:<!-- docs-test: skip \((?P<why>[^)]*)\) -->\n)?```sh\n(?P<code>.*?)```", re.S
)
LINK = re.compile(r"\]\((?!https?://|#|mailto:)(?P<target>[^)#\s]+)(?:#[^)]*)?\)")
#: The README stays short: what, for whom, install, a first example and links.
README_MAX_LINES = 150


def doc_files() -> list[Path]:
    """README.md and every Markdown page under docs/, in a fixed order."""
    return [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]


def shell_blocks(path: Path) -> list[tuple[int, str, str | None]]:
    """``(line, code, skip reason)`` of every ``sh`` block of ``path``, in order."""
    text = path.read_text(encoding="utf-8")
    return [
        (text.count("\n", 0, m.start("code")), m["code"], m["why"]) for m in BLOCK.finditer(text)
    ]


def _id(path: Path) -> str:
    return str(path.relative_to(REPO))


#: What a wheel user follows: the README (its first example) and the task guides. These pages run
#: from a wheel-installed venv only (the wheel is built from this checkout, so an edit to the
#: code or the page is tested the same), every other page from the checkout.
WHEEL_PAGES = [REPO / "README.md", *sorted((REPO / "docs" / "guide").glob("*.md"))]
RUNNABLE = [p for p in doc_files() if shell_blocks(p) and p not in WHEEL_PAGES]


def _checkout_env() -> dict[str, str]:
    """The environment of a developer who activated the checkout's ``.venv``."""
    path = f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"
    return {**os.environ, "PATH": path}


def _run(code: str, cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """Run ``code`` as a docs block: bash -e, pipefail, stdout and stderr in one stream, each
    command announced (:data:`docs_output.TRAP`)."""
    return subprocess.run(
        ["bash", "-e", "-o", "pipefail", "-c", docs_output.TRAP + code],
        cwd=cwd,
        env={**env, "PYTHONUNBUFFERED": "1"},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        check=False,
    )


def _printed(item: docs_output.Item, seen: dict[str, str], cwd: Path, env: dict[str, str]) -> str:
    """What the commands of an output block print: as a block of the page printed it before,
    else run here."""
    parts = []
    for command in item.commands:
        key = docs_output.norm_command(command)
        if key not in seen:
            proc = _run(command, cwd, env)
            seen.update(docs_output.split_by_command(proc.stdout))
            seen.setdefault(key, proc.stdout)
        parts.append(seen[key])
    return "\n".join(parts)


def _run_page(path: Path, cwd: Path, env: dict[str, str]) -> list[str]:
    """Run the ``sh`` blocks of ``path`` in order in ``cwd`` (fails the test at the first one
    that exits non-zero); the page's stale output blocks, one message each."""
    seen: dict[str, str] = {}
    stale: list[str] = []
    for item in docs_output.items(path.read_text(encoding="utf-8")):
        where = f"{_id(path)}:{item.line}"
        if item.code is None:
            if item.commands:
                printed = _printed(item, seen, cwd, env)
                problem = docs_output.mismatch(item.out or "", printed, item.rel)
                if problem:
                    stale.append(f"{where}: the output block is stale: {problem}\n--- printed:\n"
                                 f"{printed.strip()}")  # fmt: skip
            continue
        if item.why is not None:
            assert item.why.strip(), f"{where}: a skipped block must say why"
            continue
        proc = _run(item.code, cwd, env)
        seen.update(docs_output.split_by_command(proc.stdout))
        if proc.returncode != 0:
            lines = [x for x in proc.stdout.splitlines() if not x.startswith(docs_output.SENTINEL)]
            tail = "\n".join("\n".join(lines).strip().splitlines()[-8:])
            pytest.fail(f"{where}: block exited {proc.returncode}:\n{item.code}\n{tail}")
    return stale


@pytest.mark.slow
@pytest.mark.parametrize("path", RUNNABLE, ids=_id)
def test_every_shell_block_runs_and_prints_what_the_page_shows(path: Path, tmp_path: Path) -> None:
    for name in ("datasets", "examples", "tests"):
        (tmp_path / name).symlink_to(REPO / name)
    stale = _run_page(path, tmp_path, _checkout_env())
    assert not stale, "\n\n".join(stale)


@pytest.fixture(scope="module")
def wheel_user_venv(warm_venv: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """:func:`warm_venv` (``pip install`` and ``deformctl warmup`` done) as a wheel user who
    activated it sees it: its ``bin/`` first on PATH (``deformctl``, ``python`` and ``python3``
    are the venv's, the checkout is nowhere on the path)."""
    found = subprocess.run(
        ["bash", "-c", "command -v deformctl python python3; "
         "python -c 'import deformctl; print(deformctl.__file__)'"],
        cwd=tmp_path_factory.mktemp("user"), env=venv_env(warm_venv), capture_output=True,
        text=True, check=True,
    ).stdout.split()  # fmt: skip
    assert len(found) == 4, found
    assert all(Path(p).is_relative_to(warm_venv) for p in found), found
    return warm_venv


@pytest.mark.slow
@pytest.mark.parametrize("path", WHEEL_PAGES, ids=_id)
def test_the_guides_run_from_a_wheel_installed_venv(
    path: Path, wheel_user_venv: Path, tmp_path: Path
) -> None:
    """As a wheel user follows a page: in the warmed-up venv (:func:`wheel_user_venv`),
    ``deformctl examples DIR`` and the page's ``sh`` blocks in order in ``DIR``, its output
    blocks checked as above."""
    env = venv_env(wheel_user_venv)
    cwd = tmp_path / path.stem
    subprocess.run([wheel_user_venv / "bin" / "deformctl", "examples", cwd], env=env, check=True,
                   capture_output=True)  # fmt: skip
    stale = _run_page(path, cwd, env)
    assert not stale, "\n\n".join(stale)


@pytest.mark.parametrize("path", doc_files(), ids=_id)
def test_every_output_block_is_checked_or_regenerated(path: Path) -> None:
    if path == REPO / "docs" / "reference" / "cli.md":  # generated; test_cli_reference_is_current
        return
    for item in docs_output.items(path.read_text(encoding="utf-8")):
        if item.code is not None:
            continue
        where = f"{_id(path)}:{item.line}"
        if item.bench is not None:
            assert (REPO / "bench" / f"{item.bench.removeprefix('bench:')}.py").is_file(), where
        else:
            assert item.commands, f"{where}: a text block needs <!-- output-of: `COMMAND` -->"


#: Folders of one machine, not of a clone: no docs block may name them.
MACHINE_PATH = re.compile(r"(?<![\w:/.])/(?:work|home|root|Users|mnt|srv|scratch)/[\w./*-]*")


def _tracked() -> set[str]:
    files = subprocess.run(
        ["git", "ls-files"], cwd=REPO, capture_output=True, text=True, check=True
    ).stdout.split()
    return {"/".join(f.split("/")[:k]) for f in files for k in range(1, f.count("/") + 2)}


@pytest.mark.parametrize("path", doc_files(), ids=_id)
def test_no_block_names_a_folder_a_fresh_clone_lacks(path: Path) -> None:
    tracked = _tracked()
    tops = {t for t in tracked if "/" not in t and (REPO / t).is_dir()}
    for line, code, _ in shell_blocks(path):
        assert not MACHINE_PATH.search(code), f"{_id(path)}:{line}: {MACHINE_PATH.search(code)}"
        for token in re.findall(r"(?<![\w/.-])[\w.-]+/[\w./-]*", code):
            if token.split("/")[0] in tops:
                assert token.rstrip("/.") in tracked, f"{_id(path)}:{line}: {token} is not tracked"


def test_cli_reference_is_current() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "deformctl.cli.reference", "--check", "docs/reference/cli.md"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr


def test_readme_is_short_and_links_the_docs() -> None:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= README_MAX_LINES
    for page in ("docs/guide/", "docs/explanation/", "docs/reference/cli.md"):
        assert page in text, page


@pytest.mark.parametrize("path", doc_files(), ids=_id)
def test_relative_links_name_existing_files(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    missing = [m["target"] for m in LINK.finditer(text) if not (path.parent / m["target"]).exists()]
    assert not missing, f"{_id(path)}: links to missing files: {missing}"


def _inward(value: float, up: bool) -> float:
    """``value`` rounded to 3 significant digits toward the inside of a range (a stated lower
    bound up, an upper one down), so that every value inside the stated range is inside."""
    if value == 0:
        return 0.0
    exp = math.floor(math.log10(abs(value))) - 2
    return round((math.ceil if up else math.floor)(value / 10.0**exp) * 10.0**exp, 12)


RANGE = r"([\d.]+)–([\d.]+)"


def _stated(path: str, pattern: str) -> list[float]:
    text = " ".join((REPO / path).read_text(encoding="utf-8").split())
    m = re.search(pattern, text)
    assert m is not None, f"{path}: no range stated as {pattern!r}"
    return [float(g) for g in m.groups()]


def test_the_grip_models_stated_range_is_the_one_it_enforces() -> None:
    from deformctl.grip.fast import Predictor

    ranges = Predictor.load("grip").ranges  # outside these, a prediction is flagged
    stated = _stated(
        "docs/guide/gripper.md",
        rf"for W {RANGE} N, D {RANGE} N/cm, λ {RANGE} N·s/cm and μ {RANGE},",
    )
    names = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu")
    want = [_inward(v, up=k == 0) for name in names for k, v in enumerate(ranges[name])]
    assert stated == want, dict(
        zip(names, zip(stated[::2], stated[1::2], strict=True), strict=True)
    )
    for name, lo, hi in zip(names, stated[::2], stated[1::2], strict=True):
        assert ranges[name][0] <= lo < hi <= ranges[name][1], name


def test_the_grip_populations_stated_range_is_the_one_it_draws() -> None:
    from deformctl import population as pop

    stated = _stated(
        "docs/explanation/model.md",
        rf"W {RANGE} N and D {RANGE} N/cm log-uniform .*?λ with \(λ \+ ([\d.]+)\) log-uniform on "
        rf"{RANGE} N·s/cm, μ uniform on {RANGE},",
    )
    assert stated == [
        *pop.GRIP_WEIGHT_N,
        *pop.GRIP_DEFORMABILITY_N_PER_CM,
        pop.GRIP_DAMPING_SHIFT_NS_PER_CM,
        *pop.GRIP_DAMPING_NS_PER_CM,
        *pop.GRIP_FRICTION_MU,
    ]


def test_the_output_comparison_catches_stale_numbers_and_lines() -> None:
    shown = "object  D (N/cm)  samples\nfoam    19.975 ± 0.023  957\ndone in … s"
    now = "object D (N/cm) samples\nfoam 19.971 ± 0.024 957\n\ndone in 3.2 s\n"
    assert docs_output.mismatch(shown, now, 0.02) is None
    assert "957 shown, 1000 printed" in str(
        docs_output.mismatch(shown, now.replace("957", "1000"), 0.02)
    )
    assert "0.0031 shown" in str(docs_output.mismatch("rate 0.0031", "rate 0.00085", 0.02))
    assert "line 1 differs" in str(docs_output.mismatch("a b", "a b c", 0.02))
    assert "1 line(s) shown, 2 printed" in str(docs_output.mismatch("a", "a\nb", 0.02))
    assert docs_output.mismatch("x 0.002", "x 0.003", 0.02) is None  # one unit of the last digit
    assert docs_output.mismatch("x 0.002", "x 0.004", 0.02) is not None


def test_each_command_of_a_block_is_told_apart() -> None:
    proc = subprocess.run(
        [
            "bash",
            "-e",
            "-c",
            docs_output.TRAP + 'echo one\necho two >&2\nfalse || echo "exit $?"\n',
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        check=True,
    )
    parts = dict(docs_output.split_by_command(proc.stdout))
    assert parts["echo one"].strip() == "one"
    assert parts["echo two 1>&2"].strip() == "two"  # as bash names it
    assert parts['echo "exit $?"'].strip() == "exit 1"


def test_api_reference_is_current() -> None:
    pytest.importorskip("pdoc")  # a development dependency (pyproject.toml's dev extra)
    proc = subprocess.run(
        [sys.executable, "-m", "deformctl.cli.api_reference", "--check", "docs/reference/api.md"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr


def test_api_reference_covers_every_exported_name_and_catches_a_stale_file(
    tmp_path: Path,
) -> None:
    pytest.importorskip("pdoc")
    import deformctl
    from deformctl.cli import api_reference as apidoc

    text = (REPO / "docs" / "reference" / "api.md").read_text(encoding="utf-8")
    for name in set(deformctl.__all__) - {"__version__"}:
        assert f"## `deformctl.{name}`" in text, name
    assert "def read_recording(" in text
    stale = tmp_path / "api.md"
    stale.write_text(text.replace("BagSource", "BagSauce", 1), encoding="utf-8")
    assert apidoc.main(["--check", str(stale)]) == 1


def _defined_names() -> set[str]:
    """Every module, class, function, method and module-level name defined in deformctl/."""
    names: set[str] = set()
    for path in (REPO / "deformctl").rglob("*.py"):
        names.update(path.relative_to(REPO).with_suffix("").parts)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.ClassDef):
                names.add(node.name)
            elif isinstance(node, ast.Assign | ast.AnnAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names.update(t.id for t in targets if isinstance(t, ast.Name))
    return names


def _resolve(dotted: str) -> object:
    """The object ``dotted`` names: its longest importable module prefix, then attributes."""
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            value: object = importlib.import_module(".".join(parts[:k]))
        except ModuleNotFoundError:
            continue
        for part in parts[k:]:
            value = getattr(value, part)
        return value
    raise ModuleNotFoundError(dotted)


def test_development_md_names_only_what_exists() -> None:
    import deformctl

    text = (REPO / "docs" / "development.md").read_text(encoding="utf-8")
    top = {p.stem for p in (REPO / "deformctl").iterdir() if p.suffix == ".py" or p.is_dir()}
    defined = _defined_names()
    missing = []
    # words in backquotes that are not deformctl's: the extras' name, a placeholder, typing's flag
    # and the test markers pyproject.toml declares
    markers = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["tool"][
        "pytest"
    ]["ini_options"]["markers"]
    others = {"dev", "COMMAND", "TYPE_CHECKING", *(m.split(":")[0].strip() for m in markers)}
    for token in sorted(set(re.findall(r"`([A-Za-z_][\w.]*)(?:\(\))?`", text)) - others):
        if token.endswith(".py"):
            continue  # a file: checked below
        head = token.split(".")[0]
        if head == "deformctl" and token != "deformctl.datasets":  # datasets is package data
            try:
                _resolve(token)
            except (ImportError, AttributeError):
                missing.append(token)
        elif "." in token and head in top:
            try:
                _resolve(f"deformctl.{token}")
            except (ImportError, AttributeError):
                missing.append(token)
        elif "." not in token and token not in defined:
            missing.append(token)
    for path in re.findall(r"`((?:deformctl|tests|cli|datasets)/[\w/.]+|[\w/]+\.py)`", text):
        where = [REPO / path, REPO / "deformctl" / path]
        if not any(p.exists() for p in where) and not list(REPO.glob(f"deformctl/**/{path}")):
            missing.append(path)
    # the library calls listed for ``import deformctl`` are the ones it exports
    calls = text.split("- `deformctl/__init__.py`:", 1)[1].split("\n- ", 1)[0]
    for name in re.findall(r"`([A-Za-z_]\w*)`", calls):
        if name not in deformctl.__all__:
            missing.append(f"deformctl.{name}")
    assert not missing, f"docs/development.md names what does not exist: {missing}"
