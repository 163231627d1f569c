"""Shared pytest hooks. Keep additions here small and independent of each other."""

from __future__ import annotations

from pathlib import Path

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
