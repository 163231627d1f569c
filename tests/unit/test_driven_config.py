"""Driven chains in experiment files: walls.<side>.motion and chain.drive, their checks
(one line naming the key, and the index in a list), the line they build, and what a
driven run file keeps."""

from __future__ import annotations

import numpy as np
import pytest

from chainrun.config import parse_experiment
from chainrun.errors import ConfigError

LINE = '''name = "driven"
[chain]
n = 3
k = 0
alpha = 1.5
{chain}
[walls.left]
stiffness = 1.0
{left}
[walls.right]
stiffness = 1.0
[solver]
{solver}
'''


def experiment(tmp_path, chain="", left="", solver="t_end = 5.0"):
    path = tmp_path / "driven.toml"
    text = LINE.format(chain=chain, left=left, solver=solver)
    path.write_text(text)
    return parse_experiment(text, "toml", str(path))


def problems(tmp_path, **keys) -> list[str]:
    with pytest.raises(ConfigError) as info:
        experiment(tmp_path, **keys).runs()
    return info.value.problems


def test_a_wall_motion_builds_a_moving_wall(tmp_path):
    (spec,) = experiment(tmp_path, left="motion = {amplitude = 0.01, frequency = 2.0, "
                                        "ramp = 0.5}").runs()
    motion = spec.line.left.motion
    assert [(s.amplitude, s.frequency, s.ramp) for s in motion.sines] == [(0.01, 2.0, 0.5)]
    assert spec.line.right.motion is None and not spec.line.has_terminal_state
    assert spec.config["walls"]["left"]["motion"] == {"amplitude": 0.01, "frequency": 2.0,
                                                      "ramp": 0.5}


def test_a_list_of_sines_is_their_sum(tmp_path):
    (spec,) = experiment(tmp_path, left="motion = [{amplitude = 0.01, frequency = 2.0}, "
                                        "{amplitude = -0.02, frequency = 0.5, ramp = 1.0}]"
                         ).runs()
    motion = spec.line.left.motion
    t = np.linspace(1.5, 3.0, 7)  # past the ramp
    np.testing.assert_allclose(motion(t), 0.01 * np.sin(4 * np.pi * t)
                               - 0.02 * np.sin(np.pi * t), rtol=0, atol=1e-15)


def test_a_motion_from_a_file(tmp_path):
    (tmp_path / "drive.csv").write_text("time, displacement\n0, 0\n0.5, 1e-3\n1.0, 0  # end\n")
    (spec,) = experiment(tmp_path, left='motion = {file = "drive.csv"}').runs()
    motion = spec.line.left.motion
    np.testing.assert_array_equal(motion.times, [0.0, 0.5, 1.0])
    assert float(motion(3.0)) == 0.0 and float(motion(0.5)) == 1e-3  # held after the end
    assert len(spec.config["walls"]["left"]["motion"]["sha256"]) == 64


def test_forces_in_time_on_balls(tmp_path):
    (tmp_path / "push.txt").write_text("0 0.5\n1 1.0\n2 0.0\n")
    (spec,) = experiment(tmp_path, chain='drive = [{ball = 2, amplitude = 0.3, frequency = '
                                         '1.0}, {ball = 2, file = "push.txt"}]').runs()
    (b1, d1), (b2, d2) = spec.line.drives
    assert (b1, b2) == (1, 1) and d1.sines[0].amplitude == 0.3 and d2.values[0] == 0.5


def test_a_frequency_sweep(tmp_path):
    text = LINE.format(chain="", left="motion = {amplitude = 0.01, frequency = 2.0}",
                       solver="t_end = 5.0") + '[sweep]\n"walls.left.motion.frequency" = [1.0, 3.0]\n'
    specs = parse_experiment(text, "toml").runs()
    assert [s.run_id for s in specs] == ["left_motion_frequency=1.0",
                                         "left_motion_frequency=3.0"]
    assert [s.line.left.motion.sines[0].frequency for s in specs] == [1.0, 3.0]


def test_a_problem_every_run_of_a_sweep_has_is_reported_once():
    """A driven line between walls without t_end, its drive's frequency swept: no run
    has a terminal state, which is said once for the three."""
    text = LINE.format(chain="", left="motion = {amplitude = 0.01, frequency = 2.0}",
                       solver="") + '[sweep]\n"walls.left.motion.frequency" = [1.0, 2.0, 3.0]\n'
    with pytest.raises(ConfigError) as exc:
        parse_experiment(text, "toml")
    assert exc.value.problems == [
        "sweep (all 3 runs): solver.t_end: required: the line is held between two walls "
        "and walls.left.motion drives it, so the run has no terminal state"]


def test_a_problem_of_some_runs_of_a_sweep_names_each():
    text = LINE.format(chain="", left="motion = {amplitude = 0.01, frequency = 2.0}",
                       solver="t_end = 5.0")
    text += '[sweep]\n"walls.left.motion.frequency" = [1.0, -2.0, -3.0]\n'
    with pytest.raises(ConfigError) as exc:
        parse_experiment(text, "toml")
    assert exc.value.problems == [
        "sweep (left_motion_frequency=-2.0): walls.left.motion.frequency: must be > 0, got -2.0",
        "sweep (left_motion_frequency=-3.0): walls.left.motion.frequency: must be > 0, got -3.0"]


@pytest.mark.parametrize("keys, expected", [
    (dict(left="motion = {amplitude = 0.01, frequency = 2.0}", solver=""),
     "solver.t_end: required: the line is held between two walls and walls.left.motion "
     "drives it, so the run has no terminal state"),
    (dict(chain="drive = {ball = 1, amplitude = 0.1, frequency = 1.0}", solver=""),
     "solver.t_end: required: the line is held between two walls and chain.drive drives "
     "it, so the run has no terminal state"),
    (dict(left="motion = {amplitude = 0.01, frequency = -2.0}"),
     "walls.left.motion.frequency: must be > 0, got -2.0"),
    (dict(left="motion = {amplitude = 0.01, frequency = 0}"),
     "walls.left.motion.frequency: must be > 0, got 0"),
    (dict(left="motion = [{amplitude = 0.01, frequency = 2.0}, {amplitude = 0.01, "
               "frequncy = 2.0}]"),
     "walls.left.motion[1].frequncy: unknown key (did you mean 'frequency'?)"),
    (dict(left="motion = [{amplitude = 0.01, frequency = 2.0, ramp = -1}]"),
     "walls.left.motion[0].ramp: must be >= 0, got -1"),
    (dict(left="motion = {frequency = 2.0}"),
     "walls.left.motion.amplitude: required (the sine's amplitude A, the wall's largest "
     "displacement from its place; m in SI)"),
    (dict(chain="drive = [{ball = 1, amplitude = 0.1}]"),
     "chain.drive[0].frequency: required (the sine's frequency f, in cycles per unit of "
     "time; Hz in SI)"),
    (dict(left="motion = 3"),
     "walls.left.motion: expected a table {amplitude, frequency, ramp} or {file}, got 3"),
    (dict(left='motion = {file = "drive.csv", amplitude = 1.0}'),
     "walls.left.motion.amplitude: unknown key (a drive from a file takes no other key)"),
    (dict(chain="drive = [{ball = 4, amplitude = 0.1, frequency = 1.0}]"),
     "chain.drive[0].ball: ball 4 is beyond chain.n (3)"),
    (dict(chain="drive = [{ball = 1, amplitude = 0.1, frequency = 1.0}, "
                "{amplitude = 0.1, frequency = 1.0}]"),
     "chain.drive[1].ball: required (the driven ball, from 1)"),
])
def test_bad_drives_are_named_by_their_key(tmp_path, keys, expected):
    (tmp_path / "drive.csv").write_text("0 0\n1 1e-3\n")
    assert any(p.endswith(expected) for p in problems(tmp_path, **keys)), \
        problems(tmp_path, **keys)


@pytest.mark.parametrize("rows, expected", [
    (None, "walls.left.motion.file: no such file"),
    ("0 0\n0.5 1e-3\n0.4 0\n", "times must increase, got 0.4 after 0.5 (row 3)"),
    ("0 0\n0.5 1e-3\n0.5 0\n", "times must increase, got 0.5 after 0.5 (row 3)"),
    ("0.1 0\n0.5 1e-3\n", "the first time must be 0, got 0.1"),
    ("0 1e-3\n0.5 0\n", "its displacement at t = 0 must be 0, got 0.001"),
    ("0 0\n", "holds 1 rows: a drive needs at least two (time, displacement)"),
    ("0 0 1\n", "line 1: 3 numbers, expected 2"),
])
def test_bad_drive_files(tmp_path, rows, expected):
    if rows is not None:
        (tmp_path / "drive.csv").write_text(rows)
    (problem,) = problems(tmp_path, left='motion = {file = "drive.csv"}')
    assert problem.startswith("walls.left.motion.file: ") and expected in problem, problem


def test_a_driven_run_file_keeps_its_drives_and_their_work(tmp_path):
    import chainrun
    from helpers import simulate_text

    out = simulate_text(tmp_path, LINE.format(
        chain="precompression = 0.1\ndrive = {ball = 2, amplitude = 0.001, frequency = 0.3}",
        left="motion = {amplitude = 0.001, frequency = 0.2, ramp = 2.0}",
        solver="t_end = 10.0\n[output]\ntimes = {start = 0, stop = 10, step = 0.5}"))
    from chainrun.store import read_run

    run = read_run(out / "run.h5")
    assert run.line.left.motion.sines[0].ramp == 2.0
    (ball, drive), = run.line.drives
    assert ball == 1 and drive.sines[0].amplitude == 0.001
    o = run.observables
    energy = o["kinetic_energy"] + o["potential_energy"] + o["dissipated_energy"]
    assert np.any(o["drive_work"]) and run.drive_energy == pytest.approx(o["drive_work"][-1])
    scale = np.abs(o["drive_work"]).max()
    assert np.abs(energy - energy[0] - o["drive_work"]).max() < 1e-10 * scale
    ds = chainrun.open_run(out / "run.h5")
    assert ds.drive_work.attrs["units"] and ds.attrs["final_drive_work"] == run.drive_energy


def test_a_lone_driven_ball_without_walls_is_refused():
    text = ('name = "lone"\n[chain]\nn = 1\nk = 0\nalpha = 1.5\n'
            'drive = {ball = 1, amplitude = 0.1, frequency = 1.0}\n[solver]\nt_end = 5.0\n')
    with pytest.raises(ConfigError) as info:
        parse_experiment(text, "toml").runs()
    assert any(p.startswith("chain.drive: a lone ball without walls touches nothing")
               for p in info.value.problems), info.value.problems
