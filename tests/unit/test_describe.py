"""What a figure's title says a line is (``chainrun.plotting.views.describe``), from an
experiment file's runs as they are checked, without running them: the words and units
are the file's values written by hand."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np

from chainrun.config import parse_experiment
from chainrun.plotting.views import describe
from chainrun.store._h5 import to_json

DRIVEN = """name = "driven"
units = "si"
[chain]
n = 30
k = 0
diameter = 0.019
material = {pattern = ["steel", "aluminium"]}
precompression = 10.0
[walls.left]
material = "steel"
motion = {amplitude = 1.0e-8, frequency = 5500.0, ramp = 1.0e-3}
[walls.right]
material = "steel"
[solver]
t_end = 6.0e-3
"""


def runs(text: str) -> list:
    """Each run of the experiment ``text`` as the views see a run file: its line, units,
    resolved config (through JSON, as the file keeps it) and swept keys."""
    specs = parse_experiment(text, "toml", to_run=False).runs(to_run=False)
    return [SimpleNamespace(line=spec.line, units=spec.units,
                            parameters={"config_resolved": json.loads(to_json(spec.config)),
                                        "overrides": dict(spec.overrides)})
            for spec in specs]


def test_a_driven_wall_is_named_with_its_amplitude_frequency_and_ramp():
    (run,) = runs(DRIVEN)
    assert describe(run) == (
        "N = 30 steel and aluminium spheres of 19 mm, Hertz contacts, walls at both "
        "ends, precompressed 10 N, left wall driven 10 nm at 5.5 kHz (1 ms ramp)")
    # wrapped between its parts, the drive whole on one line
    assert describe(run, width=72).splitlines()[-1] == (
        "left wall driven 10 nm at 5.5 kHz (1 ms ramp)")


def test_a_sweeps_title_leaves_out_the_drives_swept_keys():
    text = DRIVEN + '[sweep]\n"walls.left.motion.frequency" = [2000.0, 7600.0]\n'
    first, second = runs(text)
    assert describe(first).endswith("left wall driven 10 nm at 2 kHz (1 ms ramp)")
    assert describe(second).endswith("left wall driven 10 nm at 7.6 kHz (1 ms ramp)")
    assert describe(first, first.parameters["overrides"]).endswith(
        "precompressed 10 N, left wall driven 10 nm (1 ms ramp)")
    text = DRIVEN + '[sweep]\n"walls.left.motion.amplitude" = [1.0e-8, 2.0e-8]\n'
    run = runs(text)[0]
    assert describe(run, ["walls.left.motion.amplitude"]).endswith(
        "left wall driven at 5.5 kHz (1 ms ramp)")


def test_a_driven_ball_is_named_with_its_force():
    text = DRIVEN.replace('precompression = 10.0', 'precompression = 10.0\ndrive = '
                          '[{ball = 3, amplitude = 0.02, frequency = 200.0}, '
                          '{ball = 3, amplitude = 0.005, frequency = 300.0}]')
    text = text.replace('motion = {amplitude = 1.0e-8, frequency = 5500.0, ramp = 1.0e-3}',
                        '')
    (run,) = runs(text)
    assert describe(run).endswith(
        "precompressed 10 N, ball 3 driven by a force of 20 mN at 200 Hz + 5 mN at 300 Hz")


def test_a_drive_in_the_papers_units_names_its_numbers():
    text = """name = "shaken"
[chain]
n = 4
k = 0
alpha = 1.5
precompression = 1.0
[walls.left]
stiffness = 1.0
motion = {amplitude = 0.01, frequency = 0.2, ramp = 50.0}
[walls.right]
stiffness = 1.0
[solver]
t_end = 100.0
"""
    (run,) = runs(text)
    assert describe(run).endswith(
        "left wall driven with amplitude 0.01 at frequency 0.2 (ramp 50)")


MASSES = """name = "masses"
units = "si"
[chain]
n = 24
k = 1
speed = 0.5
alpha = 1.5
mass = {mass}
stiffness = {stiffness}
[solver]
t_end = 1.0e-3
"""


def test_masses_are_given_with_their_unit_and_pattern():
    (run,) = runs(MASSES.format(mass="{pattern = [0.03, 0.01]}", stiffness="5.0e9"))
    assert describe(run) == ("N = 24, masses 30 g / 10 g alternating, 1 striker at "
                             "500 mm/s, Hertz contacts")
    (run,) = runs(MASSES.format(mass="{pattern = [0.01, 0.02, 0.03]}", stiffness="5.0e9"))
    assert describe(run).startswith("N = 24, masses 10 g / 20 g / 30 g repeating,")
    # a taper from its first ball to its last, which says its way
    (run,) = runs(MASSES.format(mass="{taper = 0.9, start = 0.03}", stiffness="5.0e9"))
    low = 0.03 * 0.9 ** 23  # the 24th ball's: 2.657 g
    assert describe(run).startswith(f"N = 24, masses 30 g (ball 1) to {low * 1e3:.4g} g "
                                    f"(ball 24),")


def test_random_stiffnesses_carry_their_unit():
    (run,) = runs(MASSES.format(
        mass="0.01", stiffness="{random = 'uniform', low = 1.0e9, high = 5.0e9, seed = 1}"))
    assert describe(run) == ("N = 24, stiffnesses uniform 1e+09-5e+09 N m-1.5, 1 striker "
                             "at 500 mm/s, Hertz contacts")


def test_strikers_are_counted_in_words_but_on_the_papers_line():
    text = MASSES.format(mass="0.01", stiffness="5.0e9").replace("k = 1", "k = 3")
    (run,) = runs(text)
    assert describe(run) == "N = 24, 3 strikers at 500 mm/s, Hertz contacts"
    # the paper's own line, in its units, keeps the paper's K
    (run,) = runs('name = "paper"\n[chain]\nn = 5\nk = 2\nalpha = 1.5\n')
    assert describe(run) == "N = 5, K = 2, Hertz contacts"
    # a line in the paper's units that is not the paper's
    (run,) = runs('name = "general"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n'
                  'mass = {pattern = [1.0, 0.5]}\n')
    assert describe(run) == "N = 5, masses 1 / 0.5 alternating, 1 striker, Hertz contacts"


def test_the_balls_values_say_which_ball_is_which():
    from chainrun.units import balls_text

    d = np.full(5, 0.0254)
    assert balls_text(d, "diameter", "si") == "25.4 mm"
    d[0] = 0.032002  # a striker of another size
    assert balls_text(d, "diameter", "si", 5) == "25.4 mm, ball 1 of 32.002 mm"
    taper = 0.0254 * 0.9 ** np.arange(5)
    assert balls_text(taper, "diameter", "si") == "25.4 mm (ball 1) to 16.66 mm (ball 5)"
    assert balls_text([0.01, 0.03, 0.02], "mass", "si") == "10 g to 30 g"
