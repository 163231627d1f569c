"""Units and their prefixes (chainrun.units): what a person reads on an axis or a line."""

from __future__ import annotations

import math

import pytest

from chainrun.units import (
    PAPER,
    axis_label,
    end_phrase,
    format_digits,
    format_measured,
    format_value,
    format_with_error,
    scale_for,
    scale_for_column,
)


@pytest.mark.parametrize("quantity, values, factor, unit", [
    ("time", [0.0, 2.2e-4], 1e6, "µs"),
    ("time", [5.0], 1.0, "s"),
    ("position", [3e-9], 1e9, "nm"),
    ("velocity", [0.005], 1e3, "mm/s"),
    ("velocity", [0.0005], 1e6, "µm/s"),
    ("force", [1000.0], 1e-3, "kN"),
    ("force", [999.0], 1.0, "N"),
    ("energy", [-6.05e-5], 1e6, "µJ"),
    ("mass", [0.002145], 1e3, "g"),   # a mass takes its prefix on the gram
    ("mass", [3.2], 1.0, "kg"),
    ("momentum", [1e-4], 1e6, "µN s"),
    ("time", [0.0, math.nan], 1.0, "s"),  # nothing finite to scale by
])
def test_an_si_prefix_puts_the_largest_value_in_1_to_1000(quantity, values, factor, unit):
    scaled = scale_for(quantity, "si", values)
    assert scaled.unit == unit
    assert scaled.factor == pytest.approx(factor, rel=1e-15)


def test_paper_units_are_named_and_not_scaled():
    assert scale_for("time", "paper", [1e-5]).factor == 1.0
    assert axis_label("time", "time", "paper", [3.0])[0] == f"time ({PAPER})"
    assert axis_label("time", "time", "si", [3e-3])[0] == "time (ms)"
    assert scale_for("stiffness", "si", [6e9]).unit == "N m-alpha"


def test_a_value_for_a_person():
    assert format_value(2.23585e-4, "time", "si") == "223.6 µs"
    assert format_value(0.5, "velocity", "si") == "500 mm/s"
    assert format_value(6.17702, "time", "paper") == "6.177"
    assert format_value(math.inf, "time", "si") == "inf"


def test_a_value_is_shown_to_its_errors_second_digit():
    assert format_with_error(602.706, 0.23) == ("602.71", "0.23")
    assert format_with_error(1234.5, 56.0) == ("1234", "56")
    assert format_with_error(589.809, float("nan")) == ("589.809", "")
    # the value and its error in one notation, the error's two digits after rounding
    assert format_with_error(0.84050884, 3.7e-9) == ("0.8405088400", "0.0000000037")
    assert format_with_error(55562.5, 1673.0) == ("55600", "1700")
    # a range's ends to the deviation's place, or to their own second digit where finer
    assert format_with_error(55562.5, 1673.0, 53210.0, 58001.0) == ("55600", "1700",
                                                                 "53200", "58000")
    assert format_with_error(2.0e5, 5.9e5, 1421.0, 1.9e6, 0.0) == (
        "200000", "590000", "1400", "1900000", "0")
    assert format_with_error(0.3, 0.0996) == ("0.30", "0.10")
    assert format_with_error(-0.004, 0.23) == ("0.00", "0.23")  # no "-0.00"


def test_a_range_is_shown_to_the_place_of_its_mean():
    assert format_with_error(88.41, 11.81, 75.13, 109.6) == ("88", "12", "75", "110")
    assert format_with_error(150.5, 2.851, 144.52, 153.8) == (
        "150.5", "2.9", "144.5", "153.8")


def test_velocities_where_runs_stopped_say_when():
    assert end_phrase([True, True], [3.0, 7.0], "paper") == ""   # final: terminal
    assert end_phrase([False, False], [1.5e-3, 1.5e-3], "si") == "at t = 1.5 ms"
    assert end_phrase([True, False], [1e-3, 1.5e-3], "si") == "where each run stopped"


def test_a_measured_value_keeps_the_digits_its_error_supports():
    assert format_measured(26.0007e-6, 3.8e-9, "time", "si") == "26.00 µs"
    assert format_measured(25.99752e-6, 3.6e-11, "time", "si") == "25.998 µs"  # five at most
    assert format_measured(26.0e-6, 1e-12, "time", "si") == "26.000 µs"         # zeros kept
    assert format_measured(150.3968e-6, 5.4e-9, "time", "si") == "150.40 µs"
    assert format_measured(263e-6, 30e-6, "time", "si") == "300 µs"
    assert format_measured(60.802e-6, math.nan, "time", "si") == "60.802 µs"
    # to one digit in plain notation, within its prefix
    assert format_measured(699e-6, math.nan, "force", "si", 1) == "700 µN"
    assert format_measured(3.59e-3, math.nan, None, "si", 1) == "0.004"


def test_a_columns_prefix_suits_its_typical_value():
    assert scale_for_column("velocity", "si", [0.116e-3, 0.267e-3, 1.64e-3]).unit == "µm/s"
    assert scale_for_column("velocity", "si", [0.0, 0.4, 0.5]).unit == "mm/s"
    assert scale_for_column("velocity", "si", [0.0, 0.0]).unit == "m/s"
    assert format_digits(477.95, math.nan, 6) == "477.950"
    assert format_digits(417.98213, 0.005, 6) == "417.98"
    assert format_digits(417.98213, 0.02, 6) == "418.0"
    assert format_digits(26.0007, 0.004) == "26.00"
