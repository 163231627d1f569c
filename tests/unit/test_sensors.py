"""Force sensors: the contact forces on chosen balls, sampled exactly on a uniform grid."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import simulate_text

import chainrun
from chainrun.analysis import derived
from chainrun.config import parse_experiment
from chainrun.errors import ConfigError
from chainrun.solver import simulate
from chainrun.solver.physics import contact_forces
from chainrun.store import read_run


@pytest.mark.parametrize(("alpha", "k"), [(1.5, 1), (1.0, 3), (2.3, 2)])
def test_samples_are_the_forces_of_snapshots_at_the_same_times(alpha, k):
    """A sample taken alone (the kernel evaluates only the sensor's neighbours) equals
    the force computed from a full snapshot at that time, bitwise: both come from the
    step that contains the instant."""
    n, dt = 30, 0.25
    sol = simulate(n, k, alpha, sensors=[1, 12, n], sensor_dt=dt)
    assert sol.sensor_time[0] == 0.0 and sol.sensor_time[-1] <= sol.end_time
    assert sol.end_time - sol.sensor_time[-1] < dt
    np.testing.assert_array_equal(sol.sensor_time, dt * np.arange(sol.sensor_time.size))
    snap = simulate(n, k, alpha, sol.sensor_time)
    np.testing.assert_array_equal(snap.final_velocity, sol.final_velocity)
    forces = contact_forces(snap.positions, alpha)              # (M, n - 1)
    np.testing.assert_array_equal(sol.sensor_force[:, 1, 0], forces[:, 10])
    np.testing.assert_array_equal(sol.sensor_force[:, 1, 1], forces[:, 11])
    np.testing.assert_array_equal(sol.sensor_force[:, 0, 0], 0.0)   # ball 1: no left contact
    np.testing.assert_array_equal(sol.sensor_force[:, 0, 1], forces[:, 0])
    np.testing.assert_array_equal(sol.sensor_force[:, 2, 1], 0.0)   # last ball: no right one


def test_a_sensor_records_the_solitary_waves_peak_force(tmp_path):
    """Deep in a Hertz line struck by one ball the solitary wave is steady: the sensor's
    peak contact force is the paper's 0.640 (section 5a) and the one chainrun measures
    from the wave's snapshots."""
    out = simulate_text(tmp_path, """name = "wave"
[chain]
n = 100
k = 1
alpha = 1.5
[output]
times = {start = 0, stop = 110, step = 0.1}
sensors = [50]
sensor_dt = 0.005
""")  # as configs/sec5a-solitary-wave.toml, with a sensor
    run = read_run(out / "run.h5")
    peak = run.sensor_force[:, 0, :].max()
    assert peak == pytest.approx(0.640, abs=5e-4)
    wave = derived.solitary_wave(run, (40.0, 80.0), (30, 80))
    assert peak == pytest.approx(wave.max_force, rel=1e-4)
    ds = chainrun.open_run(out / "run.h5")
    assert list(ds.sensor.values) == [50] and ds.sizes["sample"] == run.sensor_time.size
    np.testing.assert_array_equal(ds.sensor_mean_force.values, run.sensor_force.mean(axis=2))


def test_sensor_keys_are_checked_with_the_key_named():
    base = 'name = "x"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n[output]\n'
    cases = {
        "sensors = [2, 6]\nsensor_dt = 0.1": "output.sensors: ball 6 (position 1) is beyond chain.n (5)",
        "sensors = [2, 2]\nsensor_dt = 0.1": "output.sensors: ball 2 is listed twice (position 1)",
        "sensors = [0]\nsensor_dt = 0.1": "output.sensors: must be a ball number >= 1",
        "sensors = [2]": "output.sensor_dt: required with output.sensors",
        "sensor_dt = 0.1": "output.sensor_dt: given without output.sensors",
        "sensors = [2]\nsensor_dt = 0": "output.sensor_dt:",
    }
    for text, message in cases.items():
        with pytest.raises(ConfigError) as exc:
            parse_experiment(base + text, "toml").runs()
        assert message in str(exc.value), text
    (spec,) = parse_experiment(base + "sensors = [2, 5]\nsensor_dt = 0.1", "toml").runs()
    assert (spec.sensors, spec.sensor_dt) == ((2, 5), 0.1)
    with pytest.raises(ValueError, match="sensor_dt"):
        simulate(5, 1, 1.5, sensors=[2])
