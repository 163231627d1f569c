"""The same config gives bitwise-identical results: reruns, and any ``--jobs``.

Compared are the arrays (final state, separation, events, snapshots) and every dataset
and attribute of the run and index files, except what records when and how long:
the root ``created`` attribute, ``diagnostics@wall_time`` and the index's
``wall_time`` column. File bytes are not compared: they hold those timestamps.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from chainrun.cli import main
from chainrun.solver import simulate

#: Attributes and datasets that record the time of writing or the cost of a run.
VARYING = {"/@created", "/diagnostics@wall_time", "/table/wall_time"}

SWEEP = """\
name = "same"
[chain]
n = 12
k = 1
alpha = 1.5
[output]
times = {start = 0, stop = 8, step = 0.5}
[sweep]
"chain.k" = [1, 2, 3]
"chain.alpha" = [1.0, 1.5, 2.5]
"""


def same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind == "O" or b.dtype.kind == "O":  # variable-length strings
        return a.shape == b.shape and a.tolist() == b.tolist()
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("n, k, alpha", [(20, 2, 1.5), (10, 1, 1.0), (8, 3, 2.5)])
def test_simulate_twice_is_bitwise_identical(n, k, alpha):
    times = np.linspace(0, 15, 31)
    a = simulate(n, k, alpha, times)
    b = simulate(n, k, alpha, times)
    assert a.outcome == b.outcome and a.end_time == b.end_time and a.message == b.message
    assert len(a.event_time) > 0
    for name in ("final_position", "final_velocity", "separation_time", "separation_velocity",
                 "event_time", "event_contact", "event_kind", "positions", "velocities"):
        assert same_bits(getattr(a, name), getattr(b, name)), name
    da, db = a.diagnostics, b.diagnostics
    assert (da.steps, da.rejected_steps, da.events, da.momentum_error, da.energy_error,
            da.max_window) == (db.steps, db.rejected_steps, db.events, db.momentum_error,
                               db.energy_error, db.max_window)


def contents(path: Path) -> dict[str, object]:
    """Every dataset and attribute of an HDF5 file (links not followed), by path."""
    found: dict[str, object] = {}
    with h5py.File(path, "r") as h5:
        for key, value in h5.attrs.items():
            found[f"/@{key}"] = value

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                found[f"/{name}"] = obj[()]
            for key, value in obj.attrs.items():
                if key not in ("DIMENSION_LIST", "REFERENCE_LIST"):  # object references
                    found[f"/{name}@{key}"] = value

        h5.visititems(visit)
        if "runs" in h5:  # index files: the link targets, not the linked files
            for run_id in h5["runs"]:
                link = h5["runs"].get(run_id, getlink=True)
                found[f"/runs/{run_id}->"] = (link.filename, link.path)
    return found


def assert_same_results(out_a: Path, out_b: Path) -> None:
    names_a = sorted(p.name for p in out_a.iterdir())
    assert names_a == sorted(p.name for p in out_b.iterdir())
    assert "index.h5" in names_a and len(names_a) > 1
    for name in names_a:
        a, b = contents(out_a / name), contents(out_b / name)
        assert sorted(a) == sorted(b), name
        different = [key for key in a if key not in VARYING and not same_bits(a[key], b[key])]
        assert not different, f"{name}: {different}"


def run_cli(config: Path, outdir: Path, *args: str) -> None:
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(outdir), *args])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    assert result.exit_code == 0, result.output


def test_the_command_twice_gives_the_same_files(tmp_path):
    config = tmp_path / "same.toml"
    config.write_text(SWEEP)
    run_cli(config, tmp_path / "a")
    run_cli(config, tmp_path / "b")
    assert_same_results(tmp_path / "a", tmp_path / "b")


def test_any_number_of_jobs_gives_the_same_files(tmp_path):
    config = tmp_path / "same.toml"
    config.write_text(SWEEP.replace('"chain.alpha" = [1.0, 1.5, 2.5]\n', ""))
    run_cli(config, tmp_path / "one", "--jobs", "1")
    run_cli(config, tmp_path / "two", "--jobs", "2")
    assert_same_results(tmp_path / "one", tmp_path / "two")
