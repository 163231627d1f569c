"""Pulse measurements against the solitary wave of a Hertz chain struck by one ball.

The paper (section 5a) prints the wave's speed 0.841 and peak contact force 0.640 in its
units; an independent integration here (scipy's DOP853 on the paper's equations, with
no chainrun code, the peaks and crossings found on its dense output) gives each number
to more digits. A uniform steel chain in SI gives the same through the paper's scales,
computed here from the material constants.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import pytest
import xarray as xr
from scipy import integrate, optimize

import chainrun
from chainrun.analysis.pulse import measure_pulses
from chainrun.config import load_experiment
from chainrun.runner import run_file, simulate_run
from chainrun.store import read_run
from closed_forms import STEEL, steel_bead

SENSORS = [20, 25, 30, 35, 40, 45, 50]
N, T_END, DT = 60, 75.0, 0.01


def _simulate(tmp_path, text: str):
    """The run file of a one-run experiment given as TOML text."""
    path = tmp_path / "experiment.toml"
    path.write_text('name = "pulse"\n' + text)
    (spec,) = load_experiment(path).runs()
    summary = simulate_run(spec, tmp_path)
    assert summary.ok, summary.message
    return run_file(tmp_path, spec)


def _paper_line(tmp_path, n=N, t_end=T_END, sensors=SENSORS, extra=""):
    return _simulate(tmp_path, f"""
[chain]
n = {n}
k = 1
alpha = 1.5
{extra}
[output]
sensors = {sensors}
sensor_dt = {DT}
[solver]
t_end = {t_end}
""")


@cache
def _reference():
    """The same line by scipy alone: per sensor ball b, of the contact between balls b
    and b + 1 (the one the wave leaves through), the peak force and its time (the
    maximum of the dense output), the FWHM and the arrival at 0.1 of the peak (roots of
    the dense output); the peak of the ball's mean force; the speed, the slope of the
    contacts' places (b + 1/2) against their peak times."""
    def rhs(_, y):
        x, v = y[:N], y[N:]
        f = np.maximum(x[:-1] - x[1:], 0.0) ** 1.5
        a = np.zeros(N)
        a[:-1] -= f
        a[1:] += f
        return np.concatenate([v, a])

    y0 = np.zeros(2 * N)
    y0[N] = 1.0
    sol = integrate.solve_ivp(rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-12,
                              atol=1e-14, dense_output=True)
    grid = np.arange(0.0, T_END, DT)
    x = sol.sol(grid)[:N]

    def contact(j):            # the force of contact j, between balls j and j + 1
        return lambda t: max(float(sol.sol(t)[j - 1] - sol.sol(t)[j]), 0.0) ** 1.5

    out = {key: [] for key in ("peak", "time", "width", "arrival", "mean")}
    for b in SENSORS:
        f = contact(b)
        mean = lambda t, f0=contact(b - 1), f1=f: 0.5 * (f0(t) + f1(t))  # noqa: E731
        on_grid = np.maximum(x[b - 2:b] - x[b - 1:b + 1], 0.0) ** 1.5  # contacts b - 1, b
        for name, g, samples in (("peak", f, on_grid[1]), ("mean", mean, on_grid.mean(0))):
            i = int(np.argmax(samples))
            best = optimize.minimize_scalar(lambda t: -g(t), bounds=(grid[i - 1], grid[i + 1]),
                                            method="bounded", options={"xatol": 1e-12})
            out[name].append(-best.fun)
            if name == "peak":
                tp, fp = best.x, -best.fun
        out["time"].append(tp)
        half = [optimize.brentq(lambda t: f(t) - 0.5 * fp, a, b_)
                for a, b_ in ((tp - 3.0, tp), (tp, tp + 3.0))]
        out["width"].append(half[1] - half[0])
        out["arrival"].append(optimize.brentq(lambda t: f(t) - 0.1 * fp, tp - 3.0, tp))
    out = {k: np.array(v) for k, v in out.items()}
    out["speed"] = np.polyfit(out["time"], np.array(SENSORS) + 0.5, 1)[0]
    return out


def test_solitary_wave_in_the_papers_units(tmp_path):
    """Balls 20-50 of a 60-ball line struck by one ball: peak contact force 0.6396 and
    speed 0.841 (the paper's digits), and every number as the independent integration
    gives it."""
    p = measure_pulses(_paper_line(tmp_path))
    ref = _reference()
    assert np.all(np.abs(p.peak_force - 0.6396) <= 5e-5)      # 0.6396 to its 4 digits
    assert abs(p.speed.value - 0.841) <= 5e-4                 # the paper's 0.841
    np.testing.assert_array_equal(p.side, 1)
    np.testing.assert_allclose(p.peak_force, ref["peak"], atol=1e-8)
    np.testing.assert_allclose(p.peak_time, ref["time"], atol=1e-6)
    # crossings interpolated linearly between samples 0.01 apart: up to 3e-5 off
    np.testing.assert_allclose(p.width, ref["width"], atol=5e-5)
    np.testing.assert_allclose(p.arrival_time, ref["arrival"], atol=5e-5)
    np.testing.assert_allclose(p.peak_mean_force, ref["mean"], atol=1e-8)
    assert p.speed.value == pytest.approx(ref["speed"], rel=1e-7)
    assert p.speed.error < 1e-6 and p.speed.points == len(SENSORS)   # a steady wave


def test_solitary_wave_in_si_through_the_scaling(tmp_path):
    """Steel beads of 25.4 mm struck at 0.5 m/s: the same wave in N, s and m/s, by the
    paper's scales: time (m^2/(k^2 V))^(1/5), force k^(2/5) m^(3/5) V^(6/5)."""
    m, k = steel_bead()
    V, d = 0.5, STEEL["d"]
    T = (m**2 / (k**2 * V)) ** 0.2
    F = k**0.4 * m**0.6 * V**1.2
    path = _simulate(tmp_path, f"""
units = "si"
[chain]
n = {N}
k = 1
speed = {V}
diameter = {d}
young = {STEEL["E"]}
poisson = {STEEL["nu"]}
density = {STEEL["rho"]}
[output]
sensors = {SENSORS}
sensor_dt = {DT * T!r}
[solver]
t_end = {T_END * T!r}
""")
    p = measure_pulses(read_run(path))
    ref = _reference()
    assert p.units == "si"
    assert np.all(np.abs(p.peak_force / F - 0.6396) <= 5e-5)
    assert abs(p.speed_si.value / (d / T) - 0.841) <= 5e-4
    np.testing.assert_allclose(p.peak_force / F, ref["peak"], atol=1e-8)
    np.testing.assert_allclose(p.peak_time / T, ref["time"], atol=1e-6)
    np.testing.assert_allclose(p.width / T, ref["width"], atol=5e-5)
    np.testing.assert_allclose(p.arrival_time / T, ref["arrival"], atol=5e-5)
    np.testing.assert_allclose(p.peak_mean_force / F, ref["mean"], atol=1e-8)
    assert p.speed.value * T == pytest.approx(ref["speed"], rel=1e-7)       # balls/s
    assert p.speed_si.value == pytest.approx(ref["speed"] * d / T, rel=1e-7)  # m/s
    assert p.speed_si.error < 1e-6 * p.speed_si.value

    ds = chainrun.pulses(path)
    assert list(ds.sensor.values) == SENSORS
    units = {name: ds[name].attrs["units"] for name in ds.data_vars
             if name not in ("side", "on_wall")}
    assert units == {"peak_force": "N", "peak_mean_force": "N", "peak_time": "s",
                     "width": "s", "arrival_time": "s", "wave_speed": "ball/s",
                     "wave_speed_error": "ball/s", "wave_speed_si": "m/s",
                     "wave_speed_si_error": "m/s"}
    assert all(ds[name].attrs["long_name"] for name in ds.data_vars)
    np.testing.assert_array_equal(ds.peak_force.values, p.peak_force)
    assert ds.wave_speed_si.item() == p.speed_si.value
    # the run's Dataset holds what the file does: the same measurements
    xr.testing.assert_identical(chainrun.pulses(chainrun.open_run(path)), ds)


def test_the_first_of_two_pulses_is_measured(tmp_path):
    """On a 40-ball line against a wall the wave comes back through balls 20 and 30 about
    as strong: the first pulse is the same as on the 60-ball line without a wall."""
    p = measure_pulses(_paper_line(tmp_path, n=40, t_end=100.0, sensors=[20, 30],
                                   extra="[walls.right]\nstiffness = 1.0"))
    ref = _reference()
    np.testing.assert_allclose(p.peak_time, ref["time"][[0, 2]], atol=1e-6)
    np.testing.assert_allclose(p.peak_force, ref["peak"][[0, 2]], atol=1e-8)
    np.testing.assert_allclose(p.width, ref["width"][[0, 2]], atol=5e-5)


def test_sensors_the_wave_does_not_reach_and_no_sensors(tmp_path):
    """Stopped at t = 30: ball 30's pulse is cut off before its peak and ball 50's never
    comes (NaN, and no speed from one sensor); a run without sensors is an error."""
    path = _paper_line(tmp_path, t_end=30.0, sensors=[20, 30, 50])
    ds = chainrun.pulses(path)
    ref = _reference()
    assert ds.peak_force.sel(sensor=20).item() == pytest.approx(ref["peak"][0], abs=1e-8)
    for name in ("peak_force", "peak_time", "width", "arrival_time", "peak_mean_force"):
        assert np.isnan(ds[name].sel(sensor=[30, 50]).values).all()
    assert math.isnan(ds.wave_speed.item()) and math.isnan(ds.wave_speed_error.item())
    assert "wave_speed_si" not in ds
    xr.testing.assert_identical(chainrun.pulses(chainrun.open_run(path)), ds)
    (tmp_path / "bare").mkdir()
    bare = _simulate(tmp_path / "bare", "[chain]\nn = 5\nk = 1\nalpha = 1.5\n")
    for run in (bare, chainrun.open_run(bare)):
        with pytest.raises(chainrun.errors.ChainrunError, match="no force sensors"):
            chainrun.pulses(run)
