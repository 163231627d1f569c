"""Shared pytest hooks. Keep additions here small and independent of each other."""

from __future__ import annotations

import os
from pathlib import Path

from hypothesis import settings

# --- kinds: a test's folder is its marker -------------------------------------------------
# tests/unit, tests/property, tests/regression and tests/integration hold the tests of each
# kind; every test is marked with its folder's name, so ``pytest -m unit`` or
# ``pytest -m "not integration"`` picks by kind (the markers are declared in pyproject.toml).
TESTS = Path(__file__).resolve().parent
KINDS = ("unit", "property", "regression", "integration")


def pytest_collection_modifyitems(items):
    for item in items:
        path = Path(item.path).resolve()
        folder = path.relative_to(TESTS).parts[0] if path.is_relative_to(TESTS) else None
        if folder in KINDS:
            item.add_marker(folder)


# --- fuzzing: the same draws on every run of the suite -----------------------------------
# Under ``make test`` (and CI) hypothesis draws the same cases every time, so that a run
# fails only for a change in the code; a long run (``CHAINRUN_FUZZ_EXAMPLES``, the guide's
# Accuracy section) draws new ones, to explore. The fuzzers' own ``settings(...)`` take
# every option they do not name from the profile loaded here.
settings.register_profile("suite", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("explore" if os.environ.get("CHAINRUN_FUZZ_EXAMPLES") else "suite")


# --- fuzzing: report the number of cases tried (tests/property/test_fuzz.py) --------------
# A fuzz test records ``record_property("fuzz_cases", n)``; the property travels with its
# report (also from pytest-xdist workers) and is summed here, after the run.


# A test may add ``record_property("fuzz_detail", text)``: what became of its cases.


def pytest_terminal_summary(terminalreporter):
    counts: dict[str, int] = {}
    details: dict[str, str] = {}
    for outcome in ("passed", "failed"):
        for report in terminalreporter.stats.get(outcome, []):
            for name, value in getattr(report, "user_properties", ()):
                if name == "fuzz_cases":
                    counts[report.nodeid.split("::")[-1]] = int(value)
                elif name == "fuzz_detail":
                    details[report.nodeid.split("::")[-1]] = str(value)
    if counts:
        parts = ", ".join(f"{name} {n}" for name, n in sorted(counts.items()))
        terminalreporter.write_line(f"fuzz: {sum(counts.values())} cases tried ({parts})")
    for name, text in sorted(details.items()):
        terminalreporter.write_line(f"fuzz: {name}: {text}")
