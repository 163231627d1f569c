"""Runs too large for the machine: memory refused up front, disk space reported."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from chainrun import limits
from chainrun.config import parse_experiment
from chainrun.errors import ChainrunError

GB = 10**9


def state_bytes(n: int) -> int:
    """Bytes of the arrays the solver allocates for N balls, counted on the real state."""
    from chainrun.solver import _setup

    state = _setup._new_state(n, 1, 1.5, 1e-12, None, None)
    return sum(a.nbytes for a in state if isinstance(a, np.ndarray))


@pytest.mark.parametrize("n", [10, 1000, 100_000])
def test_the_estimate_covers_the_solver_state(n):
    """The estimate counts at least what ``_setup._new_state`` allocates, and not far more.

    If this fails after a change of the solver's state, update the constants of
    ``chainrun.limits`` (bytes per ball, window) to match.
    """
    actual = state_bytes(n)
    estimate = limits.estimate_run_memory(n, 0)
    assert estimate >= actual
    assert estimate - limits.FIXED_BYTES <= 4 * max(actual - 2 * (1 << 16) * 17, 1) + 10**6


def test_the_bytes_per_ball_are_the_solvers_own():
    """The per-ball constants are those of the arrays ``_setup`` allocates: what grows
    with N in the state, and with the capacity in the window of integrated balls."""
    from chainrun.solver import _setup

    small, large = 10_000, 20_000
    per_ball = (state_bytes(large) - state_bytes(small)) / (large - small)
    window = (sum(a.nbytes for a in _setup._alloc_window(2048).values())
              - sum(a.nbytes for a in _setup._alloc_window(1024).values())) / 1024
    assert per_ball == limits.STATE_BYTES_PER_BALL
    assert window == limits.WINDOW_BYTES_PER_BALL


def test_a_damped_lines_bytes_per_ball_are_the_solvers_own():
    """A damped line's state holds more per ball (the damping's rows of the contacts'
    parameters and of the sealed collisions' closed forms): what the estimate adds."""
    from chainrun.solver import Line, _setup

    def damped_bytes(n):
        line = Line.make(n, k=1, alpha=1.5, damping=0.1, damping_exponent=0.5)
        state = _setup._line_state(_setup._Prepared(line), 1e-12, None, None)
        return sum(a.nbytes for a in state if isinstance(a, np.ndarray))

    small, large = 10_000, 20_000
    more = ((damped_bytes(large) - damped_bytes(small))
            - (state_bytes(large) - state_bytes(small))) / (large - small)
    assert more == limits.DAMPED_BYTES_PER_BALL
    n = 10**6
    assert (limits.estimate_run_memory(n, 10, damped=True)
            - limits.estimate_run_memory(n, 10)) == n * limits.DAMPED_BYTES_PER_BALL


@pytest.mark.parametrize(("keys", "damped"), [
    ("", False),
    ("damping = 0.0\n", False),
    ("damping = 0.1\ndamping_exponent = 0.5\n", True),
    ('restitution = 0.9\ndamping_law = "tsuji"\n', True),
    ('restitution = 1.0\ndamping_law = "tsuji"\n', False),
    ('damping = {random = "uniform", low = 0.0, high = 0.1, seed = 1}\n', True),
    ('[walls.right]\nstiffness = 1.0\nrestitution = 0.8\ndamping_law = "tsuji"\n', True),
    ("[walls.left]\nstiffness = 1.0\n", False),
])
def test_a_run_says_whether_its_line_may_dissipate(keys, damped):
    """Read from the settings before the line is built, for the memory estimate; a
    value that may dissipate counts, as a generated one does."""
    text = 'name = "x"\n[chain]\nn = 10\nk = 1\nalpha = 1.5\n' + keys
    if "[walls" in keys:
        text += "[solver]\nt_end = 10.0\n"
    (spec,) = parse_experiment(text, "toml").runs()
    assert spec.damped is damped
    assert spec.line.is_damped is damped


def test_the_estimate_grows_with_n_and_not_with_snapshots_times_n():
    small = limits.estimate_run_memory(10**6, 10)
    assert limits.estimate_run_memory(10**7, 10) > 9 * (small - limits.FIXED_BYTES)
    # snapshots are streamed: a thousand more cost about a thousand times, not N each
    more = limits.estimate_run_memory(10**6, 1010) - small
    assert 0 < more < 1000 * 1000
    kept = limits.estimate_run_memory(10**6, 1010, keep_snapshots=True) - small
    assert kept > 1000 * 2 * 8 * 10**6


def test_check_memory_refuses_with_the_numbers():
    need = limits.estimate_run_memory(10**9, 61)
    with pytest.raises(ChainrunError) as info:
        limits.check_memory(10**9, 61, available=8 * GB)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("a run of N = 1000000000 balls with 61 snapshots needs about ")
    assert f"{need / GB:.1f} GB of memory" in message
    assert message.endswith("but 8.0 GB is available")
    assert limits.check_memory(1000, 61, available=8 * GB) == limits.estimate_run_memory(1000, 61)


def test_check_memory_counts_runs_at_once():
    need = limits.estimate_run_memory(10**7, 10)
    assert limits.check_memory(10**7, 10, available=2 * need) == need
    with pytest.raises(ChainrunError, match=r"\(4 at once: "):
        limits.check_memory(10**7, 10, available=2 * need, runs_at_once=4)


def test_force_samples_are_counted_at_the_solvers_own_bytes():
    """A sensor's samples cost what the solver's buffers hold for them (its ball and
    two neighbours, positions and velocities, in buffers that double) and what is
    written (two forces and their mean): the estimate counts each, and a run with too
    many says which keys to change."""
    from chainrun.solver import Line, _driver, _setup

    P = _setup._Prepared(Line.make(20, k=1, alpha=1.5))
    sensors = _driver._Sensors(np.array([5, 12]), 0.1, None, 1.0, P)
    taken = 3000
    for i in range(taken):
        sensors.take(np.zeros(sensors.probe.size), np.zeros(sensors.probe.size))
    held = sensors.rows.nbytes + sensors.vrows.nbytes
    written = sensors.forces()[1].nbytes * 3 // 2  # forces, and their mean
    assert (held + written) / (taken * 2) <= limits.BYTES_PER_SAMPLE
    assert (limits.estimate_run_memory(100, 10, samples=10**6)
            - limits.estimate_run_memory(100, 10)) == 10**6 * limits.BYTES_PER_SAMPLE
    with pytest.raises(ChainrunError, match="force samples .output.sensor_dt, "
                                            "output.sensor_end. needs about"):
        limits.check_memory(100, 10, available=GB, samples=10**8)


def test_absurd_n_is_refused_on_this_machine():
    with pytest.raises(ChainrunError, match="memory"):
        limits.check_memory(2**62, 2)


def test_memory_available_reads_meminfo_and_falls_back(tmp_path, monkeypatch):
    meminfo = tmp_path / "meminfo"
    meminfo.write_text("MemTotal:       16000000 kB\nMemFree:  100 kB\n"
                       "MemAvailable:    8000000 kB\n")
    monkeypatch.setattr(limits, "_MEMINFO", str(meminfo))
    assert limits.memory_available() == 8000000 * 1024

    # an old kernel without MemAvailable, or no /proc: free pages from sysconf
    meminfo.write_text("MemTotal: 16000000 kB\n")
    monkeypatch.setattr(limits.os, "sysconf",
                        lambda name: {"SC_AVPHYS_PAGES": 1000, "SC_PAGE_SIZE": 4096}[name])
    assert limits.memory_available() == 4096 * 1000
    monkeypatch.setattr(limits, "_MEMINFO", str(tmp_path / "absent"))
    assert limits.memory_available() == 4096 * 1000

    def no_sysconf(name):
        raise ValueError(name)

    monkeypatch.setattr(limits.os, "sysconf", no_sysconf)
    assert limits.memory_available() is None
    # unknown: nothing is refused
    assert limits.check_memory(2**40, 10) == limits.estimate_run_memory(2**40, 10)


def test_disk_space_is_reported(tmp_path):
    size = limits.estimate_file_size(10**6, 1000)
    assert size >= 1000 * 10**6 * 2 * 8
    small = limits.estimate_file_size(10**4, 1000)
    assert small < limits.LARGE_OUTPUT
    assert limits.check_disk(10**4, 1000, tmp_path, free=small + 1) is None
    # output that fits, but is large: said, with what keeps it small
    assert limits.check_disk(10**6, 1000, tmp_path, free=size + 1) == (
        f"the run file may take up to {size / GB:.1f} GB before compression (mostly "
        "snapshots: fewer output.times keep it small)")
    warning = limits.check_disk(10**6, 1000, tmp_path, free=10 * GB)
    assert warning == (f"the run file may take up to {size / GB:.1f} GB before compression, "
                       f"and 10.0 GB is free in {tmp_path}")
    warning = limits.check_disk(10**6, 1000, tmp_path, free=10 * GB, runs=3)
    assert warning.startswith("the 3 run files may take up to ")


def test_free_disk_of_a_folder_not_made_yet(tmp_path):
    free = limits.free_disk(tmp_path / "not" / "yet")
    assert free is not None and free > 0
    assert limits.check_disk(5, 10, tmp_path / "not" / "yet") is None
    assert "free in" in limits.check_disk(10**9, 10**6, tmp_path / "not" / "yet")


def test_check_runs_of_a_sweep(tmp_path):
    exp = parse_experiment(
        'name = "x"\n[chain]\nn = 10\nk = 1\nalpha = 1.5\n[output]\n'
        'times = {start = 0, stop = 99, step = 1}\n[sweep]\n"chain.n" = [10, 1000000, 100]\n',
        "toml")
    specs = exp.runs()
    (warning,) = limits.check_runs(specs, tmp_path, available=8 * GB, free=100 * GB)
    assert warning.endswith("(mostly snapshots: fewer output.times keep them small)")
    assert limits.check_runs(specs[:1], tmp_path, available=8 * GB, free=100 * GB) == []
    big = limits.estimate_run_memory(10**6, 100)
    with pytest.raises(ChainrunError, match="N = 1000000 balls with 100 snapshots"):
        limits.check_runs(specs, tmp_path, available=big - 1, free=100 * GB)
    with pytest.raises(ChainrunError, match="3 at once"):
        limits.check_runs(specs, tmp_path, runs_at_once=8, available=2 * big, free=100 * GB)
    (warning,) = limits.check_runs(specs, tmp_path, available=8 * GB, free=10**6)
    assert warning.startswith("the 3 run files may take up to 1.6 GB before compression")
    assert limits.check_runs([], tmp_path) == []


def test_module_imports_neither_the_solver_nor_h5py():
    tree = ast.parse(Path(limits.__file__).read_text())
    names = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import)
             for alias in node.names}
    names |= {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert not {name for name in names if name.startswith(("h5py", "chainrun.solver", "numba"))}
