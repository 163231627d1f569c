"""chainrun from Python: ``chainrun.simulate`` and ``chainrun.open_run`` give the run as
an xarray Dataset, the same as the command's run file holds."""

from __future__ import annotations

import re
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
    assert dict(ds.sizes) == {"time": 21, "ball": 5, "contact": 4, "wall": 2,
                              "event": t.size}
    np.testing.assert_array_equal(ds.position.values, x)
    np.testing.assert_array_equal(ds.final_velocity.values, v)
    np.testing.assert_array_equal(ds.event_time.values, t)
    assert list(ds.ball.values) == [1, 2, 3, 4, 5]
    assert ds.attrs["n"] == 5 and ds.attrs["outcome"] == "terminal"
    # short, as an axis label takes it; the Dataset says what the paper's units are
    assert ds.velocity.attrs["units"] == ds.final_velocity.attrs["units"] == "paper units"
    assert "striker speed 1" in ds.attrs["units"]
    assert {ds[name].attrs["units"] for name in ("stiffness", "damping", "mass")} == {
        "paper units"}
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


SPEEDS = """name = "speeds"
[chain]
n = 12
k = 1
alpha = 1.5
[output]
times = {start = 0, stop = 20, step = 1}
sensors = [4, 8]
sensor_dt = 0.05
[solver]
t_end = 20.0
[sweep]
"chain.speed" = [0.5, 2.0]
"""


def test_a_sweep_from_python_is_read_along_run_as_the_commands_folder(tmp_path):
    import tomllib

    folder = simulate_text(tmp_path, SPEEDS, "speeds")
    tree = chainrun.simulate(tomllib.loads(SPEEDS))
    along = chainrun.open_sweep(tree)
    _same(along.drop_vars("diagnostics_wall_time"),
          chainrun.open_sweep(folder).drop_vars("diagnostics_wall_time"))
    assert list(along["run"].values) == ["speed=0.5", "speed=2.0"]
    assert list(along["chain.speed"].values) == [0.5, 2.0]
    # every ball starts at rest but the striker, at the swept speed
    np.testing.assert_array_equal(along.initial_velocity.sel(ball=1), [0.5, 2.0])
    p = chainrun.pulses(tree)
    assert list(p["chain.speed"].values) == [0.5, 2.0]
    assert p.peak_force.dims == ("run", "sensor")


def test_every_variable_has_a_short_label_for_plots_and_its_description():
    # xarray's plots label an axis "long_name [units]": a label, not a definition
    tree = chainrun.simulate(chain={"n": 12, "k": 1, "alpha": 1.5},
                             output={"times": {"start": 0, "stop": 20, "step": 1},
                                     "sensors": [4, 8], "sensor_dt": 0.05},
                             solver={"t_end": 20.0}, sweep={"chain.speed": [0.5, 2.0]})
    for ds in (chainrun.open_sweep(tree), chainrun.pulses(tree)):
        for name, var in ds.variables.items():
            label = var.attrs.get("long_name", "")
            assert label and len(label) <= 40 and ":" not in label, (name, label)
    ds = tree["speed=0.5"].to_dataset()
    assert ds.drive_work.attrs["long_name"] == "drive work"
    assert "kinetic + potential + dissipated" in ds.drive_work.attrs["description"]
    assert "NaN" in ds.separation_time.attrs["description"]
    assert ds["sample"].attrs["long_name"] == "sample time"
    assert chainrun.open_sweep(tree)["chain.speed"].attrs["long_name"] == "speed (chain.speed)"


def test_an_si_datasets_attributes_carry_units_and_the_files_conventions():
    """A line of steel beads without walls, to its terminal state: its unset t_end and
    event limit read as in the file (NaN, -1: docs/schema.md), the absent walls'
    coefficients have the contacts' law's unit, the scales have theirs, and the
    pulses' two wave speeds are told apart by their labels."""
    ds = chainrun.simulate(units="si", chain={"n": 30, "k": 1, "speed": 0.1,
                                              "diameter": 0.008, "material": "steel"},
                           output={"sensors": [10, 20], "sensor_dt": 1e-7,
                                   "sensor_end": 6e-4})
    assert np.isnan(ds.attrs["t_end"]) and ds.attrs["max_events"] == -1
    assert ds.wall_stiffness.attrs["units"] == "N m-1.5"
    assert {ds.attrs[f"scales_{k}_unit"] for k in ("mass", "length", "time", "velocity",
                                                  "force")} == {"kg", "m", "s", "m/s", "N"}
    assert re.fullmatch(r"terminal state reached at t = [\d.]+ [mµ]s after \d+ events",
                        ds.attrs["message"])
    p = chainrun.pulses(ds)
    assert p.wave_speed.attrs["units"] == "ball/s" and p.wave_speed_si.attrs["units"] == "m/s"
    assert p.wave_speed.attrs["long_name"] != p.wave_speed_si.attrs["long_name"]


def test_pulses_of_one_sensor_picked_by_sel():
    from chainrun.errors import ChainrunError

    ds = chainrun.simulate(chain={"n": 12, "k": 1, "alpha": 1.5},
                           output={"sensors": [4, 8], "sensor_dt": 0.05},
                           solver={"t_end": 20.0})
    one = chainrun.pulses(ds.sel(sensor=8))
    assert list(one["sensor"].values) == [8]
    # the Hertz solitary wave's peak contact force, the paper's 0.640
    assert one.peak_force.item() == pytest.approx(0.640, abs=2e-3)
    with pytest.raises(ChainrunError, match="side"):
        chainrun.pulses(ds.sel(side="towards ball 1"))


def test_what_the_readers_and_measures_cannot_take_is_a_chainrun_error():
    from chainrun.errors import ChainrunError, StoreError

    ds = chainrun.simulate(chain={"n": 5, "k": 1, "alpha": 1.5})
    spectrum = chainrun.spectrum(chain={"n": 5, "k": 0, "alpha": 1.5, "precompression": 1.0},
                                 walls={"left": {}, "right": {}})
    cases = [
        (lambda: chainrun.open_run(ds), StoreError, "open_run: expected a run file's path, "
                                                    "got Dataset"),
        (lambda: chainrun.open_run(None), StoreError, "got NoneType"),
        (lambda: chainrun.open_sweep(ds), StoreError, "open_sweep: expected an output "
                                                      "folder's path or the DataTree"),
        (lambda: chainrun.open_sweep(chainrun.spectrum(
            chain={"n": 5, "k": 0, "alpha": 1.5, "precompression": 1.0},
            walls={"left": {}, "right": {}}, sweep={"chain.precompression": [1.0, 2.0]})),
         StoreError, "open_sweep: precompression=1.0 is not a run's Dataset"),
        (lambda: chainrun.pulses(ds.velocity), ChainrunError, "pulses: expected a run.*got "
                                                              "DataArray"),
        (lambda: chainrun.pulses({"chain": {}}), ChainrunError, "got dict"),
        (lambda: chainrun.pulses(spectrum), ChainrunError, "got a Dataset, a spectrum's"),
        (lambda: chainrun.transmission(spectrum), ChainrunError, "a spectrum's"),
        (lambda: chainrun.transmission(ds, harmonics="3"), ChainrunError,
         "harmonics: expected a whole number >= 1, got '3'"),
        (lambda: chainrun.transmission(ds, periods=2.5), ChainrunError, "periods: expected"),
        (lambda: chainrun.spectrum(chain={"n": 5, "k": 0, "alpha": 1.5,
                                          "precompression": 1.0},
                                   walls={"left": {}, "right": {}}, period=[2]),
         ChainrunError, r"period: expected a number of balls >= 0, got \[2\]"),
    ]
    for call, kind, message in cases:
        with pytest.raises(kind, match=message):
            call()


def test_bad_input_is_a_config_error_naming_the_key(tmp_path):
    with pytest.raises(ConfigError, match=r"chain\.n"):
        chainrun.simulate(chain={"n": 0, "k": 1})
    with pytest.raises(ConfigError, match="expected a path or a dict"):
        chainrun.simulate(42)
    config = tmp_path / "c.toml"
    config.write_text(CRADLE)
    with pytest.raises(ConfigError, match="keyword tables"):
        chainrun.simulate(config, chain={"n": 3})
    with pytest.raises(ConfigError, match=r"output\.times: cannot use a set"):
        chainrun.simulate(chain=TABLES["chain"], output={"times": {1.0, 2.0}})
    with pytest.raises(ConfigError, match=r"chain\.mass\[2\]: cannot use a complex"):
        chainrun.simulate(chain={**TABLES["chain"], "mass": [1, 1, 1j, 1, 1]})
    ds = chainrun.simulate(chain=TABLES["chain"], output={"times": range(3)})
    assert list(ds.time.values) == [0, 1, 2]
    with pytest.raises(ConfigError, match="check: expected True or False, got 'no'"):
        chainrun.simulate(chain=TABLES["chain"], check="no")
    for call in (chainrun.simulate, chainrun.spectrum):
        with pytest.raises(ConfigError, match="got an xarray Dataset"):
            call(ds)


def test_import_chainrun_is_light():
    code = "import sys, chainrun; print('xarray' in sys.modules, 'numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "False"]


def test_the_dataset_holds_the_whole_line_numbered_one_way(tmp_path):
    """Per ball, per contact and per wall, every number of the line and what it did,
    in SI units; contacts numbered from 1 in the event log as along ``contact``."""
    ds = chainrun.simulate(
        name="dimer", units="si",
        chain={"n": 6, "k": 1, "speed": 0.2, "diameter": [0.01, 0.006] * 3,
               "material": ["steel", "aluminium"] * 3, "restitution": 0.9,
               "damping_law": "tsuji"},
        walls={"right": {"material": "steel", "gap": 1e-6}},
        output={"times": [0.0, 5e-5, 1e-4]})
    rho = {"steel": 7850.0, "aluminium": 2700.0}
    d = np.array([0.01, 0.006] * 3)
    mass = np.array([rho[m] for m in ["steel", "aluminium"] * 3]) * np.pi * d**3 / 6
    np.testing.assert_allclose(ds.mass.values, mass, rtol=1e-14)
    assert ds.mass.attrs["units"] == "kg" and ds.diameter.attrs["units"] == "m"
    np.testing.assert_array_equal(ds.diameter.values, d)
    assert list(ds.material.values) == ["steel", "aluminium"] * 3
    assert list(ds.contact.values) == [1, 2, 3, 4, 5] and ds.stiffness.dims == ("contact",)
    assert np.all(ds.damping.values > 0) and np.all(ds.alpha.values == 1.5)
    assert ds.wall_gap.sel(wall="right").item() == 1e-6
    assert np.isnan(ds.wall_stiffness.sel(wall="left").item())
    assert ds.wall_impulse.attrs["units"] == "kg m/s"
    # the wall's impulse and the line's momentum: P(end) = P(0) + J
    p0 = float(mass @ ds.initial_velocity.values)
    assert float(mass @ ds.final_velocity.values) == pytest.approx(
        p0 + ds.wall_impulse.sum().item(), abs=1e-12 * p0)
    # energy: kinetic + contact + dissipated = initial, with the walls and damping
    total = ds.kinetic_energy + ds.potential_energy + ds.dissipated_energy
    np.testing.assert_allclose(total.values, 0.5 * float(mass @ ds.initial_velocity.values**2),
                               rtol=1e-10)
    assert ds.dissipated_energy.attrs["units"] == "J"
    contacts = set(ds.event_contact.values.tolist())
    assert contacts <= set(range(0, 7)) and 6 in contacts  # 6 = N: the right wall
    assert ds.contact_dissipation.sum().item() + ds.wall_dissipation.sum().item() == \
        pytest.approx(ds.attrs["dissipated_energy"], rel=1e-12)


def test_a_line_at_rest_ends_at_once_and_a_held_line_stays_put():
    # nothing moves, no force acts: the line starts in its terminal state
    ds = chainrun.simulate(chain={"n": 5, "k": 0, "alpha": 1.5})
    assert ds.attrs["outcome"] == "terminal" and ds.attrs["end_time"] == 0.0
    assert not np.any(ds.final_velocity.values)
    # precompressed between two walls: at rest in its static state until t_end
    ds = chainrun.simulate(chain={"n": 6, "k": 0, "alpha": 1.5, "precompression": 2.0},
                           walls={"left": {}, "right": {}}, solver={"t_end": 20.0},
                           output={"times": {"start": 0, "stop": 20, "step": 5}})
    assert ds.attrs["outcome"] == "stop_time"
    x0 = ds.position.isel(time=0)
    # static compression 2^(2/3) per contact, so the balls sit at 1.59 ... 9.52
    np.testing.assert_allclose(x0.values, 2.0 ** (2 / 3) * np.arange(6, 0, -1), rtol=1e-14)
    assert float(abs(ds.position - x0).max()) < 1e-13
    assert float(abs(ds.velocity).max()) < 1e-13
