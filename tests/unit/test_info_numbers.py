"""The numbers ``chainrun info`` prints, from given values: an ensemble's mean and
standard deviation to the deviation's digits, a driven sensor's response to the digits
its fit's residual allows."""

from __future__ import annotations

import math

import numpy as np

from chainrun.cli.info import _response, _statistics


def test_a_mean_is_written_to_its_deviations_digits_in_one_prefix():
    # mean 90, sample standard deviation 10 (the values' own closed form)
    assert _statistics(np.array([80.0, 90.0, 100.0]), "force", "si") == "90 +- 10 N (80 ... 100)"
    assert _statistics(np.array([0.080, 0.090, 0.100]), "force", "si") == (
        "90 +- 10 mN (80 ... 100)")
    # 88.41 +- 11.81 N is 88 +- 12 N: the deviation to two digits, the mean to its place
    x = np.array([88.41 - 11.81, 88.41, 88.41 + 11.81])
    assert _statistics(x, "force", "si") == "88 +- 12 N (77 ... 100)"


def test_counts_keep_their_exact_range():
    # mean 62/3 = 20.67, sd sqrt(19/3) = 2.52
    assert math.isclose(np.std([18, 21, 23], ddof=1), math.sqrt(19 / 3))
    assert _statistics(np.array([18.0, 21.0, 23.0]), None, "si") == "20.7 +- 2.5 (18 ... 23)"


def test_a_large_number_without_a_unit_keeps_one_notation():
    # 55000 +- 2000 balls/s, not 5.5e+04 +- 2000
    assert _statistics(np.array([53000.0, 55000.0, 57000.0]), None, "si") == (
        "55000 +- 2000 (53000 ... 57000)")


def test_a_value_the_same_in_every_run_has_no_deviation():
    assert _statistics(np.full(4, 1.5e-3), "time", "si") == "1.5 ms in every run"
    assert _statistics(np.zeros(4), None, "si") == "0 in every run"


def test_runs_without_a_value_are_left_out_and_counted():
    x = np.array([80.0, math.nan, 100.0, 90.0])
    assert _statistics(x, "force", "si") == "90 +- 10 N (80 ... 100) (in 3 of the 4 runs)"
    assert _statistics(np.full(2, math.nan), "force", "si") == "none in any run"


def test_a_steady_response_keeps_four_digits():
    assert _response(0.2321, -0.0134, 1.1923, 0.01, True, "si") == (
        "amplitude 232.1 mN, phase -0.013 rad, transmission 1.192")


def test_a_response_not_steady_gets_one_digit():
    # what the fit leaves, 53 mN rms, is 23% of the 232.1 mN amplitude
    assert _response(0.2321, -0.0134, 1.1923, 0.053, False, "si") == (
        "amplitude 200 mN, phase 0.0 rad, transmission 1 (not steady: what the fit leaves "
        "is 23% of it)")
    assert _response(125.6e-6, 3.111, 6.453e-4, 0.5 * 125.6e-6, False, "si").startswith(
        "amplitude 100 µN, phase 3.1 rad, transmission 0.0006 (not steady")


def test_a_response_below_what_the_fit_leaves_is_below_the_noise():
    # 26.44 µN under a residual 26.43 times it (699 µN rms): the transmission 1.359e-4
    # is under the residual's 1.359e-4 * 26.43 = 0.0036
    text = _response(26.44e-6, 1.820, 1.359e-4, 26.43 * 26.44e-6, False, "si")
    assert text == ("amplitude and transmission below the noise: what the fit leaves, "
                    "700 µN rms (a transmission of 0.004), is 26 times the amplitude "
                    "(not steady)")
    assert "0.0001359" not in text and "1.820" not in text


def _run(name: str, forward: float, check=None):
    """What a folder's table reads of a run's summary: a driven run stopped at 6 ms."""
    from types import SimpleNamespace

    return SimpleNamespace(path=f"{name}.h5", units="si", n=30, k=0, outcome="stop_time",
                           end_time=6e-3, events={}, forward=(3, forward),
                           energy={"dissipated": 0.0}, check=check, speed=0.0)


def test_a_folders_velocities_take_a_prefix_that_suits_the_column():
    from pathlib import Path

    from chainrun.cli.info import render_folder

    runs = [_run("a", 0.115795e-3), _run("b", 0.267306e-3), _run("c", 1.64444e-3)]
    lines = render_folder(Path("out"), runs).splitlines()
    assert "forward (µm/s)" in lines[1]
    assert [line.split()[-1] for line in lines[2:]] == ["115.795", "267.306", "1644.44"]


def test_a_folders_velocities_keep_six_digits_or_those_the_check_supports():
    from pathlib import Path
    from types import SimpleNamespace

    from chainrun.cli.info import render_folder

    # a check whose spread at ball 3 is 5e-9 m/s (0.005 µm/s): two decimals of µm/s
    check = SimpleNamespace(ok=True, final_velocity_spread=np.full(30, 5e-9),
                            holding=lambda speed: 30)
    runs = [_run("a", 477.95e-6), _run("b", 417.98213e-6, check)]
    lines = render_folder(Path("out"), runs).splitlines()
    assert lines[2].split()[-2] == "477.950"       # six digits, the zero one of them
    assert lines[3].split()[-2] == "417.98"        # the digits the spread leaves
