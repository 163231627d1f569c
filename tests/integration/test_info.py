"""``chainrun info``: the summary of a run file or an output folder, checked against the
file's own arrays read with h5py and against conservation of energy."""

from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from chainrun.cli import main

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


@pytest.fixture(scope="module")
def table1(tmp_path_factory):
    """Table 1's four runs (N = 5, K = 1..4, Hertz) in an output folder."""
    out = tmp_path_factory.mktemp("info") / "table1"
    result = CliRunner().invoke(main, ["simulate", str(CONFIGS / "table1.toml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


def info(*args):
    return CliRunner().invoke(main, ["info", *map(str, args)])


def field(text: str, label: str) -> str:
    return next(line for line in text.splitlines() if line.startswith(label))


def test_a_run_file_is_summarised_from_its_own_arrays(table1):
    path = table1 / "k=2.h5"
    with h5py.File(path) as f:
        v = f["results/final_velocity"][()]
        kinds = f["events/kind"][()]
        end = f["results"].attrs["end_time"]
    result = info(path)
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "N = 5 balls, the first K = 2" in field(out, "model")
    assert "Hertz" in field(out, "model")
    assert f"terminal state at t = {end:.6g}" in field(out, "outcome")
    assert field(out, "cost").startswith(f"cost      {kinds.size} events")
    balls = field(out, "balls")
    assert f"ball {np.argmax(v) + 1} at {v.max():.6g}" in balls
    assert f"ball {np.argmin(v) + 1} at {v.min():.6g}" in balls
    counts = re.search(r"(\d+) rebound .* (\d+) ejected .* (\d+) left behind", out)
    assert [int(c) for c in counts.groups()] == [
        int(np.sum(v < 0)), int(np.sum(v > 0.01)), int(np.sum((v >= 0) & (v <= 0.01)))]


def test_the_energy_shares_account_for_the_whole_impact_energy(table1):
    """At the terminal state every contact is open: the kinetic shares of the rebounding,
    ejected and left-behind balls add up to the impact energy, to the run's accuracy."""
    for k in range(1, 5):
        out = info(table1 / f"k={k}.h5").stdout
        shares = [float(x) for x in re.findall(r"([\d.]+)%", field(out, "energy"))]
        assert len(shares) == 4 and shares[3] == 0.0
        assert sum(shares) == pytest.approx(100.0, abs=0.02)


def test_an_output_folder_has_a_line_per_run(table1):
    result = info(table1)
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].endswith(": 4 runs")
    rows = [line.split() for line in lines[2:]]
    assert [r[0] for r in rows] == [f"k={k}.h5" for k in range(1, 5)]
    for k, row in enumerate(rows, start=1):
        with h5py.File(table1 / f"k={k}.h5") as f:
            v = f["results/final_velocity"][()]
        assert (int(row[1]), int(row[2]), row[4]) == (5, k, "terminal")
        assert float(row[-2]) == pytest.approx(v.max(), rel=1e-5)
        assert float(row[-1]) == pytest.approx(v.min(), rel=1e-5)


def test_what_is_not_a_run_is_refused_in_one_line(tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"not hdf5 at all")
    for path in (bad, tmp_path):
        result = info(path)
        assert result.exit_code == 2
        assert result.stderr.startswith("chainrun: error: ")
        assert len(result.stderr.strip().splitlines()) == 1
        assert "Traceback" not in result.output
    assert info(tmp_path / "missing.h5").exit_code == 2
