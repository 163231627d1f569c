"""Experiment files with dissipation: the damping keys of the chain and of the walls, a
restitution turned into a damping per contact, their checks, generators and sweeps.

Reference values come from the explicit solution of the damped linear oscillator (its
force's zero found here by a root finder) and from dimensional analysis, not from
``chainrun.solver.restitution``'s inverse.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from click.testing import CliRunner

from chainrun.cli import main
from chainrun.config import SWEEPABLE_KEYS, parse_experiment
from chainrun.errors import ConfigError
from closed_forms import oscillator

HEAD = 'name = "x"\n'
CHAIN = "[chain]\nn = 3\nk = 1\n"


def runs(text: str):
    return parse_experiment(HEAD + text, "toml").runs()


def line_of(text: str):
    (spec,) = runs(text)
    return spec.line


def problems(text: str) -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_experiment(HEAD + text, "toml")
    return info.value.problems


def test_linear_dashpot_restitution_per_contact():
    # each contact's eta gives its e with its own stiffness and reduced mass, at any speed
    line = line_of("[chain]\nn = 3\nk = 1\nalpha = 1.0\nmass = [1.0, 3.0, 2.0]\n"
                   "stiffness = [2.0, 5.0]\nrestitution = [0.8, 0.25]\n"
                   'damping_law = "dashpot"\n')
    np.testing.assert_array_equal(line.damping_exponent, [0.0, 0.0])
    for j, (k, e) in enumerate(((2.0, 0.8), (5.0, 0.25))):
        mu = line.mass[j] * line.mass[j + 1] / (line.mass[j] + line.mass[j + 1])
        for v in (0.01, 1.0, 100.0):
            assert oscillator(line.damping[j], k, mu, v)[0] == pytest.approx(e, abs=1e-12)


def test_tsuji_damping_scales_as_sqrt_of_mass_times_stiffness():
    # beta = (alpha - 1)/2 makes G = eta / sqrt(mu kappa): one e, one G, for every contact
    line = line_of("[chain]\nn = 3\nk = 1\nalpha = 1.5\nmass = [1.0, 1.0, 4.0]\n"
                   'stiffness = [1.0, 9.0]\nrestitution = 0.9\ndamping_law = "tsuji"\n')
    np.testing.assert_array_equal(line.damping_exponent, [0.25, 0.25])
    mu = np.array([0.5, 0.8])
    g = line.damping / np.sqrt(mu * np.array([1.0, 9.0]))
    assert g[1] == pytest.approx(g[0], rel=1e-14)
    assert line.is_damped


def test_kuwabara_kono_needs_and_uses_its_speed():
    text = "[chain]\nn = 2\nk = 1\nalpha = 1.5\nrestitution = 0.7\n" \
           'damping_law = "kuwabara-kono"\n'
    assert problems(text) == [
        "chain.restitution_speed: required: the restitution of the kuwabara-kono law "
        "depends on the impact speed (contact 1, balls 1-2, alpha = 1.5); give the speed "
        "it holds at"]
    # the first contact whose restitution depends on the speed, numbered as the run
    # file numbers contacts (for Kuwabara-Kono, alpha = 2 holds e at every speed)
    mixed = "[chain]\nn = 3\nk = 1\nalpha = [2.0, 1.5]\nrestitution = 0.7\n" \
            'damping_law = "kuwabara-kono"\n'
    assert problems(mixed) == [
        "chain.restitution_speed: required: the restitution of the kuwabara-kono law "
        "depends on the impact speed (contact 2, balls 2-3, alpha = 1.5); give the speed "
        "it holds at"]
    slow = line_of(text + "restitution_speed = 0.1\n").damping[0]
    fast = line_of(text + "restitution_speed = 10.0\n").damping[0]
    # G = eta D^(3/2) / (mu v) fixed, D = (mu v^2 / kappa)^(2/5): eta ~ v^(-1/5)
    assert fast / slow == pytest.approx(100.0 ** -0.2, rel=1e-12)
    # at alpha = 2 its e does not depend on the speed: no speed needed
    assert line_of(text.replace("1.5", "2.0")).damping_exponent[0] == 0.5


def test_damping_given_directly():
    line = line_of(CHAIN + "alpha = 1.5\ndamping = [0.1, 0.2]\n")
    np.testing.assert_array_equal(line.damping, [0.1, 0.2])
    np.testing.assert_array_equal(line.damping_exponent, [0.0, 0.0])
    line = line_of(CHAIN + "alpha = 1.5\ndamping = 0.1\ndamping_exponent = [0.5, 0.25]\n")
    np.testing.assert_array_equal(line.damping_exponent, [0.5, 0.25])
    line = line_of(CHAIN + 'alpha = [1.0, 2.0]\ndamping = 0.1\ndamping_law = "tsuji"\n')
    np.testing.assert_array_equal(line.damping_exponent, [0.0, 0.5])
    # an elastic line stays the paper's
    (spec,) = runs(CHAIN + "alpha = 1.5\n")
    assert spec.is_paper and not spec.line.is_damped


def test_generators_and_elastic_contacts():
    line = line_of("[chain]\nn = 5\nk = 1\nalpha = 1.0\nrestitution = {pattern = [1.0, 0.5]}\n"
                   'damping_law = "dashpot"\n')
    assert line.damping[0] == line.damping[2] == 0.0
    assert line.damping[1] == line.damping[3] > 0.0
    assert oscillator(line.damping[1], 1.0, 0.5, 1.0)[0] == pytest.approx(0.5, abs=1e-12)
    line = line_of("[chain]\nn = 4\nk = 1\nalpha = 1.5\n"
                   "damping = {value = 0.0, impurity = {at = 2, value = 0.3}}\n")
    np.testing.assert_array_equal(line.damping, [0.0, 0.3, 0.0])


def test_walls_take_the_same_keys():
    line = line_of("[chain]\nn = 2\nk = 1\nalpha = 1.0\nmass = [1.0, 3.0]\n"
                   "[walls.right]\nstiffness = 4.0\nrestitution = 0.6\n"
                   'damping_law = "dashpot"\n'
                   "[walls.left]\nstiffness = 2.0\ndamping = 0.2\ndamping_exponent = 0.5\n"
                   "[solver]\nt_end = 10.0\n")
    # the right wall meets ball 2 (mass 3): its reduced mass is the ball's
    assert oscillator(line.right.damping, 4.0, 3.0, 1.0)[0] == pytest.approx(0.6, abs=1e-12)
    assert line.right.damping_exponent == 0.0
    assert (line.left.damping, line.left.damping_exponent) == (0.2, 0.5)
    assert not np.any(line.damping)         # the chain's own contacts stay elastic


def test_si_beads_with_restitution():
    line = line_of('units = "si"\n[chain]\nn = 3\nk = 1\nspeed = 0.5\ndiameter = 0.0254\n'
                   'material = "steel"\nrestitution = 0.9\ndamping_law = "tsuji"\n'
                   '[walls.right]\nmaterial = "steel"\nrestitution = 0.8\n'
                   'damping_law = "tsuji"\n')
    mu, kappa = line.mass[0] / 2.0, line.stiffness[0]
    # G = eta / sqrt(mu kappa) is a number of order 1 whatever the units
    assert 0.01 < line.damping[0] / math.sqrt(mu * kappa) < 1.0
    assert line.right.damping > 0.0 and line.right.damping_exponent == 0.25


@pytest.mark.parametrize("text, expected", [
    (CHAIN + "alpha = 1.5\ndamping = -1.0\n", ["chain.damping: must be >= 0, got -1.0"]),
    (CHAIN + "alpha = 1.5\ndamping = [0.1, -1.0]\n",
     ["chain.damping[1]: must be >= 0, got -1.0"]),
    ("[chain]\nn = 5\nk = 1\nalpha = 1.5\ndamping = {pattern = [0.1, -2.0]}\n",
     ["chain.damping[1]: must be >= 0, got -2.0"]),
    (CHAIN + "alpha = 1.5\ndamping = 0.1\ndamping_exponent = -0.5\n",
     ["chain.damping_exponent: must be >= 0, got -0.5"]),
    (CHAIN + 'alpha = 1.5\nrestitution = 0.0\ndamping_law = "tsuji"\n',
     ["chain.restitution: must be > 0, got 0.0"]),
    (CHAIN + 'alpha = 1.5\nrestitution = [0.9, 1.5]\ndamping_law = "tsuji"\n',
     ["chain.restitution[1]: must be <= 1, got 1.5"]),
    (CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping_law = "hertz"\n',
     ["chain.damping_law: unknown damping law 'hertz' (known: dashpot, kuwabara-kono, tsuji)"]),
    (CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping_law = "tsuij"\n',
     ["chain.damping_law: unknown damping law 'tsuij' (did you mean 'tsuji'?) "
      "(known: dashpot, kuwabara-kono, tsuji)"]),
    (CHAIN + "alpha = 1.5\nrestitution = 0.9\n",
     ["chain.damping_law: required with restitution (one of dashpot, kuwabara-kono, tsuji)"]),
    (CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping = 0.1\ndamping_law = "tsuji"\n',
     ["chain.damping: give restitution or damping, not both"]),
    (CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping_exponent = 0.1\ndamping_law = "tsuji"\n',
     ["chain.damping_exponent: give restitution or damping, not both"]),
    (CHAIN + 'alpha = 1.5\ndamping = 0.1\ndamping_exponent = 0.1\ndamping_law = "tsuji"\n',
     ["chain.damping_exponent: set by damping_law; give one or the other"]),
    (CHAIN + 'alpha = 1.5\ndamping_law = "tsuji"\n',
     ["chain.damping_law: needs damping or restitution"]),
    (CHAIN + "alpha = 1.5\ndamping_exponent = 0.5\n",
     ["chain.damping_exponent: given without damping"]),
    (CHAIN + "alpha = 1.5\ndamping = 0.1\nrestitution_speed = 1.0\n",
     ["chain.restitution_speed: given without restitution"]),
    (CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping_law = "dashpot"\nrestitution_speed = 0.0\n',
     ["chain.restitution_speed: must be > 0, got 0.0"]),
    (CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping_law = "dashpot"\n',
     ["chain.restitution_speed: required: the restitution of the dashpot law depends on "
      "the impact speed (contact 1, balls 1-2, alpha = 1.5); give the speed it holds at"]),
    (CHAIN + "alpha = 1.5\n[walls.right]\nrestitution = 1.5\n",
     ["walls.right.restitution: must be <= 1, got 1.5"]),
    (CHAIN + "alpha = 1.5\n[walls.right]\ndamping = -0.1\n",
     ["walls.right.damping: must be >= 0, got -0.1"]),
    (CHAIN + "alpha = 1.5\n[walls.left]\nrestitution = 0.5\n",
     ["walls.left.damping_law: required with restitution (one of dashpot, kuwabara-kono, tsuji)"]),
    (CHAIN + 'alpha = 1.5\n[walls.left]\nrestitution = 0.5\ndamping_law = "kuwabara-kono"\n',
     ["walls.left.restitution_speed: required: the restitution of the kuwabara-kono law "
      "depends on the impact speed (alpha = 1.5); give the speed it holds at"]),
    (CHAIN + "alpha = 1.5\n[walls.left]\ndamping = 0.1\nrestitution = 0.5\n"
     'damping_law = "tsuji"\n',
     ["walls.left.damping: give restitution or damping, not both"]),
])
def test_each_wrong_dissipation_is_one_line(text, expected):
    assert problems(text) == expected


def test_a_wrong_restitution_exits_2_without_traceback(tmp_path):
    config = tmp_path / "bad.toml"
    config.write_text(HEAD + CHAIN + 'alpha = 1.5\nrestitution = [0.5, 2.0]\n'
                      'damping_law = "tsuji"\n')
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert result.stderr.strip() == f"{config}: chain.restitution[1]: must be <= 1, got 2.0"
    assert "Traceback" not in result.output


def test_dissipation_keys_are_sweepable():
    for key in ("damping", "damping_exponent", "restitution", "restitution_speed"):
        assert SWEEPABLE_KEYS[f"chain.{key}"] is float
        for side in ("left", "right"):
            assert SWEEPABLE_KEYS[f"walls.{side}.{key}"] is float
    specs = runs(CHAIN + 'alpha = 1.0\ndamping_law = "dashpot"\n[sweep]\n'
                 '"chain.restitution" = [0.5, 0.9]\n"walls.right.restitution" = [1.0, 0.8]\n'
                 '[walls.right]\ndamping_law = "dashpot"\n[solver]\nt_end = 1.0\n')
    assert [s.run_id for s in specs] == [
        "restitution=0.5_right_restitution=1.0", "restitution=0.5_right_restitution=0.8",
        "restitution=0.9_right_restitution=1.0", "restitution=0.9_right_restitution=0.8"]
    for spec in specs:
        e = spec.overrides["chain.restitution"]
        assert oscillator(spec.line.damping[0], 1.0, 0.5, 1.0)[0] == pytest.approx(e, abs=1e-12)
        assert (spec.line.right.damping == 0.0) == (spec.overrides["walls.right.restitution"] == 1.0)
    assert len({s.config_hash for s in specs}) == 4
    specs = runs(CHAIN + "alpha = 1.5\n[sweep]\n\"chain.damping\" = [0.0, 0.5]\n")
    assert [s.run_id for s in specs] == ["damping=0.0", "damping=0.5"]
    assert [s.line.is_damped for s in specs] == [False, True]


def test_a_sweep_that_conflicts_names_its_combination():
    assert problems(CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping_law = "tsuji"\n'
                    '[sweep]\n"chain.damping" = [0.1]\n') == [
        "sweep (damping=0.1): chain.damping: give restitution or damping, not both"]
    assert problems(CHAIN + 'alpha = 1.5\nrestitution = 0.9\ndamping_law = "tsuji"\n'
                    '[sweep]\n"chain.restitution" = [0.5, 1.5]\n') == [
        "sweep (restitution=1.5): chain.restitution: must be <= 1, got 1.5"]
