"""Interrupting chainrun at random moments never leaves a file that lies.

``chainrun simulate`` runs in a real subprocess and is sent SIGINT, SIGTERM or SIGKILL
at a random moment of a long run or of a sweep; every file then found under a final
name must be a complete run or index file, and a signal the process can handle leaves
no partial file behind. Then the same command, run again,
finishes the experiment (a sweep resumes).
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from chainrun.store import read_index, read_run

#: three runs of a few seconds each, so that signals land in start-up, inside a
#: run and while files are written
CONFIG = """\
name = "interrupted"
[chain]
n = 60000
k = 1
alpha = 1.5
[output]
times = {start = 0, stop = 70000, step = 5000}
[sweep]
"chain.alpha" = [1.5, 1.45, 1.55]
"""


def _interruptible() -> None:
    """In the child before it runs: Ctrl-C as a terminal gives it. A test worker
    (pytest-xdist's) ignores SIGINT, a child inherits that, and Python then installs no
    KeyboardInterrupt for it: the signal would be ignored, and the test would not test."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(config: Path, outdir: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "chainrun", "simulate", str(config), "-o", str(outdir),
         "--jobs", "1"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"}, preexec_fn=_interruptible,
    )


def _check_final_files(outdir: Path) -> int:
    """Every file under a final name reads back whole; return how many there are."""
    found = 0
    for path in sorted(outdir.glob("*.h5")):
        found += 1
        if path.name == "index.h5":
            assert read_index(path), path
        else:
            run = read_run(path)
            assert run.final_velocity.shape == (run.n,)
            assert run.positions.shape[0] == len(run.times)
    return found


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL],
                         ids=["SIGINT", "SIGTERM", "SIGKILL"])
def test_random_interruptions_leave_only_whole_files(tmp_path, sig):
    rng = random.Random(20261121 + int(sig))
    config = tmp_path / "interrupted.toml"
    config.write_text(CONFIG)
    outdir = tmp_path / "out"
    for attempt in range(4):
        proc = _start(config, outdir)
        time.sleep(rng.uniform(0.5, 6.0))
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=120)
        if proc.returncode == 0:
            break  # finished before the signal: still checked below
        assert proc.returncode != 0
        if sig != signal.SIGKILL:
            # an interruption it can see: said in one line, its partial files removed
            assert "Traceback" not in err, err
            assert "interrupted" in err or "chainrun: error" in err, err
            assert not list(outdir.glob(".*.partial-*"))
        _check_final_files(outdir)
    # the same command completes the experiment, reusing what was finished
    proc = _start(config, outdir)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err
    assert _check_final_files(outdir) == 4  # three runs and the index
    assert not list(outdir.glob(".*.partial-*"))


def test_an_interrupted_single_run_says_what_is_left(tmp_path):
    """Ctrl-C on a run of no sweep: exit status 130, and no sweep to resume is promised."""
    config = tmp_path / "one.toml"
    # the bench's random line of 1000 balls: some 20 s of collisions to its terminal state
    config.write_text('name = "one"\n[chain]\nn = 1000\nk = 1\nalpha = 1.5\n'
                      'mass = {random = "uniform", low = 1.0, high = 10.0, seed = 1}\n'
                      'stiffness = {random = "uniform", low = 1.0, high = 10.0, seed = 2}\n')
    proc = _start(config, tmp_path / "out")
    banner = proc.stderr.readline()  # (said once the experiment is read: the run starts)
    assert banner.startswith("one: 1 run"), banner
    time.sleep(2.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted; no run file was written: the same command runs it again" in err
    assert "sweep" not in err.splitlines()[-1]
