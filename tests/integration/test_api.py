"""chainrun from Python: ``chainrun.simulate`` and ``chainrun.open_run`` give the run as
an xarray Dataset, the same as the command's run file holds."""

from __future__ import annotations

import subprocess
import sys

import h5py
import numpy as np
import pytest
import xarray as xr
from helpers import simulate_text

import chainrun
from chainrun.errors import ConfigError

CRADLE = """name = "cradle"
[chain]
n = 5
k = 1
alpha = 1.5
[output]
times = {start = 0, stop = 10, step = 0.5}
"""
TABLES = {"chain": {"n": 5, "k": 1, "alpha": 1.5},
          "output": {"times": {"start": 0, "stop": 10, "step": 0.5}}}
#: attributes that differ between two computations of the same run, or with the text
VARYING = ("created", "diagnostics_wall_time", "config")


def _same(a: xr.Dataset, b: xr.Dataset):
    a, b = a.copy(), b.copy()
    for key in VARYING:
        a.attrs.pop(key, None)
        b.attrs.pop(key, None)
    xr.testing.assert_identical(a, b)


@pytest.fixture(scope="module")
def cradle_file(tmp_path_factory):
    out = simulate_text(tmp_path_factory.mktemp("api"), CRADLE, "cradle")
    return out.parent / "cradle.toml", out / "run.h5"


def test_open_run_reads_the_file(cradle_file):
    _, path = cradle_file
    ds = chainrun.open_run(path)
    with h5py.File(path) as f:
        x = f["particles/chain/position/value"][:, :, 0]
        v = f["results/final_velocity"][()]
        t = f["events/time"][()]
    assert dict(ds.sizes) == {"time": 21, "ball": 5, "event": t.size}
    np.testing.assert_array_equal(ds.position.values, x)
    np.testing.assert_array_equal(ds.final_velocity.values, v)
    np.testing.assert_array_equal(ds.event_time.values, t)
    assert list(ds.ball.values) == [1, 2, 3, 4, 5]
    assert ds.attrs["n"] == 5 and ds.attrs["outcome"] == "terminal"
    assert "paper units" in ds.velocity.attrs["units"]
    # Table 1 of the paper, K = 1: the last ball leaves at 0.9888
    assert ds.final_velocity.sel(ball=5).item() == pytest.approx(0.9888, abs=5e-5)


def test_simulate_gives_what_the_command_wrote(cradle_file):
    config, path = cradle_file
    written = chainrun.open_run(path)
    _same(chainrun.simulate(config), written)
    _same(chainrun.simulate({"name": "cradle", **TABLES}), written)
    _same(chainrun.simulate(name="cradle", **TABLES), written)
    _same(chainrun.simulate({"name": "cradle", "chain": TABLES["chain"]},
                            output=TABLES["output"]), written)


def test_a_sweep_is_a_tree_of_runs():
    tree = chainrun.simulate(chain={"n": 5, "alpha": 1.5}, sweep={"chain.k": [1, 2, 3]})
    assert isinstance(tree, xr.DataTree)
    assert list(tree.children) == ["k=1", "k=2", "k=3"]
    for k in (1, 2, 3):
        ds = tree[f"k={k}"].to_dataset()
        assert ds.attrs["k"] == k
        # momentum K is shared out among the balls at the end
        assert ds.final_velocity.sum().item() == pytest.approx(k, abs=1e-12)


def test_bad_input_is_a_config_error_naming_the_key(tmp_path):
    with pytest.raises(ConfigError, match=r"chain\.n"):
        chainrun.simulate(chain={"n": 0, "k": 1})
    with pytest.raises(ConfigError, match="expected a path or a dict"):
        chainrun.simulate(42)
    config = tmp_path / "c.toml"
    config.write_text(CRADLE)
    with pytest.raises(ConfigError, match="keyword tables"):
        chainrun.simulate(config, chain={"n": 3})


def test_import_chainrun_is_light():
    code = "import sys, chainrun; print('xarray' in sys.modules, 'numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "False"]
