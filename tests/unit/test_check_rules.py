"""The conditioning check's rules (``chainrun.check``), its key in experiment files, and
how a number is shown with only the digits its spread supports."""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np
import pytest

from chainrun.check import HOLD, Check, check_rtol, spread
from chainrun.config import parse_experiment
from chainrun.errors import ConfigError
from chainrun.units import format_supported, supported_format

LINE = 'name = "x"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n'


def test_the_check_runs_at_a_tenth_of_the_tolerance_or_ten_times_below_the_floor():
    assert check_rtol(1e-12) == pytest.approx(1e-13, rel=1e-15)
    assert check_rtol(1e-3) == pytest.approx(1e-4, rel=1e-15)
    assert check_rtol(1e-14) == 1e-15          # 1e-14 / 10 rounds just below 1e-15
    # below 1e-15 the solver cannot go; a clamp would compare a run with itself
    assert check_rtol(5e-15) == pytest.approx(5e-14, rel=1e-15)
    assert check_rtol(1e-15) == pytest.approx(1e-14, rel=1e-15)


def test_a_spread_is_the_difference_and_a_never_separated_ball_has_none():
    a = np.array([1.0, -0.5, np.nan, np.nan, 0.25])
    b = np.array([1.0 + 3e-9, -0.5, np.nan, 0.1, 0.25 - 1e-3])
    out = spread(a, b)
    assert out[0] == abs(a[0] - b[0]) and out[1] == 0.0 and out[4] == abs(a[4] - b[4])
    assert out[2] == 0.0                        # NaN in both runs: they agree
    assert out[3] == np.inf                     # NaN in one: they disagree on the ball


def _check(final, separation):
    return Check(rtol=1e-13, outcome="terminal", message="", wall_time=0.0,
                 final_velocity_spread=np.asarray(final, float),
                 separation_velocity_spread=np.asarray(separation, float))


def test_a_ball_holds_when_both_spreads_are_within_a_billionth_of_the_impact_speed():
    c = _check([1e-12, 5e-9, 1e-10, 0.0], [1e-12, 1e-12, 3e-9, np.inf])
    assert c.holding(1.0) == 1                  # ball 1 only
    assert c.holding(10.0) == 3                 # 1e-9 of 10: balls 1 to 3
    assert c.largest() == (4, np.inf)
    assert HOLD == 1e-9
    assert "1 of 4 balls hold to 1e-9" in c.line(1.0)
    failed = Check(rtol=1e-13, outcome="event_limit", message="too many", wall_time=0.0,
                   final_velocity_spread=np.full(4, np.nan),
                   separation_velocity_spread=np.full(4, np.nan))
    assert failed.holding(1.0) == 0 and "failed (event_limit)" in failed.line(1.0)


def test_solver_check_is_a_boolean_key_left_out_of_the_config_and_its_hash():
    plain = parse_experiment(LINE, "toml").runs()[0]
    checked = parse_experiment(LINE + "[solver]\ncheck = true\n", "toml").runs()[0]
    unchecked = parse_experiment(LINE + "[solver]\ncheck = false\n", "toml").runs()[0]
    assert (plain.check, checked.check, unchecked.check) == (False, True, False)
    assert plain.config == checked.config == unchecked.config
    assert "check" not in plain.config["solver"]
    # the hash of a file without the key is the sha256 of its canonical JSON, as before
    canonical = json.dumps(plain.config, sort_keys=True, separators=(",", ":"))
    assert plain.config_hash == hashlib.sha256(canonical.encode()).hexdigest()
    assert checked.config_hash == plain.config_hash == unchecked.config_hash
    with pytest.raises(ConfigError) as err:
        parse_experiment(LINE + "[solver]\ncheck = 1\n", "toml")
    assert err.value.problems == ["solver.check: expected true or false, got 1"]


def test_the_check_runs_spec_is_the_file_written_at_the_check_tolerance():
    spec = parse_experiment(LINE + "[solver]\ncheck = true\n", "toml").runs()[0]
    other = parse_experiment(LINE + "[solver]\nrtol = 1e-13\n", "toml").runs()[0]
    checked = spec.for_check()
    assert checked.rtol == other.rtol and not checked.check
    assert checked.config == other.config and checked.config_hash == other.config_hash


@pytest.mark.parametrize("value, spread_, text", [
    (0.148611, 0.0, "0.148611"),          # no spread: .6g, as before
    (0.148611, math.nan, "0.148611"),     # not measured
    (0.148611, 1e-13, "0.148611"),        # a spread below the sixth digit cuts nothing
    (0.148611, 3e-5, "0.1486"),           # the last digit's unit (1e-4) is >= 3e-5
    (0.148611, 1e-5, "0.14861"),
    (0.148611, 0.002, "0.15"),
    (0.5004, 0.001, "0.500"),             # zeros kept: they are digits
    (45.7321, 0.05, "45.7"),
    (7.6e8, 1e6, "7.60e+08"),
    (7.6e8, 7e8, "~8e+08"),               # not even the leading digit holds
    (0.3, math.inf, "—"),
])
def test_a_number_shows_no_digit_beyond_its_spread(value, spread_, text):
    assert format_supported(value, spread_) == text
    if math.isfinite(spread_) and spread_ > 0:
        # every digit shown is within one unit of the value, and the next one is not shown
        shown = float(text.lstrip("~"))
        decimals = len(text.split(".")[1].split("e")[0]) if "." in text else 0
        if "e" not in text:
            assert 10.0 ** -decimals >= spread_ * (1 - 1e-12)
            assert abs(shown - value) <= 0.5 * 10.0 ** -decimals + 1e-15


@pytest.mark.parametrize("fmt, value, spread_, text", [
    (".4f", 0.148611, 3e-4, "0.149"),
    (".4f", 0.148611, 1e-13, "0.1486"),
    (".1%", 0.0391, 0.002, "4%"),         # a share's spread counts in percent points
    ("+.4f", 0.021, 1e-3, "+0.021"),
    (".0e", 3e-5, 1e-9, "3e-05"),
    (".3f", 0.52, math.nan, "0.520"),
])
def test_a_quoted_value_is_cut_to_its_spread(fmt, value, spread_, text):
    assert supported_format(fmt, value, spread_) == text


def test_spreads_are_measured_against_the_impact_or_else_the_drive_speed():
    # a struck line: its largest initial speed; a line at rest shaken by a wall of
    # amplitude A at f: 2 pi f A (the wall's largest speed); a line at rest and not
    # driven: the unit
    from chainrun.check import reference_speed
    from chainrun.solver import Drive, Line, Wall

    assert reference_speed(Line.make(5, alpha=1.5, velocity=[0.3, -0.7, 0, 0, 0])) \
        == (0.7, "the impact speed")
    shaken = Line.make(4, alpha=1.5, velocity=np.zeros(4), right=Wall(1.0),
                       left=Wall(1.0, motion=Drive.sine(2e-8, 3000.0, 1e-3)))
    speed, name = reference_speed(shaken)
    assert speed == pytest.approx(2 * math.pi * 3000.0 * 2e-8, rel=1e-15)
    assert name == "the drive's speed"
    assert reference_speed(Line.make(4, alpha=1.5, velocity=np.zeros(4))) \
        == (1.0, "the unit of velocity")
