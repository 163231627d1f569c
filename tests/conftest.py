"""Shared pytest hooks. Keep additions here small and independent of each other."""

from __future__ import annotations


# --- fuzzing: report the number of cases tried (tests/test_fuzz.py) -----------------------
# A fuzz test records ``record_property("fuzz_cases", n)``; the property travels with its
# report (also from pytest-xdist workers) and is summed here, after the run.


def pytest_terminal_summary(terminalreporter):
    counts: dict[str, int] = {}
    for outcome in ("passed", "failed"):
        for report in terminalreporter.stats.get(outcome, []):
            for name, value in getattr(report, "user_properties", ()):
                if name == "fuzz_cases":
                    counts[report.nodeid.split("::")[-1]] = int(value)
    if counts:
        parts = ", ".join(f"{name} {n}" for name, n in sorted(counts.items()))
        terminalreporter.write_line(f"fuzz: {sum(counts.values())} cases tried ({parts})")
