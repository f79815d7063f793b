"""A pytest plugin that measures each test's CPU time: ``pytest -p bench.pytest_cpu``.

The CPU time of a test is the user + sys time of its worker process *and* of the child
processes it waited for (``subprocess.run`` of a CLI command, a built wheel, a docs block),
read from ``getrusage`` before and after each phase (setup, call, teardown) of the test. A
session fixture's cost falls on the first test that uses it. Under xdist each worker measures its
own tests and sends the numbers to the controller with the test's report.

At the end of the session the plugin prints the test files and the tests that took the most CPU
time (``--cpu-top N``, default 15) and the sum over all tests; the wall time of the same tests
is printed beside each (it waits for the other jobs of a shared machine, the CPU time does not).
``--cpu-json PATH`` also writes every test's numbers as JSON.
"""

from __future__ import annotations

import json
import resource
from collections import defaultdict
from collections.abc import Generator
from pathlib import Path
from typing import Any

import pytest

_KEY = "cpu_s"


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("cpu", "CPU time per test (bench/pytest_cpu.py)")
    group.addoption("--cpu-top", type=int, default=15, help="files and tests to print")
    group.addoption("--cpu-json", default=None, help="write every test's CPU and wall s here")


class _Recorder:
    def __init__(self, config: pytest.Config) -> None:
        self.config = config
        self.cpu: dict[str, float] = defaultdict(float)
        self.wall: dict[str, float] = defaultdict(float)

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_makereport(
        self, item: pytest.Item, call: pytest.CallInfo[Any]
    ) -> Generator[None, Any, None]:
        outcome = yield
        report = outcome.get_result()
        start = getattr(item, "_cpu_start", None)
        if start is not None:
            report.user_properties.append((_KEY, _cpu() - start))

    @pytest.hookimpl(tryfirst=True)
    def pytest_runtest_setup(self, item: pytest.Item) -> None:
        item._cpu_start = _cpu()  # type: ignore[attr-defined]

    @pytest.hookimpl(tryfirst=True)
    def pytest_runtest_call(self, item: pytest.Item) -> None:
        item._cpu_start = _cpu()  # type: ignore[attr-defined]

    @pytest.hookimpl(tryfirst=True)
    def pytest_runtest_teardown(self, item: pytest.Item) -> None:
        item._cpu_start = _cpu()  # type: ignore[attr-defined]

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        for key, value in report.user_properties:
            if key == _KEY:
                self.cpu[report.nodeid] += float(value)  # type: ignore[arg-type]
        self.wall[report.nodeid] += report.duration

    def pytest_terminal_summary(self, terminalreporter: Any) -> None:
        if not self.cpu:
            return
        top = self.config.getoption("cpu_top")
        files: dict[str, float] = defaultdict(float)
        files_wall: dict[str, float] = defaultdict(float)
        for node, cpu in self.cpu.items():
            files[node.split("::")[0]] += cpu
            files_wall[node.split("::")[0]] += self.wall[node]
        write = terminalreporter.write_line
        terminalreporter.section("CPU time (bench/pytest_cpu.py)")
        write(f"{sum(self.cpu.values()):.1f} s CPU in {len(self.cpu)} tests")
        write(f"top {top} files (CPU s, wall s):")
        for name, cpu in sorted(files.items(), key=lambda kv: -kv[1])[:top]:
            write(f"{cpu:8.1f} {files_wall[name]:8.1f}  {name}")
        write(f"top {top} tests (CPU s, wall s):")
        for node, cpu in sorted(self.cpu.items(), key=lambda kv: -kv[1])[:top]:
            write(f"{cpu:8.1f} {self.wall[node]:8.1f}  {node}")
        path = self.config.getoption("cpu_json")
        if path:
            rows = {n: {"cpu_s": c, "wall_s": self.wall[n]} for n, c in self.cpu.items()}
            Path(path).write_text(json.dumps(rows, indent=1, sort_keys=True) + "\n")


def pytest_configure(config: pytest.Config) -> None:
    config.pluginmanager.register(_Recorder(config), "cpu_recorder")
