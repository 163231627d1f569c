"""The numbers ``chainrun info`` prints for a folder of runs, from given values: an
ensemble's mean and standard deviation to the deviation's digits."""

from __future__ import annotations

import math

import numpy as np

from chainrun.cli.info import _statistics


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
