"""``chainrun analyze --check``: every value's spread against the same analysis of runs
the test makes itself at a tenth of the tolerance, and check runs that are not the
runs' checks refused."""

from __future__ import annotations

import math
import shutil

import pytest

from chainrun import artefacts
from chainrun.analysis import analyze
from chainrun.config import load_experiment, parse_experiment
from chainrun.errors import ChainrunError
from chainrun.runner import simulate_experiment
from chainrun.store import read_analysis

from helpers import ROOT


@pytest.fixture(scope="module")
def checked(tmp_path_factory):
    """Table 1's runs with their check runs, analysed with --check."""
    results = tmp_path_factory.mktemp("results")
    experiment = load_experiment(ROOT / "configs" / "table1.toml")
    simulate_experiment(experiment, artefacts.run_dir("table1", results),
                        check_outdir=artefacts.run_dir("table1", results / "check"))
    return results, read_analysis(analyze("table1", results=results, check=True))


def test_each_value_has_the_spread_of_the_same_recipe_at_a_tenth_of_the_tolerance(
        checked, tmp_path):
    results, data = checked
    text = (ROOT / "configs" / "table1.toml").read_text() + "\n[solver]\nrtol = 1e-13\n"
    tenth = parse_experiment(text, "toml")
    simulate_experiment(tenth, artefacts.run_dir("table1", tmp_path))
    other = read_analysis(analyze("table1", results=tmp_path)).values
    assert data.spreads.keys() == data.values.keys() and data.values.keys() == other.keys()
    for key, value in data.values.items():
        expected = 0.0 if math.isnan(value) and math.isnan(other[key]) \
            else abs(value - other[key])
        assert data.spreads[key] == expected, key
    # a clean line: every velocity of Table 1 holds far beyond its printed digits
    velocities = [k for k in data.values if k.startswith("v_")]
    assert len(velocities) >= 20
    assert max(data.spreads[k] for k in velocities) < 1e-9
    assert any(data.spreads[k] > 0 for k in velocities)   # measured, not assumed
    assert any(row["kind"] == "analysis" and row["name"] == "check/table1"
               for row in data.inputs)


def test_check_runs_of_another_config_are_refused(checked, tmp_path):
    results, _ = checked
    copy = tmp_path / "results"
    shutil.copytree(results / "runs", copy / "runs")
    shutil.copytree(results / "runs", copy / "check" / "runs")   # not the checks
    with pytest.raises(ChainrunError, match="not the check run"):
        analyze("table1", results=copy, check=True)


def test_missing_check_runs_name_the_command_that_makes_them(checked, tmp_path):
    results, _ = checked
    shutil.copytree(results / "runs", tmp_path / "runs")
    with pytest.raises(ChainrunError, match="--check-outdir"):
        analyze("table1", results=tmp_path, check=True)
