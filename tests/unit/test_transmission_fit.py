"""The transmission's pieces alone: the least-squares fit of a drive's harmonics and its
window of whole periods, against synthetic sums of sines written in the test."""

from __future__ import annotations

import math

import numpy as np
import pytest

from chainrun.analysis.transmission import fit_harmonics, fit_window
from chainrun.errors import ChainrunError


def test_the_fit_recovers_a_sum_of_sines_at_the_harmonics():
    # 3 columns, each a mean plus harmonics 1..3 of f with their own amplitudes and
    # phases, sampled at a step that is not a whole fraction of the period
    f, dt = 0.37, 0.0831
    t = np.arange(0.0, 40.0, dt)
    mean = np.array([5.0, -1.0, 0.0])
    amp = np.array([[1.0, 0.2, 3e-4], [0.03, 0.0, 2.0], [1e-6, 5e-7, 0.0]])
    phase = np.array([[0.3, -2.9, 1.0], [math.pi, 0.0, -0.5], [-1.2, 2.0, 0.0]])
    y = mean + sum(amp[k] * np.sin(2 * math.pi * (k + 1) * f * t[:, None] + phase[k])
                   for k in range(3))
    m, a, p, residual = fit_harmonics(t, y, f, harmonics=3)
    np.testing.assert_allclose(m, mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a, amp, rtol=1e-10, atol=1e-13)
    present = amp > 0
    wrapped = np.angle(np.exp(1j * (p - phase)))   # pi and -pi are one phase
    np.testing.assert_allclose(wrapped[present], 0.0, atol=1e-8)
    assert np.all(residual < 1e-12)


def test_a_frequency_that_is_not_a_harmonic_is_left_in_the_residual():
    # over whole periods of f a sine at 1.5 f is orthogonal to the sines at f, 2f, 3f:
    # the fit's amplitudes stay, and the residual is its rms, a / sqrt(2)
    f = 1.0
    t = np.linspace(0.0, 20.0, 20 * 64, endpoint=False)
    y = 2.0 * np.sin(2 * math.pi * f * t + 0.4) + 0.5 * np.sin(2 * math.pi * 1.5 * f * t)
    _, a, p, residual = fit_harmonics(t, y, f, harmonics=3)
    assert abs(a[0] - 2.0) < 1e-2 and abs(p[0] - 0.4) < 1e-2 and np.all(a[1:] < 1e-2)
    assert residual == pytest.approx(0.5 / math.sqrt(2.0), rel=2e-2)


def test_the_window_is_whole_periods_ending_at_the_last_sample():
    t = np.arange(0.0, 10.0 + 1e-12, 0.01)           # up to 10.0
    begin, end, periods = fit_window(t, 0.3, 4.0)     # 6 / (1/0.3) = 1.8 periods -> 1
    assert (end, periods) == (t[-1], 1) and begin == pytest.approx(t[-1] - 1 / 0.3)
    begin, end, periods = fit_window(t, 2.5, 0.0)      # exactly 25 periods fit
    assert periods == 25 and begin == pytest.approx(0.0, abs=1e-12)
    assert fit_window(t, 2.5, 0.0, periods=4)[2] == 4
    # a start before the record is its first sample: the 25 periods it holds
    assert fit_window(t, 2.5, -1.0) == fit_window(t, 2.5, 0.0)


@pytest.mark.parametrize("start, periods, message", [
    (9.0, None, "not one whole period"),
    (0.0, 40, "40 periods of the drive are longer"),
    (0.0, 0, "periods: must be >= 1"),
])
def test_a_window_without_the_periods_asked_for_is_refused(start, periods, message):
    t = np.arange(0.0, 10.0, 0.01)
    with pytest.raises(ChainrunError, match=message):
        fit_window(t, 0.3, start, periods)
