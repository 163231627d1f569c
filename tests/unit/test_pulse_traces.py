"""Pulse measurements (``chainrun.analysis.pulse``) on synthetic traces with closed-form
answers: the peak, its time, the FWHM and the arrival of Gaussian and sech^2 pulses,
the first of two pulses, cut-off and missing pulses, the speed fit, and a run's
sensors on a line of unequal spheres with gaps."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import optimize, stats

from chainrun.analysis.pulse import (
    first_pulse,
    measure_pulses,
    parabola_peak,
    wave_speed,
)
from chainrun.errors import ChainrunError
from chainrun.solver import Solution
from chainrun.store import RunData
from chainrun.units import format_measured, format_value

DT = 0.01


def gaussian(t, t0, s, height=1.0, base=0.0):
    return base + height * np.exp(-(((t - t0) / s) ** 2))


def sech2(t, t0, w, height=1.0):
    return height / np.cosh((t - t0) / w) ** 2


def test_parabola_peak_is_exact_on_a_parabola():
    t = np.arange(0.0, 1.0, 0.1)
    y = 3.0 - 2.0 * (t - 0.437) ** 2
    tp, yp = parabola_peak(t, y, 4)
    assert tp == pytest.approx(0.437, abs=1e-12) and yp == pytest.approx(3.0, abs=1e-12)


def test_gaussian_pulse_on_a_baseline():
    """FWHM 2 s sqrt(ln 2); arrival at fraction q: t0 - s sqrt(ln(1/q)); the half and
    the fraction measured from the baseline, the peak including it."""
    t = np.arange(0.0, 10.0, DT)
    t0, s, base = 4.3217, 0.7, 2.5
    p = first_pulse(t, gaussian(t, t0, s, 1.5, base))
    assert p.peak == pytest.approx(base + 1.5, abs=1e-6)
    assert p.peak_time == pytest.approx(t0, abs=1e-6)
    assert p.width == pytest.approx(2 * s * math.sqrt(math.log(2)), abs=1e-4)
    assert p.arrival_time == pytest.approx(t0 - s * math.sqrt(math.log(10)), abs=1e-4)
    q = first_pulse(t, gaussian(t, t0, s, 1.5, base), arrival=0.5)
    assert q.arrival_time == pytest.approx(t0 - s * math.sqrt(math.log(2)), abs=1e-4)


def test_sech2_pulse_and_the_interpolation_converges():
    """sech^2((t - t0)/w): FWHM 2 w arccosh(sqrt 2), arrival at 0.1 at t0 - w
    arccosh(sqrt 10). Linear interpolation of the crossings: the error falls as dt^2."""
    t0, w = 3.21, 0.45
    width = 2 * w * math.acosh(math.sqrt(2))
    arrival = t0 - w * math.acosh(math.sqrt(10))
    errors = []
    for dt in (0.02, 0.01):
        t = np.arange(0.0, 8.0, dt)
        p = first_pulse(t, sech2(t, t0, w, 0.64))
        assert p.peak == pytest.approx(0.64, rel=1e-5)
        assert p.peak_time == pytest.approx(t0, abs=1e-5)
        errors.append((abs(p.width - width), abs(p.arrival_time - arrival)))
    assert errors[1][0] < 2e-4 and errors[1][1] < 2e-4
    assert errors[0][0] / errors[1][0] > 3 and errors[0][1] / errors[1][1] > 3


def test_a_widths_printed_digits_hold_as_the_sampling_is_refined():
    """A sech^2 pulse of 75 N whose FWHM is 26 µs (2 w arccosh(sqrt 2)), sampled every
    0.5 µs and every 0.05 µs: each crossing's error bound holds the closed form, and
    the width is printed to the digits it supports, which a ten times finer sampling
    keeps (five digits at 0.5 µs would print 26.001 µs)."""
    width, t0 = 26e-6, 123.4567e-6
    w = 0.5 * width / math.acosh(math.sqrt(2))
    arrival = t0 - w * math.acosh(math.sqrt(10))
    shown, five = [], []
    for dt in (5e-7, 5e-8):
        t = np.arange(0.0, 300e-6, dt)
        p = first_pulse(t, sech2(t, t0, w, 75.0))
        assert abs(p.width - width) <= p.width_error < 0.01 * dt
        assert abs(p.arrival_time - arrival) <= p.arrival_error < 0.01 * dt
        shown.append(format_measured(p.width, p.width_error, "time", "si"))
        five.append(format_value(p.width, "time", "si", 5, zeros=True))
    assert shown == ["26.00 µs", "26.000 µs"]
    assert five[0] != five[1]    # the fifth digit at 0.5 µs does not hold
    # the coarse digits are the fine value's, rounded
    assert f"{float(shown[1].split()[0]):.2f}" == shown[0].split()[0]


def test_the_first_of_two_pulses_is_measured():
    """A reflected pulse, larger or smaller, comes later; the first is measured while
    the later is under twice as high (then ``detect`` lowers the threshold)."""
    t = np.arange(0.0, 20.0, DT)
    first = sech2(t, 4.567, 0.5)
    for later in (0.5, 1.8):
        p = first_pulse(t, first + sech2(t, 12.0, 0.5, later))
        assert p.peak_time == pytest.approx(4.567, abs=1e-5)
        assert p.peak == pytest.approx(1.0, abs=1e-5)
        assert p.width == pytest.approx(2 * 0.5 * math.acosh(math.sqrt(2)), abs=2e-4)
    hidden = first + sech2(t, 12.0, 0.5, 2.5)
    assert first_pulse(t, hidden).peak_time == pytest.approx(12.0, abs=1e-5)
    assert first_pulse(t, hidden, detect=0.3).peak_time == pytest.approx(4.567, abs=1e-5)


def test_the_first_of_two_pulses_above_a_given_baseline():
    t = np.arange(0.0, 10.0, DT)
    f = 2.0 + gaussian(t, 2.345, 0.3, 3.0) + gaussian(t, 7.0, 0.3, 5.0)
    p = first_pulse(t, f, baseline=2.0)
    assert p.peak_time == pytest.approx(2.345, abs=1e-4) and p.peak == pytest.approx(5.0, abs=1e-3)


def test_cut_off_and_missing_pulses_give_nan():
    t = np.arange(0.0, 5.0, DT)
    # the samples end before the peak: nothing but its onset is known
    rising = first_pulse(t, sech2(t, 6.0, 0.5))
    assert all(math.isnan(x) for x in (rising.peak, rising.peak_time, rising.width,
                                       rising.arrival_time))
    # its onset: where it first rose above half its largest sample
    half = 0.5 * sech2(t[-1], 6.0, 0.5)
    assert rising.onset == pytest.approx(6.0 - 0.5 * math.acosh(math.sqrt(1 / half)), abs=DT)
    # the samples end after the peak, before its half maximum
    falling = first_pulse(t, sech2(t, 4.8, 0.5))
    assert falling.peak_time == pytest.approx(4.8, abs=1e-5) and math.isnan(falling.width)
    assert falling.arrival_time == pytest.approx(4.8 - 0.5 * math.acosh(math.sqrt(10)),
                                                 abs=1e-4)
    # the pulse began before the samples: no rising edge (a baseline given)
    early = first_pulse(t, sech2(t, 0.3, 0.5), baseline=0.0)
    assert early.peak_time == pytest.approx(0.3, abs=1e-5)
    assert math.isnan(early.width) and math.isnan(early.arrival_time)
    # nothing, or less than min_rise, or too few samples: no pulse
    for f, kw in ((np.zeros_like(t), {}), (1e-20 * sech2(t, 2.0, 0.5), {"min_rise": 1e-9}),
                  (np.array([0.0, 1.0]), {})):
        p = first_pulse(t[:f.size], f, **kw)
        assert all(math.isnan(x) for x in dataclasses.astuple(p))


def test_wave_speed_fit():
    t = np.array([1.0, 2.5, 3.0, 4.25, 6.0])
    exact = wave_speed(7.0 + 0.8404 * t, t)
    assert exact.value == pytest.approx(0.8404, rel=1e-14)
    assert exact.error < 1e-14 and exact.points == 5       # no residual
    x = 7.0 + 0.8404 * t + np.array([0.01, -0.02, 0.015, 0.0, -0.005])
    fit, ref = wave_speed(x, t), stats.linregress(t, x)
    assert fit.value == pytest.approx(ref.slope, rel=1e-12)
    assert fit.error == pytest.approx(ref.stderr, rel=1e-10)
    two = wave_speed([20.0, 30.0], [2.0, 4.0])              # no residual to estimate from
    assert two.value == pytest.approx(5.0) and math.isnan(two.error) and two.points == 2
    gaps = wave_speed([20.0, 30.0, 40.0, 50.0], [2.0, np.nan, 6.0, np.nan])
    assert gaps.value == pytest.approx(5.0) and gaps.points == 2
    one = wave_speed([20.0, 30.0], [2.0, np.nan])
    assert math.isnan(one.value) and math.isnan(one.error) and one.points == 1


# ------------------------------------------------------------------- on a run's sensors
def _run(n, sensors, t, force, model=None) -> RunData:
    """A RunData holding only what pulse measurements read."""
    def blank(cls):
        return {f.name: None for f in dataclasses.fields(cls)
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    solution = Solution(**{**blank(Solution), "n": n, "sensor_balls": np.asarray(sensors),
                           "sensor_time": t, "sensor_force": force})
    return RunData(**{**blank(RunData), "solution": solution, "path": Path("synthetic.h5"),
                      "parameters": {"n": n}, "model": model})


def test_run_sensors_on_unequal_spheres_with_gaps():
    """A sech^2 pulse travelling at 30 m/s along 6 spheres of unequal diameters with
    gaps, in each direction: the contact the wave leaves through is measured, and the
    speed in m/s is found from the places of the contacts (middles of the gaps),
    computed here by walking along the line. Going right, ball 6's is the right wall's
    contact, where a wave reflects: measured, and left out of the fit."""
    d = np.array([0.010, 0.012, 0.008, 0.011, 0.009, 0.010])
    gap = np.array([1e-4, 0.0, 2e-4, 5e-5, 0.0])
    right_wall_gap = 3e-4
    surface, place = 0.0, [0.0]             # place[j]: contact j, between balls j, j + 1
    for j in range(6):                      # walk right from ball 1's left surface
        g = gap[j] if j < 5 else right_wall_gap
        place.append(surface + d[j] + g / 2)
        surface += d[j] + g
    place = np.array(place)
    model = {"units": "si", "diameter": d, "gap": gap, "scales": {"force": 1.0},
             "walls": {"right": {"gap": right_wall_gap}}}
    speed, w = 30.0, 1e-5
    t = np.arange(0.0, 3e-3, 1e-7)
    sensors = np.array([2, 3, 5, 6])
    for direction in (1, -1):
        start = 0.0 if direction > 0 else place[-1]
        when = (place - start) / (direction * speed) + 2e-4
        force = np.stack([np.stack([sech2(t, when[b - 1 + side], w) for side in (0, 1)],
                                   axis=-1) for b in sensors], axis=1)
        p = measure_pulses(_run(6, sensors, t, force, model))
        leaving = 1 if direction > 0 else 0
        np.testing.assert_array_equal(p.side, leaving)
        np.testing.assert_allclose(p.peak_time, when[sensors - 1 + leaving], atol=1e-10)
        np.testing.assert_allclose(p.peak_force, 1.0, atol=1e-6)
        np.testing.assert_allclose(p.width, 2 * w * math.acosh(math.sqrt(2)), rtol=1e-3)
        wall = (sensors == 6) & (leaving == 1)
        np.testing.assert_array_equal(p.on_wall, wall)
        assert p.speed_si.value == pytest.approx(direction * speed, rel=1e-6)
        assert p.speed_si.error < 1e-6 * speed and p.speed_si.points == 4 - wall.sum()
        # in balls: the contact of balls b and b + 1 at b + 1/2
        used = sensors[~wall]
        ref = stats.linregress(when[used - 1 + leaving], used - 0.5 + leaving)
        assert p.speed.value == pytest.approx(ref.slope, rel=1e-6)
        # the two contacts' pulses do not overlap: the mean force peaks at half
        np.testing.assert_allclose(p.peak_mean_force, 0.5, rtol=1e-6)


def test_waves_going_both_ways_are_fitted_apart():
    """Balls struck from both ends of a line of 30: the sensors near ball 1 see the
    wave going towards ball N first, those near ball 30 the other; each wave's speed
    comes from its own sensors (one line through all four would be neither's)."""
    t = np.arange(0.0, 40.0, DT)
    c = 1.25                                     # balls per unit time, both waves
    sensors = np.array([5, 10, 20, 25])
    force = np.zeros((t.size, sensors.size, 2))
    for s, ball in enumerate(sensors):
        for side in (0, 1):
            j = ball - 1 + side                  # contact j at j + 1/2 balls
            when = (j + 0.5) / c if ball < 15 else (30.0 - (j + 0.5)) / c
            force[:, s, side] = sech2(t, when + 2.0, 0.3)
    p = measure_pulses(_run(30, sensors, t, force))
    np.testing.assert_array_equal(p.side, [1, 1, 0, 0])
    assert p.speed.value == pytest.approx(c, rel=1e-6) and p.speed.points == 2
    assert p.backward_speed.value == pytest.approx(-c, rel=1e-6)
    assert p.backward_speed.points == 2
    from chainrun.api import pulses

    ds = pulses(_run(30, sensors, t, force))
    assert ds.wave_speed.item() == pytest.approx(c, rel=1e-6)
    assert ds.backward_wave_speed.item() == pytest.approx(-c, rel=1e-6)
    assert "towards ball 1" in ds.backward_wave_speed.attrs["long_name"]


def test_run_sensors_at_the_ends_and_without_sensors():
    """At an end ball the outer side carries nothing: the inner one is measured. A run
    in the paper's units has no speed in m/s; a run without sensors is an error."""
    t = np.arange(0.0, 10.0, DT)
    contact = {1: sech2(t, 3.0, 0.5), 2: sech2(t, 4.0, 0.5), 3: sech2(t, 5.0, 0.5)}
    sensors = [1, 2, 4]
    force = np.zeros((t.size, 3, 2))
    for s, ball in enumerate(sensors):
        for side in (0, 1):
            force[:, s, side] = contact.get(ball - 1 + side, 0.0)
    p = measure_pulses(_run(4, sensors, t, force))
    np.testing.assert_array_equal(p.side, [1, 1, 0])
    np.testing.assert_allclose(p.peak_time, [3.0, 4.0, 5.0], atol=1e-6)
    assert p.speed.value == pytest.approx(1.0, rel=1e-6) and p.speed.error < 1e-6
    assert p.speed_si is None and p.units == "paper"
    mean = optimize.minimize_scalar(lambda s: -0.5 * (sech2(s, 3.0, 0.5) + sech2(s, 4.0, 0.5)),
                                    bounds=(2.5, 3.5), method="bounded", options={"xatol": 1e-10})
    np.testing.assert_allclose(p.peak_mean_force, [0.5, -mean.fun, 0.5], rtol=1e-6)
    with pytest.raises(ChainrunError, match="no force sensors"):
        measure_pulses(_run(3, np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 0, 2))))
    with pytest.raises(ChainrunError, match="arrival"):
        measure_pulses(_run(4, sensors, t, force), arrival=1.5)
