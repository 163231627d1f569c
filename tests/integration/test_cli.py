"""End-to-end tests of ``chainrun simulate``: the real command in a temporary folder."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import chainrun
import chainrun.runner as runner
from chainrun.runner import executors
from chainrun.cli import main
from chainrun.store import read_index

from helpers import TABLE1

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


@pytest.fixture
def cli(tmp_path, monkeypatch):
    """Invoke ``chainrun ARGS`` in an empty temporary working folder."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv(runner.SCHEDULER_ENV, raising=False)

    def invoke(*args):
        return CliRunner().invoke(main, [str(a) for a in args])
    return invoke


def printed_table(stdout: str) -> dict[str, list[float]]:
    """The 'final velocities' table of the output, by column header."""
    lines = stdout.split("final velocities (paper units)\n", 1)[1].strip().splitlines()
    head = lines[0].split()
    rows = [line.split() for line in lines[1:]]
    return {name: [float(r[c]) for r in rows] for c, name in enumerate(head) if c}


def test_table1_prints_the_papers_numbers(cli, tmp_path):
    result = cli("simulate", CONFIGS / "table1.toml")
    assert result.exit_code == 0, result.output
    table = printed_table(result.stdout)
    for k, column in TABLE1.items():
        for n, printed in enumerate(column):
            decimals = len(printed.split(".")[1])
            # The paper rounds to its printed digits, we to 4 decimals.
            tolerance = 0.5 * 10.0**-decimals + 0.5e-4
            assert table[f"k={k}"][n] == pytest.approx(float(printed), abs=tolerance), (k, n + 1)
    rows = read_index(tmp_path / "results" / "table1" / "index.h5")
    assert [r["run_id"] for r in rows] == ["k=1", "k=2", "k=3", "k=4"]
    assert all(r["outcome"] == "terminal" for r in rows)
    assert "4 computed in this process" in result.stderr


def test_a_bad_config_lists_every_problem_and_writes_nothing(cli, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[chain]\nn = 0\nk = 1\nalpha = "x"\ncolour = 3\n')
    result = cli("simulate", bad)
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 3
    assert all(line.startswith(f"{bad}: chain.") for line in lines)
    assert {line.split(": ")[1] for line in lines} == {"chain.n", "chain.alpha", "chain.colour"}
    assert result.stdout == ""
    assert not (tmp_path / "results").exists()


def test_it_refuses_to_overwrite_files_of_another_config(cli, tmp_path):
    config = tmp_path / "cradle.toml"
    config.write_text('name = "cradle"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n')
    assert cli("simulate", config).exit_code == 0
    run = tmp_path / "results" / "cradle" / "run.h5"
    before = run.read_bytes()

    config.write_text('name = "cradle"\n[chain]\nn = 5\nk = 2\nalpha = 1.5\n')
    result = cli("simulate", config)
    assert result.exit_code == 2
    error = result.stderr.strip().splitlines()[-1]
    assert error.startswith("chainrun: error: ") and "run.h5" in error and "--force" in error
    assert run.read_bytes() == before

    result = cli("simulate", config, "--force")
    assert result.exit_code == 0, result.output
    assert run.read_bytes() != before
    assert read_index(run.parent / "index.h5")[0]["k"] == 2


def test_version(cli):
    result = cli("--version")
    assert result.exit_code == 0
    assert result.output.strip() == f"chainrun, version {chainrun.__version__}"


@pytest.mark.parametrize("args", [["--help"], ["simulate", "--help"]])
def test_help_has_examples(cli, args):
    result = cli(*args)
    assert result.exit_code == 0
    examples = result.output.split("Examples:\n", 1)[1]
    assert re.search(r"^\s+chainrun simulate \S+", examples, re.MULTILINE)


def test_help_explains_resumption_and_clusters(cli):
    text = " ".join(cli("simulate", "--help").output.split())
    for needed in ("--scheduler ADDRESS", "--scheduler-file", "DASK_SCHEDULER_ADDRESS",
                   "--jobs", "skipped", "--force"):
        assert needed in text, needed


def test_an_unreachable_scheduler_is_one_line(cli, tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 1.0)
    config = tmp_path / "cradle.toml"
    config.write_text('name = "cradle"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n')
    result = cli("simulate", config, "--scheduler", "tcp://127.0.0.1:9")
    assert result.exit_code == 2
    error = result.stderr.strip().splitlines()[-1]
    assert error.startswith("chainrun: error: cannot connect to Dask at tcp://127.0.0.1:9")
    assert "Traceback" not in result.output


@pytest.mark.parametrize("statement, absent", [
    # every command starts here: each imports its libraries when it needs them
    ("import chainrun.cli",
     ["matplotlib", "dask", "distributed", "scipy", "numba", "h5py", "pydantic", "yaml"]),
    # reading run and analysis files (analyze, plot) needs no config parser
    ("import chainrun.store", ["chainrun.config", "pydantic", "yaml", "numba", "scipy"]),
    # a TOML experiment file needs no YAML parser
    ("from chainrun.config import parse_experiment; "
     "parse_experiment('name = \"x\"\\n[chain]\\nn = 2\\nk = 1\\nalpha = 1.5\\n', 'toml')",
     ["yaml", "numba", "scipy"]),
    # the solver's kernels carry their tableau as literals (see _codegen)
    ("import chainrun.solver", ["scipy", "matplotlib", "h5py", "pydantic"]),
])
def test_start_up_imports_only_what_is_needed(tmp_path, statement, absent):
    # The whole process's wall time is what a run costs, start-up included.
    code = f"import sys\n{statement}\nprint(' '.join(m for m in {absent!r} if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, check=True)
    assert done.stdout.split() == []


def test_simulate_imports_only_what_a_run_needs(tmp_path):
    # A whole run in a fresh process: numba, h5py and pydantic, nothing of the analysis,
    # the figures or Dask (numba itself brings scipy.linalg). Its solver time is the
    # solve's: the kernels are loaded (or compiled) before its clock starts.
    absent = ["matplotlib", "dask", "distributed", "xarray", "h5netcdf", "pandas",
              "scipy.integrate", "scipy.optimize", "scipy.interpolate", "scipy.special",
              "scipy.sparse", "chainrun.analysis", "chainrun.plotting", "chainrun.artefacts"]
    (tmp_path / "cradle.toml").write_text(
        'name = "cradle"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n'
        "[output]\ntimes = {start = 0, stop = 10, step = 0.5}\n")
    code = ("import sys\nfrom chainrun.cli import main\n"
            "main(['simulate', 'cradle.toml'], standalone_mode=False)\n"
            f"print('imported:', *[m for m in {absent!r} if m in sys.modules])")
    env = {k: v for k, v in os.environ.items() if k != runner.SCHEDULER_ENV}
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, check=True, env=env)
    assert done.stdout.splitlines()[-1] == "imported:"
    assert "final velocities" in done.stdout
    solver_time = re.search(r"\(([0-9.]+) s of solver time\)", done.stderr)
    assert solver_time and float(solver_time.group(1)) < 0.1, done.stderr


def _numpy_blas() -> str:
    import numpy as np
    return str(np.__config__.CONFIG.get("Build Dependencies", {}).get("blas", {}).get("name"))


@pytest.mark.skipif(not Path("/proc/self/task").is_dir() or (os.cpu_count() or 1) < 2
                    or "openblas" not in _numpy_blas(),
                    reason="threads are counted in /proc, on two cores or more, with OpenBLAS")
def test_the_command_starts_no_blas_threads(tmp_path):
    # numpy's and scipy's OpenBLAS start a thread per further core when imported, which
    # spin and take CPU from the runs beside this one; the command keeps them out, and a
    # setting of the user's stands
    code = ("import os\nimport chainrun.cli\nimport numpy, scipy.linalg\n"
            "print(os.environ['OPENBLAS_NUM_THREADS'], len(os.listdir('/proc/self/task')))")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}

    def run(**extra):
        done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                              text=True, check=True, env={**env, **extra})
        setting, threads = done.stdout.split()
        return setting, int(threads)

    assert run() == ("1", 1)
    setting, threads = run(OPENBLAS_NUM_THREADS="2")
    assert setting == "2" and threads > 1


def test_loading_the_kernels_leaves_scipys_blas_alone(tmp_path):
    # numba probes for scipy's BLAS (about 0.1 s of imports) before its first load; the
    # kernels need none, and numba's own linear algebra still finds it afterwards
    code = """
import sys
import numba
import numpy as np
from chainrun.solver import load_kernels
load_kernels()
print("scipy.linalg" in sys.modules)
dot = numba.njit(lambda a, b: np.dot(a, b))
convolve = numba.njit(lambda a, b: np.convolve(a, b))
a = np.array([1.0, 2.0, 3.0])
b = np.array([0.5, -1.0])
print(dot(a, a), convolve(a, b).tolist())
import scipy.linalg
print(scipy.linalg.solve(np.eye(2), np.ones(2)).tolist())
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, check=True)
    assert done.stdout.split("\n")[:3] == [
        "False", "14.0 [0.5, 0.0, -0.5, -3.0]", "[1.0, 1.0]"], done.stdout + done.stderr


def test_a_run_that_fails_says_so_without_warnings(tmp_path):
    # an overlap whose stored energy overflows: a named failure, no numpy warning beside it
    (tmp_path / "overlap.toml").write_text(
        'name = "overlap"\n[chain]\nn = 3\nk = 1\nalpha = 1.5\ngap = -1e130\n')
    env = {k: v for k, v in os.environ.items() if k != runner.SCHEDULER_ENV}
    done = subprocess.run([sys.executable, "-m", "chainrun", "simulate", "overlap.toml"],
                          cwd=tmp_path, capture_output=True, text=True, env=env)
    assert done.returncode == 1
    assert "state became non-finite at t = 0" in done.stderr
    assert "\n1 run: 0 computed" in done.stderr
    assert "Warning" not in done.stderr and "Traceback" not in done.stderr, done.stderr


def test_a_runs_time_leaves_out_loading_the_kernels(tmp_path, monkeypatch):
    # numba loads the kernels on their first call: a run must not pay for it in its time
    import chainrun.solver as solver
    from chainrun.config import parse_experiment

    calls = []
    monkeypatch.setattr(solver, "load_kernels", lambda: calls.append("load_kernels"))
    real = solver.simulate

    def simulate(*args, **kwargs):
        calls.append("simulate")
        return real(*args, **kwargs)

    monkeypatch.setattr(solver, "simulate", simulate)
    (spec,) = parse_experiment('name = "x"\n[chain]\nn = 3\nk = 1\nalpha = 1.5\n',
                               "toml").runs()
    runner.simulate_run(spec, tmp_path)
    assert calls == ["load_kernels", "simulate"]


def test_an_interruption_before_the_runs_begin_is_said_as_one(cli, tmp_path, monkeypatch):
    # SIGINT while the experiment file is read (the command imports the solver and
    # pydantic first, a second or more on a loaded machine): the same one line and exit
    # status as an interruption inside the runs, not click's "Aborted!"
    import chainrun.config

    def interrupted(path):
        raise KeyboardInterrupt

    monkeypatch.setattr(chainrun.config, "load_experiment", interrupted)
    config = tmp_path / "line.toml"
    config.write_text('name = "line"\n[chain]\nn = 3\nk = 1\nalpha = 1.5\n')
    result = cli("simulate", config, "-o", tmp_path / "out")
    assert result.exit_code == 130
    assert "chainrun: error: interrupted" in result.output
    assert "Aborted" not in result.output
    assert not (tmp_path / "out").exists()


def test_the_velocity_table_keeps_three_digits_of_small_velocities():
    """Velocities spanning four decades in one unit: each printed value carries at
    least three significant digits (four decimals where that is more)."""
    from types import SimpleNamespace

    from chainrun.cli.text import velocity_table

    v = np.array([-2.48812, -0.303617, -0.0213312, -0.00973214, -0.000664127, 0.0])
    run = SimpleNamespace(n=v.size, units="si", final_velocity=v, terminal=True,
                          check=None, run_id="speed=3.0")
    lines = velocity_table([run]).splitlines()
    assert lines[0] == "final velocities (m/s)"
    printed = np.array([float(line.split()[1]) for line in lines[2:]])
    np.testing.assert_allclose(printed[:-1], v[:-1], rtol=5e-3)
    assert [line.split()[1] for line in lines[2:]] == [
        "-2.4881", "-0.3036", "-0.0213", "-0.00973", "-0.000664", "0.0000"]


@pytest.mark.parametrize("columns", [200, 79, 40, 24])
def test_the_progress_line_keeps_the_time_that_moves(columns):
    """On any terminal width, the simulated time of the run computing (the one number
    that moves during a long run) is on the line, whole; counts of zero are left out."""
    from chainrun.cli.simulate import _SweepBar
    from chainrun.runner import SweepProgress

    one = _SweepBar.text(SweepProgress(total=1, running=1), "run t = 1.235e+05", 62.0,
                         columns)
    assert one == "1:02 run t = 1.235e+05"[:columns]
    many = _SweepBar.text(SweepProgress(total=40, done=8, running=2, skipped=3),
                          "speed=3.0 (check) t = 0.01234", 62.0, columns)
    assert len(many) <= columns
    if columns >= 79:
        assert many.endswith("11/40 done 8, running 2, skipped 3; 1:02 speed=3.0 (check) "
                             "t = 0.01234") and "failed" not in many
    if columns >= 40:
        assert many.endswith("1:02 speed=3.0 (check) t = 0.01234")


def test_a_checked_runs_progress_says_when_its_check_runs(tmp_path):
    from chainrun.config import load_experiment

    config = tmp_path / "checked.toml"
    config.write_text('name = "checked"\n[chain]\nn = 5\nk = 1\nalpha = 1.5\n'
                      '[output]\ntimes = [0.0, 1.0, 2.0]\n')
    labels = []  # (each snapshot reports progress: the check run's too, with its files)
    runner.simulate_experiment(load_experiment(config), tmp_path / "out",
                               check_outdir=tmp_path / "check",
                               on_progress=lambda label, t: labels.append(label))
    assert labels[0] == "run" and labels[-1] == "run (check)"
    assert set(labels) == {"run", "run (check)"}


def test_counts_of_one_are_singular():
    from chainrun.cli.text import count

    assert [count(n, "events") for n in (0, 1, 2)] == ["0 events", "1 event", "2 events"]
    assert count(1, "unloadings (a damped force at 0)") == "1 unloading (a damped force at 0)"


def test_analyze_points_a_run_of_ones_own_to_info_and_plot(cli, tmp_path):
    run = tmp_path / "mine.h5"
    run.write_bytes(b"")
    result = cli("analyze", run)
    assert result.exit_code == 2 and len(result.stderr.strip().splitlines()) == 1
    assert f"chainrun info {run}" in result.stderr and f"chainrun plot {run}" in result.stderr


def test_an_interrupt_a_callback_swallowed_stops_the_run_at_its_next_snapshot(tmp_path):
    # the handler the command line installs raises KeyboardInterrupt and remembers it;
    # where the raise lands in a callback whose exceptions Python ignores (h5py's weak
    # references, while a snapshot is written), the run's next snapshot raises it again,
    # and its file is discarded
    import signal

    from chainrun import interrupt
    from chainrun.config import parse_experiment

    (spec,) = parse_experiment('name = "x"\n[chain]\nn = 30\nk = 1\nalpha = 1.5\n'
                               "[output]\ntimes = {start = 0, stop = 40, step = 1}\n",
                               "toml").runs()
    previous = signal.signal(signal.SIGINT, interrupt.handler)  # (as the command's)
    try:
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)  # (raised here, and "swallowed" below)
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGINT, previous)
    with pytest.raises(KeyboardInterrupt):
        runner.simulate_run(spec, tmp_path)
    assert not list(tmp_path.glob("*.h5")) and not list(tmp_path.glob(".*partial*"))
    interrupt.check()  # acted on: forgotten
    runner.simulate_run(spec, tmp_path)
    assert (tmp_path / "run.h5").is_file()


def test_a_run_stops_before_its_file_fills_the_disk(tmp_path, monkeypatch):
    from chainrun.config import parse_experiment
    from chainrun.errors import StoreError
    from chainrun.store import run_writer

    (spec,) = parse_experiment('name = "x"\n[chain]\nn = 3000\nk = 1\nalpha = 1.5\n'
                               "[output]\ntimes = {start = 0, stop = 400, step = 1}\n",
                               "toml").runs()
    monkeypatch.setattr(run_writer, "DISK_CHECK_BYTES", 2**20)  # a check every 1 MiB
    monkeypatch.setattr(run_writer, "free_disk", lambda folder: 2**29)  # 512 MiB left
    with pytest.raises(StoreError, match=r"stopped before the disk fills: 536.9 MB left "
                                         r"\(chainrun keeps 1.0 GB free\) after \d+ snapshots"):
        runner.simulate_run(spec, tmp_path)
    assert not list(tmp_path.iterdir())  # the partial file discarded


def _simulated_with_warnings(folder, name: str, text: str):
    """``chainrun simulate`` of the experiment ``text``: its result and stderr's warnings."""
    path = folder / f"{name}.toml"
    path.write_text(text)
    result = CliRunner().invoke(main, ["simulate", str(path), "-o", str(folder / name)])
    assert result.exit_code == 0, result.output
    return path, result, [line for line in result.stderr.splitlines() if "warning" in line]


def test_a_doubtful_input_and_a_far_off_balance_are_warned_of_and_run(tmp_path):
    from chainrun.errors import ChainrunWarning

    # ten 2 cm steel beads whose wall overlaps the last by a metre: a typo, which runs,
    # its balls leaving at hundreds of km/s; its balance holds to the rounding of the
    # gigajoules the overlap put in (|dE|/E relative to them, not to the striker's mJ)
    _, result, warned = _simulated_with_warnings(
        tmp_path, "overlap", 'name = "overlap"\nunits = "si"\n[chain]\nn = 10\nk = 1\n'
        'speed = 0.5\ndiameter = 0.02\nmaterial = "steel"\n[walls.right]\n'
        'material = "steel"\ngap = -1.0\n')
    assert len(warned) == 1
    assert warned[0].startswith("chainrun: warning: walls.right.gap: an overlap of 1 m")
    error = float(re.search(r"\|dE\|/E = ([\d.e+-]+),", result.stdout).group(1))
    assert error < 1e-12
    # eight damped beads against a wall at rtol 1e-5: a balance off by several 1e-6 of
    # the impact energy (the steps' error: its digits vary with them), far above its
    # rounding, is warned of, from the command and the API
    path, _, warned = _simulated_with_warnings(
        tmp_path, "loose", 'name = "loose"\nunits = "si"\n[chain]\nn = 8\nk = 1\n'
        'speed = 0.5\ndiameter = 0.0254\nmaterial = "steel"\nrestitution = 0.95\n'
        'damping_law = "tsuji"\n[walls.right]\nmaterial = "steel"\n[solver]\nrtol = 1e-5\n')
    assert len(warned) == 1
    assert warned[0].startswith("chainrun: warning: run: its energy balance is off by ")
    off = float(re.search(r"off by ([\d.e+-]+) of its energy", warned[0]).group(1))
    assert 1e-6 < off < 1e-4
    with pytest.warns(ChainrunWarning) as caught:
        chainrun.simulate(path)
    assert [str(w.message)[:34] for w in caught] == ["run: its energy balance is off by "]
