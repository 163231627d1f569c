"""The same config gives the same results: bitwise on reruns and any ``--jobs``; to
rounding on another CPU.

Compared are the arrays (final state, separation, events, snapshots) and every dataset
and attribute of the run and index files, except what records when and how long:
the root ``created`` attribute, ``diagnostics@wall_time`` and the index's
``wall_time`` column. File bytes are not compared: they hold those timestamps.

Across CPUs: the kernels compiled for a generic x86-64 CPU (``NUMBA_CPU_NAME=generic``,
no FMA, no AVX; in a process of its own with its own cache folder) against the
kernels compiled for this machine, on the regression lines and general ones
(``_cpu_lines``), to ``CPU_TOL``. (The kernels take no fastmath flags, so the two
builds agree bit for bit; the tolerance leaves room for a libm that rounds otherwise
on another CPU, which this machine cannot show.)
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from chainrun.cli import main
from chainrun.solver import Line, Wall, simulate

#: Attributes and datasets that record the time of writing or the cost of a run.
VARYING = {"/@created", "/diagnostics@wall_time", "/table/wall_time"}

SWEEP = """\
name = "same"
[chain]
n = 12
k = 1
alpha = 1.5
[output]
times = {start = 0, stop = 8, step = 0.5}
[sweep]
"chain.k" = [1, 2, 3]
"chain.alpha" = [1.0, 1.5, 2.5]
"""


def same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind == "O" or b.dtype.kind == "O":  # variable-length strings
        return a.shape == b.shape and a.tolist() == b.tolist()
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("n, k, alpha", [(20, 2, 1.5), (10, 1, 1.0), (8, 3, 2.5)])
def test_simulate_twice_is_bitwise_identical(n, k, alpha):
    times = np.linspace(0, 15, 31)
    a = simulate(Line.paper(n, k, alpha), times)
    b = simulate(Line.paper(n, k, alpha), times)
    assert a.outcome == b.outcome and a.end_time == b.end_time and a.message == b.message
    assert len(a.event_time) > 0
    for name in ("final_position", "final_velocity", "separation_time", "separation_velocity",
                 "event_time", "event_contact", "event_kind", "positions", "velocities"):
        assert same_bits(getattr(a, name), getattr(b, name)), name
    da, db = a.diagnostics, b.diagnostics
    assert (da.steps, da.rejected_steps, da.events, da.momentum_error, da.energy_error,
            da.max_window) == (db.steps, db.rejected_steps, db.events, db.momentum_error,
                               db.energy_error, db.max_window)


def contents(path: Path) -> dict[str, object]:
    """Every dataset and attribute of an HDF5 file (links not followed), by path."""
    found: dict[str, object] = {}
    with h5py.File(path, "r") as h5:
        for key, value in h5.attrs.items():
            found[f"/@{key}"] = value

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                found[f"/{name}"] = obj[()]
            for key, value in obj.attrs.items():
                if key not in ("DIMENSION_LIST", "REFERENCE_LIST"):  # object references
                    found[f"/{name}@{key}"] = value

        h5.visititems(visit)
        if "runs" in h5:  # index files: the link targets, not the linked files
            for run_id in h5["runs"]:
                link = h5["runs"].get(run_id, getlink=True)
                found[f"/runs/{run_id}->"] = (link.filename, link.path)
    return found


def assert_same_results(out_a: Path, out_b: Path) -> None:
    names_a = sorted(p.name for p in out_a.iterdir())
    assert names_a == sorted(p.name for p in out_b.iterdir())
    assert "index.h5" in names_a and len(names_a) > 1
    for name in names_a:
        a, b = contents(out_a / name), contents(out_b / name)
        assert sorted(a) == sorted(b), name
        different = [key for key in a if key not in VARYING and not same_bits(a[key], b[key])]
        assert not different, f"{name}: {different}"


def run_cli(config: Path, outdir: Path, *args: str) -> None:
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(outdir), *args])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    assert result.exit_code == 0, result.output


def test_the_command_twice_gives_the_same_files(tmp_path):
    config = tmp_path / "same.toml"
    config.write_text(SWEEP)
    run_cli(config, tmp_path / "a")
    run_cli(config, tmp_path / "b")
    assert_same_results(tmp_path / "a", tmp_path / "b")


def test_any_number_of_jobs_gives_the_same_files(tmp_path):
    config = tmp_path / "same.toml"
    config.write_text(SWEEP.replace('"chain.alpha" = [1.0, 1.5, 2.5]\n', ""))
    run_cli(config, tmp_path / "one", "--jobs", "1")
    run_cli(config, tmp_path / "two", "--jobs", "2")
    assert_same_results(tmp_path / "one", tmp_path / "two")


# --- another CPU ---------------------------------------------------------------------------
#: Results across CPUs agree to this, relative to the line's velocity scale (positions:
#: to the length it travels, see ``_cpu_results``).
CPU_TOL = 1e-13


def _cpu_lines() -> dict[str, tuple[Line, dict]]:
    """The lines compared across CPUs, by name: (line, keyword arguments of the run)."""
    rng = np.random.default_rng(35)
    n = 12
    snap = {"times": np.linspace(0.0, 20.0, 21)}
    lines = {f"table1-k{k}": (Line.paper(5, k, 1.5), {}) for k in (1, 2, 3, 4)}
    lines.update({
        "paper-n20-k2": (Line.paper(20, 2, 1.5), snap),
        "paper-n60-k1-hertz": (Line.paper(60, 1, 1.5), {}),
        "paper-n30-k1-linear": (Line.paper(30, 1, 1.0), snap),
        "paper-n8-k3-alpha2.5": (Line.paper(8, 3, 2.5), {}),
        "masses-gaps": (Line.make(n, mass=10 ** rng.uniform(-0.5, 0.5, n),
                                  stiffness=10 ** rng.uniform(-0.5, 0.5, n - 1),
                                  alpha=rng.choice([1.0, 1.5, 2.0], n - 1),
                                  gap=rng.uniform(-0.01, 0.2, n - 1), k=2), snap),
        "head-on-damped-walls": (Line.make(n, velocity=np.r_[1.0, np.zeros(n - 2), -0.7],
                                           alpha=1.5, damping=0.3, damping_exponent=0.25,
                                           left=Wall(2.0, 1.5, 0.1, damping=0.5),
                                           right=Wall(0.5, 1.0, 0.0)),
                                 {**snap, "t_end": 40.0}),
        "gravity-on-a-wall": (Line.make(6, mass=np.linspace(1.0, 2.0, 6), alpha=1.5,
                                        gap=0.05, force=0.3, velocity=np.zeros(6),
                                        right=Wall(1.0, 1.5, 0.0)), {"t_end": 30.0}),
        "steel-si": (Line.make(10, mass=0.0673549, stiffness=1.20843851e10, alpha=1.5,
                               speed=0.5), {}),
    })
    return lines


def _cpu_results() -> dict[str, np.ndarray]:
    """Final and snapshot velocities and positions of ``_cpu_lines``, flat by name, in
    units of the line's velocity scale V and of the length L (1 + t/T) it travels by
    their time t (L, T its length and time scales)."""
    out = {}
    for name, (line, kw) in _cpu_lines().items():
        sol = simulate(line, **kw)
        assert sol.outcome.ok, f"{name}: {sol.message}"
        sc = line.scales()
        t = np.concatenate([[sol.end_time], sol.times])[:, None] / sc.time
        v = np.concatenate([sol.final_velocity[None], sol.velocities])
        x = np.concatenate([sol.final_position[None], sol.positions])
        out[f"{name}/v"] = (v / sc.velocity).reshape(-1)
        out[f"{name}/x"] = (x / (sc.length * (1.0 + t))).reshape(-1)
        out[f"{name}/events"] = np.array([sol.event_time.size])
    return out


def _dump(path: str) -> None:
    """Write ``_cpu_results`` to ``path`` (the other CPU's process calls this)."""
    np.savez(path, **_cpu_results())


@pytest.mark.slow
def test_a_generic_cpu_gives_the_same_answers(tmp_path):
    """The kernels compiled for a generic x86-64 CPU give this machine's answers to
    CPU_TOL. They are cached in a folder of their own (``generic-cpu`` beside this
    machine's kernels, keyed by the solver's sources as they are), so this machine's
    cache is untouched, and only the first run after a change of the solver compiles
    them (100 s or more)."""
    from chainrun.solver._jit import cache_root

    path = tmp_path / "generic.npz"
    env = dict(os.environ, NUMBA_CPU_NAME="generic",
               NUMBA_CACHE_DIR=str(cache_root() / "generic-cpu"))
    code = f"import sys; sys.path[:0] = {[str(Path(__file__).parent)]!r}; " \
           f"import test_determinism as t; t._dump({str(path)!r})"
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=1800)
    other = dict(np.load(path))
    here = _cpu_results()
    assert sorted(other) == sorted(here)
    worst = {}
    for key, a in here.items():
        b = other[key]
        assert a.shape == b.shape, key
        if key.endswith("/events"):
            assert a[0] == b[0], f"{key}: {a[0]} events here, {b[0]} there"
            continue
        worst[key] = float(np.max(np.abs(a - b)))
    print("largest differences across CPUs:",
          ", ".join(f"{k} {v:.1e}" for k, v in sorted(worst.items()) if v) or "none")
    assert max(worst.values()) <= CPU_TOL, {k: v for k, v in worst.items() if v > CPU_TOL}
