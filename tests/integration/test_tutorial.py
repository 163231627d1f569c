"""The tutorial (docs/tutorial.py) runs as written and finds the paper's Table 1."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from helpers import TABLE1

TUTORIAL = Path(__file__).resolve().parents[2] / "docs" / "tutorial.py"


def test_the_tutorial_runs(tmp_path):
    result = subprocess.run([sys.executable, "-W", "error::FutureWarning", str(TUTORIAL),
                             str(tmp_path)], capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    # Table 1 of the paper, K = 1..4, to its printed digits (the tutorial prints 4 decimals)
    table = {line.split()[0]: [float(x) for x in line.split()[1:]]
             for line in lines if line.startswith("k=")}
    assert sorted(table) == ["k=1", "k=2", "k=3", "k=4"]
    for k, column in TABLE1.items():
        for printed, ours in zip(column, table[f"k={k}"]):
            tolerance = 0.5 * 10.0 ** -len(printed.split(".")[1]) + 0.5e-4
            assert ours == pytest.approx(float(printed), abs=tolerance)
    assert sorted(p.name for p in (tmp_path / "figures").iterdir()) == [
        "run-final.pdf", "run-final.png", "run-spacetime.pdf", "run-spacetime.png"]
    # real beads in SI: the mass of an 8 mm sphere of 8000 kg/m^3, and the energy balance
    beads = [line for line in lines if line.startswith("beads:")]
    grams = float(beads[0].split()[1])
    assert grams == pytest.approx(8000 * 3.141592653589793 * 0.008**3 / 6 * 1e3, rel=1e-4)
    assert "kg" in beads[0] and "N m-1.5" in beads[0]  # kappa of a Hertz line, N m^-1.5
    peaks = [float(line.split("peak force ")[1].split()[0]) for line in beads
             if "peak force" in line]
    assert len(peaks) == 2 and peaks[0] > peaks[1] > 0  # the damped wave weakens
    speed = float(next(line for line in beads if "wave runs at" in line).split()[-2])
    assert 300 < speed < 700  # m/s: between the two sensors, 10 diameters of 8 mm apart
    assert float(beads[-1].split("balance to ")[1].split(",")[0]) < 1e-9
    ensemble = [line for line in lines if line.startswith("ensemble")]
    assert ensemble[0].startswith("ensemble: 8 runs")
    assert "ensemble.png" in ensemble[1] and "sweep-runs.png" in ensemble[1]
