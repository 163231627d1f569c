"""Force sensors: the contact forces on chosen balls, sampled exactly on a uniform grid."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import simulate_text

import chainrun
from chainrun.analysis import derived
from chainrun.config import parse_experiment
from chainrun.errors import ConfigError
from chainrun.solver import Line, simulate
from chainrun.solver.result import last_sample, sample_times
from chainrun.solver.physics import line_contact_forces
from chainrun.store import read_run


@pytest.mark.parametrize(("alpha", "k"), [(1.5, 1), (1.0, 3), (2.3, 2)])
def test_samples_are_the_forces_of_snapshots_at_the_same_times(alpha, k):
    """A sample taken alone (the kernel evaluates only the sensor's neighbours) equals
    the force computed from a full snapshot at that time, bitwise: both come from the
    step that contains the instant."""
    n, dt = 30, 0.25
    sol = simulate(Line.paper(n, k, alpha), sensors=[1, 12, n], sensor_dt=dt)
    assert sol.sensor_time[0] == 0.0 and sol.sensor_time[-1] <= sol.end_time
    assert sol.end_time - sol.sensor_time[-1] < dt
    np.testing.assert_array_equal(sol.sensor_time, dt * np.arange(sol.sensor_time.size))
    snap = simulate(Line.paper(n, k, alpha), sol.sensor_time)
    np.testing.assert_array_equal(snap.final_velocity, sol.final_velocity)
    forces = line_contact_forces(snap.positions, snap.line)     # (M, n - 1)
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
    (spec,) = parse_experiment(base + "sensors = [2, 5]\nsensor_dt = 0.1\nsensor_end = 3.0",
                               "toml").runs()
    assert (spec.sensors, spec.sensor_dt, spec.sensor_end) == ((2, 5), 0.1, 3.0)
    assert spec.sensor_samples == 31 * 2  # t = 0, 0.1, ..., 3.0 on two balls
    with pytest.raises(ValueError, match="sensor_dt"):
        simulate(Line.paper(5, 1, 1.5), sensors=[2])


def test_sensors_stop_where_the_file_says_and_are_counted_before_the_run():
    base = 'name = "x"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n[output]\n'
    base += "sensors = [2]\n"
    cases = {  # what the sensors' end is by default, or why there is none
        "sensor_dt = 0.1\n[solver]\nt_end = 4.0": 4.0,
        "sensor_dt = 0.1\ntimes = [0.0, 2.5]": 2.5,
        "sensor_dt = 0.1\ntimes = [0.0, 2.5]\n[solver]\nt_end = 4.0": 4.0,
        "sensor_dt = 0.1\nsensor_end = 1.5\n[solver]\nt_end = 4.0": 1.5,
        "sensor_dt = 0.1": "output.sensor_end: required with output.sensors on a run to "
                           "its terminal state",
        # four sensors at 7.8 million times: refused, naming what to change
        "sensor_dt = 0.01\ntimes = [0.0, 78000.0]\n": None,
        "sensor_dt = 1.0e-6\nsensor_end = 20.0":
            "stop sooner with output.sensor_end",
    }
    many = base.replace("[2]", "[1, 2, 3, 4]") + "sensor_dt = 0.01\ntimes = [0.0, 78000.0]"
    with pytest.raises(ConfigError, match=r"output.sensor_dt: 4 sensors every 0.01 up to "
                                          r"78000 \(output.times\) take 3.12e\+07 samples"):
        parse_experiment(many, "toml")
    for text, want in cases.items():
        if want is None:  # one sensor at those times: within the limit
            parse_experiment(base + text, "toml")
        elif isinstance(want, float):
            (spec,) = parse_experiment(base + text, "toml").runs()
            assert spec.sensor_end == want, text
        else:
            with pytest.raises(ConfigError) as exc:
                parse_experiment(base + text, "toml")
            assert want in str(exc.value), text
            assert len(str(exc.value).splitlines()) == 1
    sol = simulate(Line.paper(5, 1, 1.5), sensors=[2], sensor_dt=0.1, sensor_end=1.55)
    np.testing.assert_allclose(sol.sensor_time, 0.1 * np.arange(16))
    assert sol.end_time > 3.0  # the run goes on; its sensors stopped


@pytest.mark.parametrize(("dt", "end", "last", "whole"), [
    (5e-6, 5e-3, 1000, True),     # 0.005 / 5e-6 is 999.9999999999999 in floating point
    (0.1, 0.3, 3, True),          # 0.3 / 0.1 is 2.9999999999999996
    (0.1, 1.55, 15, False),
    (2e-7, 1.5e-3, 7500, True),
    (0.25, 1.0, 4, True),
])
def test_the_last_sample_is_the_end_where_the_end_is_a_whole_number_of_intervals(
        dt, end, last, whole):
    assert last_sample(dt, end) == (last, whole)
    times = sample_times(dt, end)
    assert times.size == last + 1 and times[0] == 0.0
    assert times[-1] == (end if whole else last * dt)
    np.testing.assert_array_equal(times[:-1], dt * np.arange(last))


def test_every_run_of_a_sweep_samples_at_the_same_times(tmp_path):
    """The sample times are k dt in the file's units, whatever the line's scales: the
    runs of a sweep over the beads' size (each its own time scale) share them to the
    bit, and a run to t_end = 5 ms sampled every 5 us has 1001 samples, the last at
    5 ms."""
    out = simulate_text(tmp_path, """name = "sizes"
units = "si"
[chain]
n = 12
k = 1
speed = 0.5
diameter = 0.01
material = "steel"
[walls.right]
material = "steel"
[output]
sensors = [4, 9]
sensor_dt = 5e-6
[solver]
t_end = 5e-3
[sweep]
"chain.diameter" = [0.01, 0.0127, 0.019, 0.0254]
""")
    runs = [read_run(path) for path in sorted(out.glob("diameter=*.h5"))]
    assert len(runs) == 4
    want = 5e-6 * np.arange(1001)
    want[-1] = 5e-3
    for run in runs:
        np.testing.assert_array_equal(run.sensor_time, want)
    ds = chainrun.open_sweep(out)
    assert ds.sizes["sample"] == 1001
    assert not ds.sensor_force.isnull().any()
    assert ds["chain.diameter"].attrs["units"] == "m"  # the swept key's own unit


@pytest.mark.parametrize("output, expected", [
    ("sensors = [0, 99]\nsensor_dt = 0.1",
     ["output.sensors: must be a ball number >= 1, got 0 at position 0",
      "output.sensors: ball 99 (position 1) is beyond chain.n (5)"]),
    ("sensors = [98, 99]\nsensor_dt = 0.1\nsensor_end = 1.0",
     ["output.sensors: ball 98 (position 0) is beyond chain.n (5)",
      "output.sensors: ball 99 (position 1) is beyond chain.n (5)"]),
    ("sensors = [2, 99]",
     ["output.sensor_dt: required with output.sensors (the sampling interval)",
      "output.sensors: ball 99 (position 1) is beyond chain.n (5)"]),
    ("sensors = [0]",
     ["output.sensors: must be a ball number >= 1, got 0 at position 0",
      "output.sensor_dt: required with output.sensors (the sampling interval)"]),
    ("sensors = ['a', 3, 3, 7]\nsensor_dt = -1",
     ["output.sensors: expected an integer, got 'a' at position 0",
      "output.sensors: ball 3 is listed twice (position 2)",
      "output.sensor_dt: must be > 0, got -1.0",
      "output.sensors: ball 7 (position 3) is beyond chain.n (5)"]),
])
def test_every_problem_of_the_sensors_at_once(output, expected):
    # was: only the first of them (a problem of the list hid the others, and the
    # balls beyond chain.n were checked only once the output table was valid)
    base = 'name = "x"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n[output]\n'
    with pytest.raises(ConfigError) as exc:
        parse_experiment(base + output, "toml")
    assert exc.value.problems == expected


def test_sensors_beyond_n_by_sweep_combination():
    text = ('name = "x"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n[output]\nsensors = [0, 4]\n'
            'sensor_dt = 0.1\n[sweep]\n"chain.n" = [5, 3]\n')
    with pytest.raises(ConfigError) as exc:
        parse_experiment(text, "toml")
    assert exc.value.problems == [
        "output.sensors: must be a ball number >= 1, got 0 at position 0",
        "sweep (n=3): output.sensors: ball 4 (position 1) is beyond chain.n (3)"]
